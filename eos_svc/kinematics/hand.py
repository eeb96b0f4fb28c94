"""The hand, in one import: description, URDF loading, model, state and their errors
(``docs/kinematics.md``). SI units; world z up; the hand approaches along +x.
"""

from __future__ import annotations

from .description import FingerDescription, HandDescription
from .errors import (
    ConfigurationError,
    HandDescriptionError,
    KinematicsError,
    UnknownNameError,
    UrdfLoadError,
    WorkspaceError,
)
from .hand_model import HandModel
from .hand_state import HandState
from .urdf_loading import HAND3X3_URDF, load_hand

__all__ = [
    "HAND3X3_URDF",
    "ConfigurationError",
    "FingerDescription",
    "HandDescription",
    "HandDescriptionError",
    "HandModel",
    "HandState",
    "KinematicsError",
    "UnknownNameError",
    "UrdfLoadError",
    "WorkspaceError",
    "load_hand",
]
