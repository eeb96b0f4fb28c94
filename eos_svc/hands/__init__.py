"""Hands from a description: a TOML file names the URDF, the fingers and their closing
directions, the fingertips, the wrist; the builder makes the planner's hand model from it.

    from eos_svc.hands import load_hand_named
    hand = load_hand_named("trifinger")          # or a file: load_hand_named("my_hand.toml")

- :mod:`~eos_svc.hands.spec` — the description format, read and checked key by key;
- :mod:`~eos_svc.hands.sources` — where a URDF is (eos_svc's data, example-robot-data, a path);
- :mod:`~eos_svc.hands.composite` — the URDF a description makes (wrist, parts, tips, flips);
- :mod:`~eos_svc.hands.builder` — description → :class:`DescribedHand`;
- :mod:`~eos_svc.hands.registry` — the shipped descriptions by name.

The format, every key and the shipped hands: ``docs/hands.md``.
"""

from .builder import build_hand, hand_description
from .model import DescribedHand
from .registry import DEFAULT_HAND, HandRegistry, load_hand_named, shipped_hand_files
from .sources import example_robot_data_share
from .spec import HandSpec, parse_hand, read_hand_file

__all__ = [
    "DEFAULT_HAND",
    "DescribedHand",
    "HandRegistry",
    "HandSpec",
    "build_hand",
    "example_robot_data_share",
    "hand_description",
    "load_hand_named",
    "parse_hand",
    "read_hand_file",
    "shipped_hand_files",
]
