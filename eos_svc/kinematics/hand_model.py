"""The hand model: a Pinocchio model, its collision GeometryModel and the description naming its
parts (indices, frames, limits, the hand height). Immutable in use; per-configuration data lives
in :class:`~eos_svc.kinematics.hand_state.HandState`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from .description import FingerDescription, HandDescription
from .errors import ConfigurationError, HandDescriptionError, UnknownNameError
from .hand_state import HandState

__all__ = ["HandModel"]

_F64 = np.dtype(np.float64)


@dataclass(frozen=True)
class _Finger:
    """What the model knows of one finger: its joints' indices in q and v, (q index, lower,
    upper) of each, its tip frame, radius (m) and collision geometry (or None)."""

    q_index: np.ndarray
    v_index: np.ndarray
    limits: tuple[tuple[int, float, float], ...]
    tip_frame: int
    tip_radius: float
    tip_geometry: int | None


class HandModel:
    """A hand: Pinocchio model, collision GeometryModel and the description that names its parts.

    Build with :func:`load_hand`; per-configuration data lives in :class:`HandState`
    (``hand.state(q)``).
    """

    def __init__(
        self,
        model: pin.Model,
        collision_model: pin.GeometryModel,
        description: HandDescription,
        urdf_path: Path | None = None,
        load_warnings: str = "",
    ) -> None:
        self.model = model
        self.collision_model = collision_model
        self.description = description
        self.urdf_path = urdf_path
        self.load_warnings = load_warnings
        self.nq: int = int(model.nq)
        self.nv: int = int(model.nv)
        self.finger_names: tuple[str, ...] = description.finger_names
        self.opposing_finger: str = description.opposing_finger
        self.lower: np.ndarray = np.array(model.lowerPositionLimit, dtype=float)
        self.upper: np.ndarray = np.array(model.upperPositionLimit, dtype=float)
        self.velocity_limit: np.ndarray = np.array(model.velocityLimit, dtype=float)
        self.effort_limit: np.ndarray = np.array(model.effortLimit, dtype=float)
        self._wrist_q, self._wrist_v = self._joint_indices(description.wrist_joints, "wrist_joints")
        self._fingers: dict[str, _Finger] = {}
        for f in description.fingers:
            qi, vi = self._joint_indices(f.joints, f"{f.name}.joints")
            fid = self._frame_id(f.tip_frame, f"{f.name}.tip_frame")
            limits = tuple((int(i), float(self.lower[i]), float(self.upper[i])) for i in qi)
            self._fingers[f.name] = _Finger(
                qi, vi, limits, fid, f.tip_radius, self._check_tip_geometry(f, fid)
            )
        self.palm_frame_id: int = self._frame_id(description.palm_frame, "palm_frame")
        for name, idx in [*((n, f.q_index) for n, f in self._fingers.items()), ("wrist", self._wrist_q)]:
            lo, hi = self.lower[idx], self.upper[idx]
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
                raise HandDescriptionError(
                    f"{name}.joints", "every finger and wrist joint needs finite limits lower < upper"
                )
        self.hand_height: float = self._compute_hand_height()

    def _joint_indices(self, joints: Sequence[str], field: str) -> tuple[np.ndarray, np.ndarray]:
        qi, vi = [], []
        for j in joints:
            if not self.model.existJointName(j):
                raise HandDescriptionError(field, f"joint {j!r} is not in the URDF model")
            joint = self.model.joints[self.model.getJointId(j)]
            if joint.nq != 1 or joint.nv != 1:
                raise HandDescriptionError(
                    field, f"joint {j!r} has nq={joint.nq}, nv={joint.nv}; expected a 1-DoF joint"
                )
            qi.append(joint.idx_q)
            vi.append(joint.idx_v)
        return np.array(qi, dtype=np.intp), np.array(vi, dtype=np.intp)

    def _frame_id(self, name: str, field: str) -> int:
        if not self.model.existFrame(name):
            raise HandDescriptionError(field, f"frame {name!r} is not in the URDF model")
        return int(self.model.getFrameId(name))

    def _check_tip_geometry(self, f: FingerDescription, fid: int) -> int | None:
        if f.tip_geometry is None:
            return None
        gm = self.collision_model
        if not gm.existGeometryName(f.tip_geometry):
            raise HandDescriptionError(
                f"{f.name}.tip_geometry",
                f"geometry {f.tip_geometry!r} is not in the collision model "
                f"(known: {[g.name for g in gm.geometryObjects]})",
            )
        gid = int(gm.getGeometryId(f.tip_geometry))
        go = gm.geometryObjects[gid]
        frame = self.model.frames[fid]
        if go.parentJoint != frame.parentJoint:
            raise HandDescriptionError(
                f"{f.name}.tip_geometry",
                f"{f.tip_geometry!r} is not attached to the body of frame {f.tip_frame!r}",
            )
        if isinstance(go.geometry, coal.Sphere):
            if abs(go.geometry.radius - f.tip_radius) > 1e-6:
                raise HandDescriptionError(
                    f"{f.name}.tip_radius",
                    f"{f.tip_radius} m does not match the URDF sphere radius "
                    f"{go.geometry.radius} m of {f.tip_geometry!r}",
                )
            off = np.linalg.norm(go.placement.translation - frame.placement.translation)
            if off > 1e-6:
                raise HandDescriptionError(
                    f"{f.name}.tip_frame",
                    f"frame {f.tip_frame!r} is {off:.3g} m from the centre of sphere "
                    f"{f.tip_geometry!r}; the tip frame must be the sphere centre",
                )
        return gid

    def _compute_hand_height(self) -> float:
        """Distance between the mean of the non-opposing tips and the opposing tip along
        the palm's height axis, at the neutral configuration (m)."""
        st = self.state(self.neutral())
        palm = st.palm_placement()
        ax = palm.rotation @ np.asarray(self.description.height_axis)
        opp = st.tip_position(self.opposing_finger)
        others = [st.tip_position(n) for n in self.finger_names if n != self.opposing_finger]
        return float(abs(ax @ (np.mean(others, axis=0) - opp)))

    # -- queries
    def _finger(self, name: str) -> _Finger:
        try:
            return self._fingers[name]
        except KeyError:
            raise UnknownNameError("finger", f"unknown finger {name!r}; known: {self.finger_names}") from None

    def finger_q_index(self, name: str) -> np.ndarray:
        """Indices in q of the finger's joints (palm outward)."""
        return self._finger(name).q_index.copy()

    def finger_joint_limits(self, name: str) -> tuple[tuple[int, float, float], ...]:
        """(q index, lower, upper) of each of the finger's joints, palm outward."""
        return self._finger(name).limits

    def finger_v_index(self, name: str) -> np.ndarray:
        """Indices in v of the finger's joints (palm outward)."""
        return self._finger(name).v_index.copy()

    @property
    def wrist_q_index(self) -> np.ndarray:
        """Indices in q of the wrist joints (x, y, z, roll, pitch, yaw for hand3x3)."""
        return self._wrist_q.copy()

    @property
    def wrist_v_index(self) -> np.ndarray:
        """Indices in v of the wrist joints."""
        return self._wrist_v.copy()

    def tip_radius(self, name: str) -> float:
        """Fingertip sphere radius of finger ``name``, m."""
        return self._finger(name).tip_radius

    def tip_frame_id(self, name: str) -> int:
        """Pinocchio frame id of finger ``name``'s tip (sphere centre)."""
        return self._finger(name).tip_frame

    def tip_geometry_id(self, name: str) -> int | None:
        """Collision geometry index of finger ``name``'s tip, or None."""
        return self._finger(name).tip_geometry

    def frame_id(self, name: str) -> int:
        """Pinocchio frame id of any frame; raises :class:`UnknownNameError` if absent."""
        if not self.model.existFrame(name):
            raise UnknownNameError("frame", f"unknown frame {name!r}")
        return int(self.model.getFrameId(name))

    def joint_q_index(self, name: str) -> int:
        """Index in q of a 1-DoF joint; raises :class:`UnknownNameError` if absent."""
        if not self.model.existJointName(name):
            raise UnknownNameError("joint", f"unknown joint {name!r}")
        return int(self.model.joints[self.model.getJointId(name)].idx_q)

    def geometry_id(self, name: str) -> int:
        """Index of a collision geometry; raises :class:`UnknownNameError` if absent."""
        if not self.collision_model.existGeometryName(name):
            known = [g.name for g in self.collision_model.geometryObjects]
            raise UnknownNameError("geometry", f"unknown geometry {name!r}; known: {known}")
        return int(self.collision_model.getGeometryId(name))

    def neutral(self) -> np.ndarray:
        """Neutral configuration (all joints 0 for hand3x3: fingers straight, wrist at origin)."""
        return np.array(pin.neutral(self.model), dtype=float)

    def validate_q(self, q: object, field: str = "q") -> np.ndarray:
        """Return ``q`` as a fresh float array after checking length and finiteness."""
        if (
            type(q) is np.ndarray
            and q.dtype is _F64
            and q.shape == (self.nq,)
            and math.isfinite(sum(q.tolist()))  # fast path; overflow falls through to the check
        ):
            return q.copy()
        try:
            arr = np.array(q, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ConfigurationError(field, f"not a numeric vector: {exc}") from exc
        if arr.shape != (self.nq,):
            raise ConfigurationError(field, f"expected shape ({self.nq},), got {arr.shape}")
        if not np.isfinite(arr).all():
            bad = np.flatnonzero(~np.isfinite(arr)).tolist()
            raise ConfigurationError(field, f"non-finite entries at indices {bad}")
        return arr

    def within_limits(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        """True when ``q`` is within the position limits (± tol)."""
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def state(self, q: object = None) -> HandState:
        """A new :class:`HandState` at ``q`` (default: :meth:`neutral`)."""
        return HandState(self, q)

    def __repr__(self) -> str:
        return (
            f"HandModel({self.model.name!r}, nq={self.nq}, fingers={self.finger_names}, "
            f"h={self.hand_height:.4f} m)"
        )
