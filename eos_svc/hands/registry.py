"""The hands eos_svc knows by name: the descriptions shipped with the package
(``eos_svc/hands/data/*.toml``), and more added by file (``eos serve --hand FILE``).

Nothing is kept between calls: a :class:`HandRegistry` is an ordinary object its owner keeps
(the service keeps one; a command line builds one per run).
"""

from __future__ import annotations

import importlib.resources
from collections.abc import Iterable
from pathlib import Path

from eos_svc.kinematics.errors import HandDescriptionError, UnknownNameError

from .builder import build_hand
from .model import DescribedHand
from .spec import HandSpec, read_hand_file

__all__ = ["DEFAULT_HAND", "HandRegistry", "load_hand_named", "shipped_hand_files"]

#: the hand a plan uses when none is named
DEFAULT_HAND = "hand3x3"
#: the package directory that holds the shipped descriptions
_DATA = "eos_svc.hands.data"


def shipped_hand_files() -> dict[str, Path]:
    """The shipped descriptions, by file stem (= the hand's name), sorted."""
    root = importlib.resources.files(_DATA)
    files = sorted((Path(str(p)) for p in root.iterdir() if p.name.endswith(".toml")), key=lambda p: p.stem)
    return {p.stem: p for p in files}


class HandRegistry:
    """Hand descriptions by name: the shipped ones plus any added from files."""

    def __init__(self, extra_files: Iterable[str | Path] = ()) -> None:
        self._specs: dict[str, HandSpec] = {}
        for name, path in shipped_hand_files().items():
            spec = read_hand_file(path)
            if spec.name != name:
                raise HandDescriptionError(
                    "name", f"{path}: name {spec.name!r} is not the file's stem {name!r}"
                )
            self._specs[name] = spec
        for extra in extra_files:
            self.add_file(extra)

    def add_file(self, path: str | Path) -> HandSpec:
        """Read and register a description file (its ``name`` replaces a shipped one of that name).

        Raises:
            HandDescriptionError: naming the bad key.
        """
        spec = read_hand_file(path)
        self._specs[spec.name] = spec
        return spec

    @property
    def names(self) -> tuple[str, ...]:
        """The registered hands' names, sorted."""
        return tuple(sorted(self._specs))

    def spec(self, name: str) -> HandSpec:
        """The description of hand ``name``.

        Raises:
            UnknownNameError: no hand of that name.
        """
        spec = self._specs.get(name)
        if spec is None:
            raise UnknownNameError("hand", f"unknown hand {name!r}; known: {', '.join(self.names)}")
        return spec

    def resolve(self, name_or_file: str | Path) -> HandSpec:
        """A registered name, or else a description file's path."""
        text = str(name_or_file)
        if text in self._specs:
            return self._specs[text]
        if text.endswith(".toml") or Path(text).is_file():
            return read_hand_file(text)
        raise UnknownNameError(
            "hand", f"{text!r} is neither a registered hand ({', '.join(self.names)}) nor a description file"
        )

    def build(self, name_or_file: str | Path) -> DescribedHand:
        """The hand a name or a description file gives (loaded now)."""
        return build_hand(self.resolve(name_or_file))


def load_hand_named(name_or_file: str | Path = DEFAULT_HAND) -> DescribedHand:
    """The hand of a shipped name or a description file (``"trifinger"``, ``"my_hand.toml"``)."""
    return HandRegistry().build(name_or_file)
