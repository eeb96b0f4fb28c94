"""Hand kinematics (Pinocchio), contacts with the objects (coal), tactile sensing.

SI units; world z up; the hand approaches along +x. See ``docs/kinematics.md``.
"""

from .hand import (
    HAND3X3_URDF,
    ConfigurationError,
    FingerDescription,
    HandDescription,
    HandDescriptionError,
    HandModel,
    HandState,
    KinematicsError,
    UnknownNameError,
    UrdfLoadError,
    WorkspaceError,
    load_hand,
)
from .scene import Contact, Scene
from .tactile import TactileReading, TactileSensor

__all__ = [
    "HAND3X3_URDF",
    "ConfigurationError",
    "Contact",
    "FingerDescription",
    "HandDescription",
    "HandDescriptionError",
    "HandModel",
    "HandState",
    "KinematicsError",
    "Scene",
    "TactileReading",
    "TactileSensor",
    "UnknownNameError",
    "UrdfLoadError",
    "WorkspaceError",
    "load_hand",
]
