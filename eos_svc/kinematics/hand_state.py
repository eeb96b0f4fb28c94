"""The state of one hand: ``q``, Pinocchio data and geometry data kept consistent (like pink's
``Configuration``): every read after :meth:`HandState.update` refers to the same ``q``.
Motions (:meth:`HandState.close_finger`, :meth:`HandState.move_wrist`) return a new ``q``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .errors import ConfigurationError, UnknownNameError, WorkspaceError

if TYPE_CHECKING:
    from .hand_model import HandModel

__all__ = ["HandState", "read_only"]

_LWA = pin.LOCAL_WORLD_ALIGNED


def read_only(array: np.ndarray) -> np.ndarray:
    """``array`` marked read-only, in place (a view's memory stays its owner's: Pinocchio still
    updates it)."""
    array.flags.writeable = False
    return array


class HandState:
    """q, Pinocchio data and geometry data of one hand, kept consistent.

    :meth:`update` runs forward kinematics and frame placements; the joint Jacobians and the
    geometry placements are computed when first needed at that q.
    """

    __slots__ = (
        "_frame_views",
        "_gdata",
        "_geom_stale",
        "_geometry_views",
        "_jac_stale",
        "_q",
        "_tips",
        "data",
        "hand",
        "model",
    )

    def __init__(self, hand: HandModel, q: object = None) -> None:
        self.hand = hand
        self.model = hand.model
        self.data = hand.model.createData()
        self._gdata = pin.GeometryData(hand.collision_model)
        self._geom_stale = True
        self._jac_stale = True
        # live views into data.oMf / the geometry data's oMg, made on first use (see frame_views)
        self._frame_views: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._geometry_views: list[tuple[np.ndarray, np.ndarray]] | None = None
        # per finger (read from Python, data.oMf[i] costs µs): the tip frame, its body's joint and
        # that joint's placement, the tip centre (live views), and a placement to compute in
        self._tips: dict[str, tuple[int, int, pin.SE3, np.ndarray, pin.SE3]] = {}
        for f in hand.finger_names:
            fid = hand.tip_frame_id(f)
            jid = int(hand.model.frames[fid].parentJoint)
            centre = read_only(self.data.oMf[fid].translation)
            self._tips[f] = (fid, jid, self.data.oMi[jid], centre, pin.SE3.Identity())
        self._q = hand.neutral()
        self.update(self._q if q is None else q)

    @property
    def q(self) -> np.ndarray:
        """The current configuration (a copy)."""
        return self._q.copy()

    def update(self, q: object) -> None:
        """Set ``q`` (validated: length, finite) and recompute the joint and frame placements; the
        joint Jacobians and geometry placements follow on first use."""
        self._q = self.hand.validate_q(q)
        pin.framesForwardKinematics(self.model, self.data, self._q)
        self._jac_stale = True
        self._geom_stale = True

    def joint_jacobians(self) -> None:
        """Compute the joint Jacobians (``data.J``, world frame) at the current q, once per
        :meth:`update` (from the placements it left): call it before reading ``data.J``."""
        if self._jac_stale:
            pin.computeJointJacobians(self.model, self.data)
            self._jac_stale = False

    @property
    def geometry_data(self) -> pin.GeometryData:
        """Pinocchio geometry data (collision placements ``oMg``) at the current q."""
        if self._geom_stale:
            pin.updateGeometryPlacements(self.model, self.data, self.hand.collision_model, self._gdata)
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
        return self.tip_centre_view(finger).copy()

    def tip_centre_view(self, finger: str) -> np.ndarray:
        """World position of the fingertip sphere centre, m, as a live read-only view that
        follows every :meth:`update`."""
        return self._tip(finger)[3]

    def _tip(self, finger: str) -> tuple[int, int, pin.SE3, np.ndarray, pin.SE3]:
        try:
            return self._tips[finger]
        except KeyError:
            raise UnknownNameError(
                "finger", f"unknown finger {finger!r}; known: {self.hand.finger_names}"
            ) from None

    def frame_views(self, frame_id: int) -> tuple[np.ndarray, np.ndarray]:
        """Live read-only views of frame ``frame_id``'s world translation (m) and rotation: they
        follow every :meth:`update` (copy what must outlive a move)."""
        views = self._frame_views.get(frame_id)
        if views is None:
            placement = self.data.oMf[frame_id]
            views = self._frame_views[frame_id] = (
                read_only(placement.translation),
                read_only(placement.rotation),
            )
        return views

    def geometry_views(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Live read-only views of every collision geometry's world translation (m) and rotation,
        by geometry id, as :attr:`geometry_data` last computed them (read it after an update)."""
        if self._geometry_views is None:
            oMg = self._gdata.oMg
            self._geometry_views = [(read_only(M.translation), read_only(M.rotation)) for M in oMg]
        return self._geometry_views

    def palm_placement(self) -> pin.SE3:
        """World placement of the palm frame, a copy."""
        return pin.SE3(self.data.oMf[self.hand.palm_frame_id])

    def geometry_placement(self, name: str) -> pin.SE3:
        """World placement of a collision geometry, a copy."""
        return pin.SE3(self.geometry_data.oMg[self.hand.geometry_id(name)])

    # -- Jacobians (LOCAL_WORLD_ALIGNED: [v; ω] in world axes)
    def tip_jacobian(self, finger: str) -> np.ndarray:
        """6×nv Jacobian of the tip frame origin (the fingertip sphere's centre) and of the
        fingertip's orientation."""
        fid = self._tip(finger)[0]
        if self._jac_stale:
            self.joint_jacobians()
        return pin.getFrameJacobian(self.model, self.data, fid, _LWA)

    def tip_point_jacobian(self, finger: str, point_world: np.ndarray) -> np.ndarray:
        """3×nv Jacobian: world linear velocity of the material point of the fingertip body that
        is currently at ``point_world`` (m), per unit joint velocity."""
        _, jid, oMi, _, local = self._tip(finger)
        point = np.asarray(point_world, dtype=float)
        if point.shape != (3,):
            raise ConfigurationError("point_world", f"must be a 3-vector, got {point_world!r}")
        local.translation = oMi.actInv(point)  # the point in the tip body's joint frame
        if self._jac_stale:
            self.joint_jacobians()
        out: np.ndarray = pin.getFrameJacobian(self.model, self.data, jid, local, _LWA)[:3]
        return out

    def tip_angular_jacobian(self, finger: str) -> np.ndarray:
        """3×nv Jacobian of the fingertip body's angular velocity in world axes."""
        out: np.ndarray = self.tip_jacobian(finger)[3:].copy()
        return out

    # -- motions (return a new q; the state is not changed)
    def close_finger(self, finger: str, dtheta: float) -> tuple[np.ndarray, bool]:
        """New q with every joint of ``finger`` changed by ``dtheta`` rad (positive closes),
        clipped to the joint limits; the flag is True when a limit was hit."""
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
        """New q with the wrist's x, y, z joints (the first three) moved by ``dp_world`` (m, world
        axes) and its roll, pitch, yaw joints (the next three) by ``drpy`` (rad); leaving the
        joint limits raises :class:`WorkspaceError`, or clips when ``clip``."""
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
