"""Session fixtures for the kinematics tests: hand3x3 and the Allegro hand, loaded once."""

from __future__ import annotations

import importlib.metadata
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from eos_svc.kinematics import (
    FingerDescription,
    HandDescription,
    HandModel,
    load_hand,
)


def example_robot_data_share() -> Path:
    """``.../cmeel.prefix/share`` of the installed example-robot-data distribution."""
    dist = importlib.metadata.distribution("example-robot-data")
    files = dist.files or []
    for f in files:
        s = str(f).replace("\\", "/")
        if s.endswith("allegro_hand_description/urdf/allegro_right_hand.urdf"):
            urdf = Path(str(dist.locate_file(f))).resolve()
            return urdf.parents[4]  # .../share/example-robot-data/robots/<pkg>/urdf/x.urdf
    raise FileNotFoundError("allegro_right_hand.urdf not found in example-robot-data")


def allegro_description() -> HandDescription:
    """Allegro right hand: four fingers of four joints, sphere tips r = 12 mm, thumb opposes."""
    fingers = []
    for name, first in (("index", 0), ("middle", 4), ("ring", 8), ("thumb", 12)):
        last = first + 3
        fingers.append(
            FingerDescription(
                name=name,
                joints=tuple(f"joint_{k}.0" for k in range(first, first + 4)),
                tip_frame=f"link_{last}.0_tip",
                tip_radius=0.012,
                tip_geometry=f"link_{last}.0_tip_0",
            )
        )
    return HandDescription(
        fingers=tuple(fingers), wrist_joints=(), opposing_finger="thumb", palm_frame="palm_link"
    )


@pytest.fixture(scope="session")
def hand() -> HandModel:
    return load_hand()


@pytest.fixture(scope="session")
def allegro_urdf() -> tuple[Path, Path]:
    share = example_robot_data_share()
    urdf = share / "example-robot-data/robots/allegro_hand_description/urdf/allegro_right_hand.urdf"
    return urdf, share


@pytest.fixture(scope="session")
def allegro(allegro_urdf: tuple[Path, Path]) -> HandModel:
    urdf, share = allegro_urdf
    return load_hand(urdf, allegro_description(), package_dirs=[share])


def _random_q(hand: HandModel, rng: np.random.Generator, margin: float = 0.05) -> np.ndarray:
    lo, hi = hand.lower.copy(), hand.upper.copy()
    out: np.ndarray = lo + (hi - lo) * (margin + (1 - 2 * margin) * rng.random(hand.nq))
    return out


@pytest.fixture(scope="session")
def random_q() -> Callable[..., np.ndarray]:
    """random_q(hand, rng): a random configuration strictly inside the limits."""
    return _random_q
