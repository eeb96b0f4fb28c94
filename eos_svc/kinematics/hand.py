"""The hand, in one import: description, URDF loading, model, state and their errors.

Units are SI (m, rad, s). World z is up; the hand approaches along +x. Each concept has its own
module:

- :mod:`~eos_svc.kinematics.description` — :class:`FingerDescription` / :class:`HandDescription`
  say which joints make which finger, which frames are fingertip sphere centres and their radii,
  which finger opposes the others;
- :mod:`~eos_svc.kinematics.urdf_loading` — :func:`load_hand` loads any URDF with such a
  description into a :class:`HandModel` (``HAND3X3_URDF``: the three-finger hand);
- :mod:`~eos_svc.kinematics.hand_model` — :class:`HandModel`: Pinocchio model, collision
  geometry, indices, limits, hand height;
- :mod:`~eos_svc.kinematics.hand_state` — :class:`HandState` keeps ``q``, ``pin.Data`` and
  ``pin.GeometryData`` consistent;
- :mod:`~eos_svc.kinematics.errors` — the errors, each naming the field and the reason.
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
