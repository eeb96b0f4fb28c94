"""The hand: a Pinocchio model + coal collision geometry loaded from a URDF and a hand description.

Units are SI (m, rad, s). World z is up; the hand approaches along +x.

- :class:`FingerDescription` / :class:`HandDescription` say which joints make which finger,
  which frames are fingertip sphere centres and their radii, which finger opposes the others.
- :func:`load_hand` loads any URDF with such a description into a :class:`HandModel`.
- :class:`HandState` keeps ``q``, ``pin.Data`` and ``pin.GeometryData`` consistent (like pink's
  ``Configuration``): every read after :meth:`HandState.update` refers to the same ``q``.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from eos_svc.errors import NotFoundError, ValidationError

from .assets import data_file

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

_LWA = pin.LOCAL_WORLD_ALIGNED
_F64 = np.dtype(np.float64)

#: The three-finger hand's URDF (from the installed package's data, or the checkout's urdf/).
HAND3X3_URDF: Path = data_file("hand3x3.urdf")


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


# --------------------------------------------------------------------------- descriptions


@dataclass(frozen=True)
class FingerDescription:
    """One finger.

    Attributes:
        name: finger name (``"finger1"``).
        joints: its joint names, from the palm outward (each a 1-DoF joint).
        tip_frame: frame at the fingertip sphere centre.
        tip_radius: fingertip sphere radius, m (> 0).
        tip_geometry: collision geometry name of the tip in the GeometryModel (or None: the
            tip then has no geometry of its own and contacts use a sphere of ``tip_radius``).
    """

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
    """Which joints make which finger, the fingertips, the opposing finger, the palm.

    Attributes:
        fingers: the fingers; their order is the order of :attr:`HandModel.finger_names`.
        wrist_joints: joints that move the palm (may be empty for a fixed-base hand).
        opposing_finger: the finger opposing the others (the thumb; finger3 for hand3x3).
        palm_frame: frame of the palm.
        height_axis: unit axis in the palm frame along which the hand height is measured.
    """

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
            wrist_joints=(
                "wrist_x",
                "wrist_y",
                "wrist_z",
                "wrist_roll",
                "wrist_pitch",
                "wrist_yaw",
            ),
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


# --------------------------------------------------------------------------- loading


@contextlib.contextmanager
def _capture_stderr() -> Iterator[io.StringIO]:
    """Capture C-level and Python stderr (Pinocchio prints URDF warnings there)."""
    buf = io.StringIO()
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, io.UnsupportedOperation, ValueError):
        with contextlib.redirect_stderr(buf):
            yield buf
        return
    import tempfile

    sys.stderr.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), fd)
        try:
            with contextlib.redirect_stderr(buf):
                yield buf
        finally:
            sys.stderr.flush()
            os.dup2(saved, fd)
            os.close(saved)
            tmp.seek(0)
            buf.write(tmp.read().decode(errors="replace"))


def load_hand(
    urdf_path: str | os.PathLike[str] = HAND3X3_URDF,
    description: HandDescription | None = None,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
) -> HandModel:
    """Load a hand from a URDF and its description (default: hand3x3).

    Args:
        urdf_path: the URDF file.
        description: the hand description; ``None`` means :meth:`HandDescription.hand3x3`.
        package_dirs: directories Pinocchio searches to resolve ``package://`` mesh URIs.

    Raises:
        UrdfLoadError: the file is missing or Pinocchio cannot parse it.
        HandDescriptionError / UnknownNameError: the description does not match the URDF.
    """
    path = Path(urdf_path)
    if not path.is_file():
        raise UrdfLoadError("urdf_path", f"no such file: {path}")
    desc = description if description is not None else HandDescription.hand3x3()
    dirs = [str(Path(p)) for p in package_dirs]
    try:
        with _capture_stderr() as err:
            model = pin.buildModelFromUrdf(str(path))
            gmodel = pin.buildGeomFromUrdf(model, str(path), pin.COLLISION, package_dirs=dirs)
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError with a parser message
        raise UrdfLoadError("urdf_path", f"Pinocchio cannot load {path}: {exc}") from exc
    warnings = err.getvalue().strip()
    return HandModel(model, gmodel, desc, urdf_path=path, load_warnings=warnings)


# --------------------------------------------------------------------------- the model


class HandModel:
    """A hand: Pinocchio model, collision GeometryModel and the description that names its parts.

    Build with :func:`load_hand`. Immutable in use: per-configuration data lives in
    :class:`HandState` (``hand.state(q)``).
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
        self._q_shape = (self.nq,)
        self.finger_names: tuple[str, ...] = description.finger_names
        self.opposing_finger: str = description.opposing_finger

        self._q_index: dict[str, np.ndarray] = {}
        self._joint_limits: dict[str, tuple[tuple[int, float, float], ...]] = {}
        self._v_index: dict[str, np.ndarray] = {}
        for f in description.fingers:
            qi, vi = self._joint_indices(f.joints, f"{f.name}.joints")
            self._q_index[f.name], self._v_index[f.name] = qi, vi
        self._wrist_q, self._wrist_v = self._joint_indices(description.wrist_joints, "wrist_joints")

        self._tip_fid: dict[str, int] = {}
        self._tip_radius: dict[str, float] = {}
        self._tip_gid: dict[str, int | None] = {}
        for f in description.fingers:
            fid = self._frame_id(f.tip_frame, f"{f.name}.tip_frame")
            self._tip_fid[f.name] = fid
            self._tip_radius[f.name] = f.tip_radius
            self._tip_gid[f.name] = self._check_tip_geometry(f, fid)
        self.palm_frame_id: int = self._frame_id(description.palm_frame, "palm_frame")

        self.lower: np.ndarray = np.array(model.lowerPositionLimit, dtype=float)
        self.upper: np.ndarray = np.array(model.upperPositionLimit, dtype=float)
        self.velocity_limit: np.ndarray = np.array(model.velocityLimit, dtype=float)
        self.effort_limit: np.ndarray = np.array(model.effortLimit, dtype=float)
        for name, idx in [*self._q_index.items(), ("wrist", self._wrist_q)]:
            lo, hi = self.lower[idx], self.upper[idx]
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
                raise HandDescriptionError(
                    f"{name}.joints", "every finger and wrist joint needs finite limits lower < upper"
                )
        self.hand_height: float = self._compute_hand_height()

    # -- construction helpers
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
    def _check_finger(self, name: str) -> None:
        if name not in self._q_index:
            raise UnknownNameError("finger", f"unknown finger {name!r}; known: {self.finger_names}")

    def finger_q_index(self, name: str) -> np.ndarray:
        """Indices in q of the finger's joints (palm outward)."""
        self._check_finger(name)
        return self._q_index[name].copy()

    def finger_joint_limits(self, name: str) -> tuple[tuple[int, float, float], ...]:
        """(q index, lower, upper) of each of the finger's joints, palm outward (cached)."""
        limits = self._joint_limits.get(name)
        if limits is None:
            self._check_finger(name)
            limits = tuple(
                (int(i), float(self.lower[i]), float(self.upper[i])) for i in self._q_index[name]
            )
            self._joint_limits[name] = limits
        return limits

    def finger_v_index(self, name: str) -> np.ndarray:
        """Indices in v of the finger's joints (palm outward)."""
        self._check_finger(name)
        return self._v_index[name].copy()

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
        self._check_finger(name)
        return self._tip_radius[name]

    def tip_frame_id(self, name: str) -> int:
        """Pinocchio frame id of finger ``name``'s tip (sphere centre)."""
        self._check_finger(name)
        return self._tip_fid[name]

    def tip_geometry_id(self, name: str) -> int | None:
        """Collision geometry index of finger ``name``'s tip, or None."""
        self._check_finger(name)
        return self._tip_gid[name]

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
            and q.shape == self._q_shape
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


# --------------------------------------------------------------------------- the state


class HandState:
    """q, Pinocchio data and geometry data of one hand, kept consistent.

    :meth:`update` runs forward kinematics, frame placements and joint Jacobians once (geometry
    placements once, when first needed); every query afterwards reads those results.
    """

    __slots__ = ("_gdata", "_geom_stale", "_gmodel", "_q", "_tips", "data", "hand", "model")

    def __init__(self, hand: HandModel, q: object = None) -> None:
        self.hand = hand
        self.model = hand.model
        self.data = hand.model.createData()
        self._gmodel = hand.collision_model
        self._gdata = pin.GeometryData(hand.collision_model)
        self._geom_stale = True
        # Per finger, cached once (Python access to data.oMf[i] costs ~2 µs): frame id, parent
        # joint id, the joint placement (a live reference into data.oMi), the tip translation
        # (a live view into data.oMf; never handed out), and a reusable point placement.
        self._tips: dict[str, tuple[int, int, pin.SE3, np.ndarray, pin.SE3]] = {}
        for name in hand.finger_names:
            fid = hand.tip_frame_id(name)
            jid = int(hand.model.frames[fid].parentJoint)
            self._tips[name] = (
                fid,
                jid,
                self.data.oMi[jid],
                self.data.oMf[fid].translation,
                pin.SE3.Identity(),
            )
        self._q = hand.neutral()
        self.update(self._q if q is None else q)

    @property
    def q(self) -> np.ndarray:
        """The current configuration (a copy)."""
        return self._q.copy()

    def update(self, q: object) -> None:
        """Set ``q`` (validated: length, finite) and recompute kinematics (joint Jacobians,
        frame placements); the geometry placements follow on first use of :attr:`geometry_data`."""
        hand = self.hand
        if (  # inlined fast path of HandModel.validate_q (this is the hot path)
            type(q) is np.ndarray
            and q.dtype is _F64
            and q.shape == hand._q_shape
            and math.isfinite(sum(q.tolist()))
        ):
            qa = q.copy()
        else:
            qa = hand.validate_q(q)
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, qa)  # also computes data.oMi (forward kinematics)
        pin.updateFramePlacements(model, data)
        # geometry placements are computed on first use (most updates only need the tips)
        self._geom_stale = True
        self._q = qa

    @property
    def geometry_data(self) -> pin.GeometryData:
        """Pinocchio geometry data (collision placements ``oMg``) at the current q."""
        if self._geom_stale:
            pin.updateGeometryPlacements(self.model, self.data, self._gmodel, self._gdata)
            self._geom_stale = False
        return self._gdata

    def copy(self) -> HandState:
        """An independent state at the same q."""
        return HandState(self.hand, self._q)

    # -- placements
    def frame_placement(self, frame: str) -> pin.SE3:
        """World placement of any frame (a copy)."""
        return pin.SE3(self.data.oMf[self.hand.frame_id(frame)])

    def tip_placement(self, finger: str) -> pin.SE3:
        """World placement of the fingertip frame (sphere centre), a copy."""
        return pin.SE3(self.data.oMf[self.hand.tip_frame_id(finger)])

    def tip_position(self, finger: str) -> np.ndarray:
        """World position of the fingertip sphere centre, m (a copy)."""
        out: np.ndarray = self.data.oMf[self.hand.tip_frame_id(finger)].translation.copy()
        return out

    def palm_placement(self) -> pin.SE3:
        """World placement of the palm frame, a copy."""
        return pin.SE3(self.data.oMf[self.hand.palm_frame_id])

    def geometry_placement(self, name: str) -> pin.SE3:
        """World placement of a collision geometry, a copy."""
        return pin.SE3(self.geometry_data.oMg[self.hand.geometry_id(name)])

    # -- Jacobians
    def tip_jacobian(self, finger: str) -> np.ndarray:
        """6×nv Jacobian of the tip frame origin (the fingertip sphere's centre, a material point
        of the fingertip body) and of the fingertip's orientation, LOCAL_WORLD_ALIGNED
        ([v; ω] in world axes)."""
        tip = self._tips.get(finger)
        if tip is None:
            tip = self._tip(finger)  # raises UnknownNameError
        return pin.getFrameJacobian(self.model, self.data, tip[0], _LWA)

    def _tip(self, finger: str) -> tuple[int, int, pin.SE3, np.ndarray, pin.SE3]:
        try:
            return self._tips[finger]
        except KeyError:
            raise UnknownNameError(
                "finger", f"unknown finger {finger!r}; known: {self.hand.finger_names}"
            ) from None

    def tip_point_jacobian(self, finger: str, point_world: np.ndarray) -> np.ndarray:
        """3×nv Jacobian: world linear velocity of the material point of the fingertip body that
        is currently at ``point_world`` (m), per unit joint velocity."""
        tip = self._tips.get(finger)
        if tip is None:
            tip = self._tip(finger)  # raises UnknownNameError
        _, jid, oMi, _, M = tip
        if type(point_world) is not np.ndarray or point_world.shape != (3,):
            point_world = np.asarray(point_world, dtype=float)
            if point_world.shape != (3,):
                raise ConfigurationError("point_world", f"must be a 3-vector, got {point_world!r}")
        M.translation = oMi.actInv(point_world)  # the point in the tip body's joint frame
        J = pin.getFrameJacobian(self.model, self.data, jid, M, pin.LOCAL_WORLD_ALIGNED)
        out: np.ndarray = J[:3]
        return out

    def tip_angular_jacobian(self, finger: str) -> np.ndarray:
        """3×nv Jacobian of the fingertip body's angular velocity in world axes."""
        J = pin.getFrameJacobian(
            self.model, self.data, self.hand.tip_frame_id(finger), pin.LOCAL_WORLD_ALIGNED
        )
        out: np.ndarray = J[3:].copy()
        return out

    # -- motions (return a new q; the state is not changed)
    def close_finger(self, finger: str, dtheta: float) -> tuple[np.ndarray, bool]:
        """New q with every joint of ``finger`` changed by ``dtheta`` rad (positive closes),
        clipped to the joint limits; the flag is True when a limit was hit.

        Scalar arithmetic over the finger's few joints: it is on the planner's hot path.
        """
        if not math.isfinite(dtheta):
            raise ConfigurationError("dtheta", f"must be finite, got {dtheta!r}")
        q = self._q.copy()
        at_limit = False
        for i, lo, hi in self.hand.finger_joint_limits(finger):
            target = q[i] + dtheta
            if target <= lo:
                q[i], at_limit = lo, True
            elif target >= hi:
                q[i], at_limit = hi, True
            else:
                q[i] = target
        return q, at_limit

    def move_wrist(
        self,
        dp_world: np.ndarray,
        drpy: np.ndarray | None = None,
        clip: bool = False,
    ) -> np.ndarray:
        """New q with the wrist translated by ``dp_world`` (m, world axes) and its roll, pitch,
        yaw joints changed by ``drpy`` (rad).

        The first three wrist joints must be the x, y, z prismatic joints and the next three
        the roll, pitch, yaw joints (hand3x3). Leaving the joint limits raises
        :class:`WorkspaceError`, or clips when ``clip`` is True.
        """
        widx = self.hand._wrist_q
        if len(widx) < 3:
            raise WorkspaceError("wrist_joints", "this hand has no x, y, z wrist joints")
        dp = np.asarray(dp_world, dtype=float)
        if dp.shape != (3,) or not np.isfinite(dp).all():
            raise WorkspaceError("dp_world", f"must be a finite 3-vector, got {dp_world!r}")
        q = self._q.copy()
        q[widx[:3]] += dp
        if drpy is not None:
            dr = np.asarray(drpy, dtype=float)
            if dr.shape != (3,) or not np.isfinite(dr).all():
                raise WorkspaceError("drpy", f"must be a finite 3-vector, got {drpy!r}")
            if len(widx) < 6:
                raise WorkspaceError("drpy", "this hand has no roll, pitch, yaw wrist joints")
            q[widx[3:6]] += dr
        lo, hi = self.hand.lower[widx], self.hand.upper[widx]
        if np.any(q[widx] < lo - 1e-12) or np.any(q[widx] > hi + 1e-12):
            if clip:
                q[widx] = np.clip(q[widx], lo, hi)
            else:
                names = self.hand.description.wrist_joints
                bad = [
                    f"{names[k]}={q[i]:.4g} not in [{lo[k]:.4g}, {hi[k]:.4g}]"
                    for k, i in enumerate(widx)
                    if q[i] < lo[k] - 1e-12 or q[i] > hi[k] + 1e-12
                ]
                raise WorkspaceError("wrist", "outside the workspace: " + ", ".join(bad))
        return q

    def integrate(self, v: np.ndarray, dt: float) -> np.ndarray:
        """New q = integrate(q, v·dt) (Pinocchio), v in joint velocity units, dt in s."""
        va = np.asarray(v, dtype=float)
        if va.shape != (self.hand.nv,) or not np.isfinite(va).all():
            raise ConfigurationError("v", f"must be a finite vector of shape ({self.hand.nv},)")
        if not math.isfinite(dt):
            raise ConfigurationError("dt", f"must be finite, got {dt!r}")
        out: np.ndarray = pin.integrate(self.model, self._q, va * dt)
        return out
