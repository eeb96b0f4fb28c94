"""A hand description: which joints make which finger, the fingertips, the opposing finger, the palm.

Plain data, checked on creation (:class:`HandDescriptionError` names the field); matched against a
URDF by :class:`~eos_svc.kinematics.hand_model.HandModel`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import HandDescriptionError, UnknownNameError

__all__ = ["FingerDescription", "HandDescription"]


@dataclass(frozen=True)
class FingerDescription:
    """One finger: its name, its 1-DoF joints from the palm outward, the frame at its fingertip
    sphere's centre, the sphere's radius (m) and the tip's collision geometry (None: contacts use
    a sphere of ``tip_radius``)."""

    name: str
    joints: tuple[str, ...]
    tip_frame: str
    tip_radius: float
    tip_geometry: str | None = None

    def __post_init__(self) -> None:
        if not self.name:
            raise HandDescriptionError("finger.name", "must be a non-empty string")
        object.__setattr__(self, "joints", tuple(self.joints))
        if not self.joints:
            raise HandDescriptionError(f"{self.name}.joints", "a finger needs at least one joint")
        if len(set(self.joints)) != len(self.joints):
            raise HandDescriptionError(f"{self.name}.joints", f"repeated joint in {self.joints}")
        r = float(self.tip_radius)
        if not (math.isfinite(r) and r > 0.0):
            raise HandDescriptionError(
                f"{self.name}.tip_radius", f"must be finite and > 0 m, got {self.tip_radius!r}"
            )
        object.__setattr__(self, "tip_radius", r)


@dataclass(frozen=True)
class HandDescription:
    """A hand: its fingers (in :attr:`HandModel.finger_names` order), the joints that move the
    palm (none for a fixed base), the finger opposing the others (the thumb), the palm frame and
    the unit axis in it along which the hand height is measured."""

    fingers: tuple[FingerDescription, ...]
    wrist_joints: tuple[str, ...]
    opposing_finger: str
    palm_frame: str
    height_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "fingers", tuple(self.fingers))
        object.__setattr__(self, "wrist_joints", tuple(self.wrist_joints))
        if len(self.fingers) < 2:
            raise HandDescriptionError("fingers", "a hand needs at least two fingers")
        names = [f.name for f in self.fingers]
        if len(set(names)) != len(names):
            raise HandDescriptionError("fingers", f"repeated finger name in {names}")
        if self.opposing_finger not in names:
            raise HandDescriptionError(
                "opposing_finger", f"{self.opposing_finger!r} is not one of the fingers {names}"
            )
        seen: dict[str, str] = {j: "wrist" for j in self.wrist_joints}
        if len(seen) != len(self.wrist_joints):
            raise HandDescriptionError("wrist_joints", f"repeated joint in {self.wrist_joints}")
        for f in self.fingers:
            for j in f.joints:
                if j in seen:
                    raise HandDescriptionError(
                        f"{f.name}.joints", f"joint {j!r} already belongs to {seen[j]}"
                    )
                seen[j] = f.name
        ax = np.asarray(self.height_axis, dtype=float)
        if ax.shape != (3,) or not np.all(np.isfinite(ax)) or np.linalg.norm(ax) < 1e-9:
            raise HandDescriptionError("height_axis", "must be a finite non-zero 3-vector")
        object.__setattr__(self, "height_axis", tuple(float(x) for x in ax / np.linalg.norm(ax)))

    @classmethod
    def hand3x3(cls, tip_radius: float = 0.01) -> HandDescription:
        """The description of ``urdf/hand3x3.urdf`` (finger3 opposes finger1 and finger2)."""
        fingers = tuple(
            FingerDescription(
                name=f"finger{i}",
                joints=tuple(f"finger{i}_j{k}" for k in (1, 2, 3)),
                tip_frame=f"finger{i}_tip",
                tip_radius=tip_radius,
                tip_geometry=f"finger{i}_tip_0",
            )
            for i in (1, 2, 3)
        )
        return cls(
            fingers=fingers,
            wrist_joints=tuple(f"wrist_{j}" for j in ("x", "y", "z", "roll", "pitch", "yaw")),
            opposing_finger="finger3",
            palm_frame="palm",
        )

    def finger(self, name: str) -> FingerDescription:
        """The finger called ``name``."""
        for f in self.fingers:
            if f.name == name:
                return f
        raise UnknownNameError("finger", f"unknown finger {name!r}; known: {self.finger_names}")

    @property
    def finger_names(self) -> tuple[str, ...]:
        """Finger names in description order."""
        return tuple(f.name for f in self.fingers)
