"""Rolling a sphere fingertip on the object without sliding (EP1's motion), a differential-IK
loop in the manner of pink: per step, Pinocchio kinematics, a coal contact, the QP of
:mod:`~.rolling_problem` solved by :mod:`~.rolling_solvers`, ``q ← q + q̇ dt`` (``docs/ep1.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin
import qpsolvers

from .geometry import unit_vector
from .hand import HandState, KinematicsError
from .rolling_problem import JointBox, StepQP, step_qp, steps_at_speed_limits, velocity_bounds
from .rolling_solvers import RollingQPError, solve_rolling_qp
from .scene import Contact, Scene
from .tactile import TactileReading, TactileSensor
from .tip_contact import SphereTipProbe

__all__ = ["RollingQP", "RollingQPError", "RollingStep"]

_LWA = pin.LOCAL_WORLD_ALIGNED


@dataclass(slots=True)
class RollingStep:
    """Outcome of one rolling step.

    Attributes:
        contact: the contact measured at the start of the step (configuration before it).
        reading: the tactile reading of that contact (None without a sensor).
        tip_rotation: the tip frame's world rotation at the start of the step (3×3).
        qdot: full joint velocity applied during the step (nv,), SI.
        slip_speed: |tangential velocity| of the fingertip material point at the contact
            implied by ``qdot`` (the no-slip residual), m/s.
        normal_residual: |nᵀ J_p q̇ − target| (contact-keeping equality residual), m/s.
        omega_residual: |J_ω q̇ − target| (angular velocity equality residual), rad/s.
        closed_form: True when no bound was active and the closed form solved the QP.
    """

    contact: Contact
    reading: TactileReading | None
    tip_rotation: np.ndarray
    qdot: np.ndarray
    slip_speed: float
    normal_residual: float
    omega_residual: float
    closed_form: bool


class RollingQP:
    """Roll ``finger``'s tip on the scene's object about a fixed world axis at rate ``omega``.

    The roller steps on ``state``'s Pinocchio data (:attr:`state` brings the state up to date).
    ``axis``: world, tangent at the contact (its normal part removed unless ``project_axis`` is
    False); ``omega``: rad/s (signed); ``dt``: s; ``solver``: the qpsolvers backend for steps
    with an active bound; ``tactile``: a sensor read at every step; ``weights``: diagonal of W
    over the active joints (wrist, then finger); ``gap_gain``: β in (0, 1]; ``second_order``,
    ``closed_form``: see :mod:`~.rolling_problem`, :mod:`~.rolling_solvers`. :meth:`retarget`
    starts another roll with the same roller.
    """

    def __init__(
        self,
        state: HandState,
        finger: str,
        axis: object,
        omega: float,
        dt: float,
        solver: str = "osqp",
        *,
        scene: Scene,
        tactile: TactileSensor | None = None,
        weights: object = None,
        gap_gain: float = 0.5,
        project_axis: bool = True,
        second_order: bool = True,
        closed_form: bool = True,
    ) -> None:
        hand = state.hand
        if scene.hand is not hand:
            raise KinematicsError("scene", "belongs to another hand model than the state")
        if not (math.isfinite(dt) and dt > 0):
            raise KinematicsError("dt", f"must be a finite number > 0 s, got {dt!r}")
        if not (0.0 < gap_gain <= 1.0):
            raise KinematicsError("gap_gain", f"must be in (0, 1], got {gap_gain!r}")
        if solver not in qpsolvers.available_solvers:
            raise KinematicsError(
                "solver",
                f"unknown or uninstalled QP solver {solver!r}; available: {qpsolvers.available_solvers}",
            )
        gid = hand.tip_geometry_id(finger)  # raises UnknownNameError
        if gid is not None and not isinstance(
            hand.collision_model.geometryObjects[gid].geometry, coal.Sphere
        ):
            raise KinematicsError("finger", f"{finger}'s tip is not a sphere; cannot roll it")
        self.hand, self.scene, self.finger, self.tactile = hand, scene, finger, tactile
        self.solver, self.dt, self.gap_gain = solver, float(dt), float(gap_gain)
        self.second_order, self.closed_form = bool(second_order), bool(closed_form)
        self.radius = hand.tip_radius(finger)
        #: the active joints' indices in q and q̇ (the same: every joint is 1-DoF)
        self.active = np.concatenate([hand.wrist_v_index, hand.finger_v_index(finger)])
        self.nx = len(self.active)
        # the active columns of the Jacobian: a slice (a view) when they are contiguous
        first = int(self.active[0])
        contiguous = self.active.tolist() == list(range(first, first + self.nx))
        self._columns: slice | np.ndarray = slice(first, first + self.nx) if contiguous else self.active
        self.box = JointBox(
            hand.lower[self.active], hand.upper[self.active], hand.velocity_limit[self.active]
        )
        if weights is None:
            self.weights = np.ones(self.nx)
        else:
            w = np.asarray(weights, dtype=float).reshape(-1)
            if w.shape != (self.nx,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
                raise KinematicsError("weights", f"must be {self.nx} finite numbers > 0")
            self.weights = w
        self._probe = SphereTipProbe(finger, self.radius, scene.object.geometry)
        self._fid = hand.tip_frame_id(finger)
        self._qdot = np.zeros(hand.nv)
        self._zero = np.zeros(hand.nv)
        self._qp: StepQP | None = None  # the QP of the last step (or of build)
        #: steps for which the velocity bounds are surely ∓q̇max (steps_at_speed_limits)
        self._steps_at_speed_limits = 0
        self._state = state
        self.retarget(axis, omega, state=state, project_axis=project_axis)

    def retarget(
        self, axis: object, omega: float, *, state: HandState | None = None, project_axis: bool = True
    ) -> None:
        """Start a new roll about ``axis`` at ``omega`` rad/s from ``state`` (default: where the last
        roll ended), at rest (no second-order term at its first step). The object's placement is
        read from the scene."""
        if not math.isfinite(omega):
            raise KinematicsError("omega", f"must be finite rad/s, got {omega!r}")
        if state is not None:
            if state.hand is not self.hand:
                raise KinematicsError("state", "belongs to another hand model")
            if state is not self._state:  # the state rolled until now: its data back at its q
                self._state.update(self._state.q)
            self._use(state)
        self._qdot[:] = 0.0
        self._steps_at_speed_limits = 0
        self._kinematics()
        self._probe.place_object(self.scene.object.placement)
        n = self._probe.measure(self._centre).normal
        a = unit_vector("axis", axis)
        if project_axis:
            a = a - (a @ n) * n
        norm = math.sqrt(float(a @ a))
        if norm < 1e-6 or abs(a @ n) > 0.5 * norm:
            raise KinematicsError("axis", "is (nearly) parallel to the contact normal: no roll")
        self.axis = a / norm
        self.omega = float(omega)
        wx, wy, wz = (self.omega * self.axis).tolist()
        self._omega_axis = (wx, wy, wz)

    def _use(self, state: HandState) -> None:
        """Roll from ``state``'s configuration on its Pinocchio data (a new one costs ~50 µs,
        a few % of an EP1 run); live views of the tip's world translation and rotation."""
        self._state, self._q, self._data = state, state.q, state.data
        tip = self._data.oMf[self._fid]
        self._centre, self._rotation = tip.translation, tip.rotation

    @property
    def q(self) -> np.ndarray:
        """Current configuration (a copy)."""
        return self._q.copy()

    @property
    def state(self) -> HandState:
        """The caller's hand state, brought up to the current configuration."""
        self._state.update(self._q)
        return self._state

    def _kinematics(self) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics at q with the last q̇; the tip's placement (seen through the live
        views), its Jacobian over the active joints and ``J̇ q̇`` (LOCAL_WORLD_ALIGNED)."""
        model, data = self.hand.model, self._data
        pin.forwardKinematics(model, data, self._q, self._qdot, self._zero)
        pin.computeJointJacobians(model, data)
        # getFrameJacobian also places the tip frame (data.oMf[fid], the live views)
        jacobian = pin.getFrameJacobian(model, data, self._fid, _LWA)[:, self._columns]
        drift = pin.getFrameClassicalAcceleration(model, data, self._fid, _LWA).vector
        return jacobian, drift

    @property
    def problem(self) -> qpsolvers.Problem | None:
        """The QP of the last step (or of :meth:`build`) as a :class:`qpsolvers.Problem` (a new one
        on each read; None before the first step)."""
        return None if self._qp is None else self._qp.problem()

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The velocity bounds at q: ``∓q̇max`` while every position limit is out of a step's
        reach (:func:`~.rolling_problem.steps_at_speed_limits`, evaluated again when that many
        steps are taken), else :func:`~.rolling_problem.velocity_bounds`."""
        box = self.box
        if self._steps_at_speed_limits > 0:
            self._steps_at_speed_limits -= 1
            return box.velocity_floor, box.velocity
        q = self._q[self.active]
        self._steps_at_speed_limits = max(steps_at_speed_limits(q, box, self.dt) - 1, 0)  # after this one
        return velocity_bounds(q, box, self.dt)

    def _build(self) -> tuple[StepQP, Contact]:
        """The kinematics at q (with the last q̇), the contact, and the QP of the step."""
        jacobian, drift = self._kinematics()
        contact = self._probe.measure(self._centre)
        qp = step_qp(
            jacobian,
            drift if self.second_order else None,
            contact,
            self.radius,
            self._omega_axis,
            self._bounds(),
            self.weights,
            self.dt,
            self.gap_gain,
        )
        self._qp = qp
        return qp, contact

    def build(self) -> qpsolvers.Problem:
        """The QP of the next step at the current q, without solving it (pink's ``build_ik``)."""
        return self._build()[0].problem()

    def step(self) -> RollingStep:
        """Measure the contact, read the sensor, solve the QP, integrate one ``dt``."""
        qp, contact = self._build()
        rotation = np.array(self._rotation)
        reading = None if self.tactile is None else self.tactile.read_tip(contact, rotation, self.radius)
        x, closed = solve_rolling_qp(qp, self.solver, self.closed_form)
        self._qdot[self._columns] = x  # the active joints (a slice when contiguous)
        self._q += self._qdot * self.dt  # the other joints' q̇ is 0
        e0, e1, e2, e3, e4, e5 = (qp.A.dot(x) - qp.b).tolist()
        return RollingStep(
            contact,
            reading,
            rotation,
            self._qdot.copy(),
            math.hypot(e0, e1),
            abs(e2),
            math.hypot(e3, e4, e5),
            closed,
        )

    def run(self, n: int) -> list[RollingStep]:
        """``n`` steps; returns their records."""
        return [self.step() for _ in range(n)]
