"""Finding a description's URDF: a file shipped with eos_svc, a file of the installed
example-robot-data (located through its distribution's file list, never copied), or a path."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

from eos_svc.kinematics.assets import data_file
from eos_svc.kinematics.errors import HandDescriptionError, UrdfLoadError

from .spec import UrdfSource

__all__ = ["example_robot_data_share", "resolve_urdf"]

#: a file every example-robot-data distribution ships, to find its share directory by
_ERD_MARKER = "example-robot-data/robots/allegro_hand_description/urdf/allegro_right_hand.urdf"


def example_robot_data_share() -> Path:
    """``.../share`` of the installed example-robot-data (``package://example-robot-data/...``
    URIs resolve against it).

    Raises:
        UrdfLoadError: example-robot-data is not installed.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise UrdfLoadError("example-robot-data", "the distribution is not installed") from exc
    for f in dist.files or []:
        if str(f).replace("\\", "/").endswith(_ERD_MARKER):
            urdf = Path(str(dist.locate_file(f))).resolve()
            return urdf.parents[len(Path(_ERD_MARKER).parts) - 1]
    raise UrdfLoadError("example-robot-data", f"no {_ERD_MARKER} in the distribution")


def resolve_urdf(source: UrdfSource, where: str = "urdf") -> tuple[Path, list[Path]]:
    """The URDF file of ``source`` and the package directories its ``package://`` URIs need.

    Raises:
        HandDescriptionError: ``where`` names the key; the file does not exist.
    """
    dirs: list[Path] = []
    if source.kind == "data":
        path = data_file(source.name)
    elif source.kind == "example_robot_data":
        share = example_robot_data_share()
        path = share / "example-robot-data" / source.name
        dirs.append(share)
    else:
        path = Path(source.name)
        if not path.is_absolute() and source.base_dir is not None:
            path = source.base_dir / path
    if not path.is_file():
        raise HandDescriptionError(f"{where}.{source.kind}", f"no such file: {path}")
    return path, dirs
