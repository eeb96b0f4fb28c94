"""Errors of the kinematics layer: bad input, each naming the field and the reason.

All are :class:`eos_svc.errors.ValidationError` (so ``EosError`` and ``ValueError``).
"""

from __future__ import annotations

from eos_svc.errors import NotFoundError, ValidationError

__all__ = [
    "ConfigurationError",
    "HandDescriptionError",
    "KinematicsError",
    "UnknownNameError",
    "UrdfLoadError",
    "WorkspaceError",
]


class KinematicsError(ValidationError):
    """Bad input to the kinematics layer. ``field`` names what is wrong, ``reason`` says why."""


class HandDescriptionError(KinematicsError):
    """A hand description is malformed or does not match its URDF."""


class UnknownNameError(KinematicsError, NotFoundError):
    """An unknown finger, frame, joint or geometry name."""


class ConfigurationError(KinematicsError):
    """A configuration ``q`` (or velocity) of the wrong length, non-finite, or out of limits."""


class UrdfLoadError(KinematicsError):
    """A URDF that does not exist or that Pinocchio cannot load."""


class WorkspaceError(KinematicsError):
    """A wrist motion that leaves the bounded workspace."""
