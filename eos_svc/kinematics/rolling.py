"""The rolling-without-sliding step of EP1: a small differential-IK QP over joint velocities.

Each :meth:`RollingQP.step` measures the contact (coal), solves

    minimise    ½ q̇ᵀ W q̇
    subject to  t₁ᵀ J_p q̇ = 0,  t₂ᵀ J_p q̇ = 0          no slip (material point at the contact)
                nᵀ J_p q̇ = −β · gap / dt               keep contact, drift correction
                J_ω q̇ = ω · a                          roll about the fixed tangent axis a, no spin
                max(−q̇_max, (q_min − q)/dt) ≤ q̇ ≤ min(q̇_max, (q_max − q)/dt)

and integrates ``q ← q + q̇ dt``. ``J_p`` is the Jacobian of the fingertip body's material
point at the contact, ``J_ω`` of its angular velocity (world axes), ``n`` the contact normal
(object → fingertip), ``t₁, t₂`` tangents. The variables are the joint velocities of the
wrist and of the rolling finger; the other fingers keep still (their q̇ is 0).

The problem is a :class:`qpsolvers.Problem` (``RollingQP.problem``, live arrays updated in
place, pink's ``build_ik`` style). With ``solver="osqp"`` (default) one ``osqp.OSQP`` object
is set up once per roll and then updated and warm-started every step at tight tolerances
(``eps_abs = eps_rel = 1e-7`` by default, not OSQP's 1e-3: no-slip residual ≲ 1e-8 m/s);
any other installed qpsolvers backend is selectable by name and solves the same Problem through
:func:`qpsolvers.solve_problem`. A failed or infeasible QP raises :class:`RollingQPError`
carrying a copy of the problem.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin
import qpsolvers

from ._slots import slot_setters
from .chain_model import chain_model
from .geometry import tangent_pair, unit_vector
from .hand import HandState, KinematicsError
from .rolling_solvers import (
    RollingQPError,
    available_solvers,
    cached_osqp,
    min_norm_within_bounds,
    solve_with_backend,
)
from .scene import Contact, Scene
from .tactile import TactileReading, TactileSensor, read_sphere_tip, sphere_tip_point
from .tip_contact import SphereTipProbe

__all__ = ["RollingQP", "RollingQPError", "RollingStep", "available_solvers"]

_LWA = pin.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True, slots=True)
class RollingStep:
    """Outcome of one rolling step.

    Attributes:
        contact: the contact measured at the start of the step (configuration before it).
        reading: the tactile reading of that contact (None without a sensor).
        qdot: full joint velocity applied during the step (nv,), SI.
        slip_speed: |tangential velocity| of the fingertip material point at the contact
            implied by ``qdot`` (the no-slip residual), m/s.
        normal_residual: |nᵀ J_p q̇ − target| (contact-keeping equality residual), m/s.
        omega_residual: |J_ω q̇ − ω a| (angular velocity equality residual), rad/s.
        iterations: solver iterations (0 when the backend does not report them).
    """

    contact: Contact
    reading: TactileReading | None
    qdot: np.ndarray
    slip_speed: float
    normal_residual: float
    omega_residual: float
    iterations: int


_new = object.__new__
_S_CONTACT, _S_READING, _S_QDOT, _S_SLIP, _S_NORMAL, _S_OMEGA, _S_ITER = slot_setters(
    RollingStep, "contact", "reading", "qdot", "slip_speed", "normal_residual", "omega_residual",
    "iterations",
)  # fmt: skip
_MIN_NORM = min_norm_within_bounds
# struct.pack_into on a memoryview of a float64 array writes the same doubles as a numpy slice
# assignment from a tuple, ~1 µs cheaper (no sequence-to-array discovery)
_PACK18 = struct.Struct("18d").pack_into
_PACK6 = struct.Struct("6d").pack_into
_FK = pin.forwardKinematics
_JJ = pin.computeJointJacobians
_GFJ = pin.getFrameJacobian
_GFCA = pin.getFrameClassicalAcceleration
_matmul = np.matmul


class RollingQP:
    """Roll ``finger``'s tip on the scene's object about a fixed world axis at rate ``omega``.

    Args:
        state: the hand state at the start of the roll; it is not modified during the roll
            (the QP drives its own Pinocchio data) and is brought up to date by :meth:`sync`.
        finger: the rolling finger (its tip must be a sphere).
        axis: world rolling axis (unit after normalisation; tangent to the object at the
            contact — its normal component is removed at construction).
        omega: rolling rate about ``axis``, rad/s (sign gives the direction).
        dt: time step, s (> 0).
        solver: ``"osqp"`` (default, set up once and warm-started) or any installed qpsolvers
            backend name (``available_solvers()``).
        scene: the hand and the object (required; keyword).
        tactile: optional sensor; each step then carries a reading of its contact.
        weights: diagonal of W over the active joints (wrist then finger), default 1.
        gap_gain: β of the drift correction, in (0, 1].
        eps: OSQP absolute and relative tolerance.
        check_termination: OSQP checks convergence every this many iterations.
        project_axis: remove the axis' component along the current contact normal (default);
            False keeps the given axis as is (EP1 keeps one axis over several legs).
        second_order: correct the targets by ½ dt J̇q̇ so that q ← q + q̇ dt meets them on
            average over the step (slip per step O(dt³) instead of O(dt²)).
        direct: first solve the equality-constrained problem in closed form (the minimum-W-norm
            solution of the six equalities, one LAPACK ``dgels``); when it lies within the
            bounds (to ``eps``, OSQP's own tolerance) it is the QP's optimum (the bounds are
            inactive) and the backend is not called (``RollingStep.iterations`` is then 0).
            Otherwise — a bound active, a rank-deficient system — the backend solves the QP.
            False: always the backend.

    A roller can be re-used for another roll of the same finger in the same scene with
    :meth:`retarget` (new axis and rate; EP1 rolls six legs with one roller), which skips the
    set-up (Pinocchio data, coal functor, arrays).
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
        eps: float = 1e-7,
        check_termination: int = 5,
        project_axis: bool = True,
        second_order: bool = True,
        direct: bool = True,
    ) -> None:
        hand = state.hand
        self.hand = hand
        self.scene = scene
        self.finger = finger
        self.tactile = tactile
        self._check_arguments(solver, dt, omega, gap_gain, eps)
        self._set_up_kinematics(finger)
        # the contact: a coal distance functor with reused transforms and result
        self._probe = SphereTipProbe(finger, self._r, scene.object.geometry)
        self._n: tuple[float, float, float] = (0.0, 0.0, 1.0)

        self.check_termination = check_termination
        #: Second-order integration: the QP targets the step's average velocities (see _build).
        self.second_order = bool(second_order)
        self._zero_nv = np.zeros(self._model.nv)
        self._J = np.zeros((6, self._model.nv))  # the tip's frame Jacobian, set by kinematics()
        #: Use the scalar re-implementation of ``TactileSensor.read`` (same readings).
        self.fast_tactile = True
        #: Closed-form solve when the bounds are inactive (see the class doc).
        self.direct = bool(direct)

        self._set_up_qp(weights)
        self._set_up_step_buffers()
        self._retarget(state, axis, omega, project_axis)

    # ------------------------------------------------------------------ set-up (once per roller)
    def _check_arguments(self, solver: str, dt: float, omega: float, gap_gain: float, eps: float) -> None:
        """Check and keep the scalar arguments (:class:`KinematicsError` names the bad one)."""
        if not (math.isfinite(dt) and dt > 0):
            raise KinematicsError("dt", f"must be a finite number > 0 s, got {dt!r}")
        if not math.isfinite(omega):
            raise KinematicsError("omega", f"must be finite rad/s, got {omega!r}")
        if not (0.0 < gap_gain <= 1.0):
            raise KinematicsError("gap_gain", f"must be in (0, 1], got {gap_gain!r}")
        if solver != "osqp" and solver not in qpsolvers.available_solvers:
            raise KinematicsError(
                "solver",
                f"unknown or uninstalled QP solver {solver!r}; available: {qpsolvers.available_solvers}",
            )
        self.solver = solver
        self.dt = float(dt)
        self.gap_gain = float(gap_gain)
        self.eps = float(eps)

    def _set_up_kinematics(self, finger: str) -> None:
        """The active joints (wrist, then the finger), the tip, the (reduced) Pinocchio model and
        data, and live views of the tip placement."""
        hand = self.hand
        model = hand.model
        self._fid = hand.tip_frame_id(finger)
        self._r = hand.tip_radius(finger)
        gid = hand.tip_geometry_id(finger)
        if gid is not None and not isinstance(
            hand.collision_model.geometryObjects[gid].geometry, coal.Sphere
        ):
            raise KinematicsError("finger", f"{finger}'s tip is not a sphere; cannot roll it")
        self._cols = np.concatenate([hand.wrist_v_index, hand.finger_v_index(finger)])
        nx = len(self._cols)
        # the active joints as a slice when they are contiguous (finger1 of hand3x3): q[slice]
        # is a view, and slice indexing is cheaper than an index array
        c0 = int(self._cols[0])
        contiguous = bool(np.array_equal(self._cols, np.arange(c0, c0 + nx)))
        self._sel: slice | np.ndarray = slice(c0, c0 + nx) if contiguous else self._cols
        self.nx = nx
        # q + v dt is exact when every joint is 1-DoF with nq == nv (hand3x3).
        if not (model.nq == model.nv and all(j.nq == 1 for j in model.joints[1:])):
            raise KinematicsError("hand", "RollingQP needs 1-DoF joints with nq == nv")
        # When the tip's kinematic chain is exactly the active joints (wrist, then the finger;
        # no inactive joint above the tip), the kinematics run on a model reduced to that chain:
        # the same joint placements in the same order, and the other fingers keep still during a
        # roll (q̇ = 0), so FK, the Jacobian and the acceleration are the same to the bit — over
        # 9 joints instead of 15 (hand3x3), and the Jacobian comes with only the active columns.
        chain = [int(model.idx_vs[j]) for j in list(model.supports[model.frames[self._fid].parentJoint])[1:]]
        self._reduced = chain == self._cols.tolist()
        if self._reduced:
            model, self._fid = chain_model(hand, finger, self._fid, chain)
        self._model = model
        self._data = model.createData()
        # live views of the tip placement in self._data (indexing data.oMf from Python
        # costs ~2 µs per access; the views follow every kinematics update)
        tip = self._data.oMf[self._fid]
        self._c_view = tip.translation
        self._R_view = tip.rotation


    def _set_up_qp(self, weights: object) -> None:
        """The QP's arrays, preallocated: W, the OSQP constraint matrix [C; I] and the bounds,
        with C, b, lb, ub as views into them, and the ``qpsolvers.Problem`` over them."""
        hand, nx = self.hand, self.nx
        w = np.ones(nx) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
        if w.shape != (nx,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise KinematicsError("weights", f"must be {nx} finite numbers > 0")
        self._P = np.diag(w)
        # direct solve: x = W^-1/2 z with z the minimum-norm solution of (C W^-1/2) z = b
        self._wscale = None if np.all(w == 1.0) else 1.0 / np.sqrt(w)
        self._Cw = np.zeros((6, nx))
        self._qlin = np.zeros(nx)
        # OSQP constraint matrix [C; I] (CSC, column-major): column j = C[:, j] then 1.
        # C, b, lb, ub are views into the OSQP arrays, so one update feeds both the
        # qpsolvers Problem and OSQP.
        self._Ax = np.zeros(7 * nx)
        self._Ax2 = self._Ax.reshape(nx, 7)
        self._Ax2[:, 6] = 1.0
        self._C = self._Ax2[:, :6].T
        self._l = np.zeros(6 + nx)
        self._u = np.zeros(6 + nx)
        self._b = self._l[:6]
        self._lb = self._l[6:]
        self._ub = self._u[6:]
        # dgels' right-hand side must have max(6, nx) rows: b followed by (ignored) lb entries
        self._b_ext = self._l[: max(6, nx)]
        self._b_buf = self._b.data  # for struct.pack_into (see _build)
        self._lo = hand.lower[self._cols]  # q index == v index for hand3x3-like hands
        self._hi = hand.upper[self._cols]
        self._vmax = hand.velocity_limit[self._cols]
        self._Jb = np.zeros((6, nx))
        self._M = np.zeros((6, 6))  # C = M J: rows t1, t2, n (linear) and the r_f terms
        self._M[3:, 3:] = np.eye(3)
        self._M3 = self._M[:3].reshape(-1)  # view of the three changing rows
        self._M3_buf = self._M3.data  # for struct.pack_into (see _build)
        self._lo_dt = self._lo / self.dt
        self._hi_dt = self._hi / self.dt
        self._lo_dt_l: list[float] = self._lo_dt.tolist()
        self._hi_dt_l: list[float] = self._hi_dt.tolist()
        self._vmax_l: list[float] = self._vmax.tolist()
        self._pack_nx = struct.Struct(f"{nx}d").pack_into
        self._lb_buf = self._lb.data  # for struct.pack_into (_bounds)
        self._ub_buf = self._ub.data
        self._free_steps = 0  # bound evaluations that may be skipped (see _bounds)
        self._lb_tol: list[float] = []
        self._ub_tol: list[float] = []
        #: The QP of the current step as a qpsolvers Problem (live arrays, see module doc).
        self.problem = qpsolvers.Problem(
            self._P, self._qlin, None, None, self._C, self._b, self._lb, self._ub
        )
        self._osqp: Any = None
        self._osqp_solver: Any = None

    def _set_up_step_buffers(self) -> None:
        """The step's scratch arrays and the q̇ views the kinematics and the integration use."""
        nx = self.nx
        self._stale: bool = False  # the caller's state is behind the roller's q (see sync)
        self._tmp = np.zeros(nx)
        self._res6 = np.zeros(6)
        self._qdot = np.zeros(self.hand.model.nv)
        # what the kinematics take (see _retarget): the reduced model's q̇ (a view of the active
        # joints' q̇, or its own copy when they are not contiguous), or the full q̇
        self._qdot_r: np.ndarray | None = None
        if not self._reduced:
            self._qdk = self._qdot
        elif type(self._sel) is slice:
            self._qdk = self._qdot[self._sel]
        else:
            self._qdk = self._qdot_r = np.zeros(nx)
        self._qk = self._qdot  # set by _retarget
        # the Jacobian's active columns: all of them with the reduced model
        self._jsel: slice | np.ndarray | None = None if self._reduced else self._sel
        # the active joints' q̇ (slice case): a buffer for struct.pack_into (see step, the integration)
        self._qdot_a_buf: Any = self._qdot[self._sel].data if type(self._sel) is slice else None

    def retarget(
        self,
        axis: object,
        omega: float,
        *,
        state: HandState | None = None,
        project_axis: bool = True,
    ) -> None:
        """Start a new roll with this roller: axis ``axis``, rate ``omega``, from ``state``
        (default: where the last roll ended). Same as a new ``RollingQP`` with the same
        finger, scene, dt, solver and options (and the same results), without its set-up.
        The object's placement is re-read from the scene."""
        if not math.isfinite(omega):
            raise KinematicsError("omega", f"must be finite rad/s, got {omega!r}")
        if state is None:
            # the caller's state is brought up to the roller's q here, at every leg (a roll that
            # fails later leaves it at the start of its leg, as it always did)
            self.sync()
            state = self._state
        elif state.hand is not self.hand:
            raise KinematicsError("state", "belongs to another hand model")
        self._retarget(state, axis, omega, project_axis)

    def use_scene(self, scene: Scene) -> None:
        """Roll on ``scene``'s object from the next :meth:`retarget` on (same hand): a roller
        re-used across scenes (EP1 keeps one per hand and finger, every plan has its own scene).
        The contact probe is rebuilt when the object's shape differs; the object's placement is
        read by :meth:`retarget`. Nothing else of a roll depends on the scene, so a moved roller
        re-targeted rolls as a new one on ``scene`` (tested)."""
        if scene.hand is not self.hand:
            raise KinematicsError("scene", "belongs to another hand model than the roller's")
        self.scene = scene
        if self._probe.object_shape is not scene.object.geometry:
            self._probe = SphereTipProbe(self.finger, self._r, scene.object.geometry)

    def _retarget(self, state: HandState, axis: object, omega: float, project_axis: bool) -> None:
        """Start a roll from ``state``."""
        self.omega = float(omega)
        self._state = state
        self._q = state.q
        # active joints' q, kept in step with _q (a view of it when the joints are contiguous)
        self._qa = self._q[self._sel] if type(self._sel) is slice else self._q[self._cols].copy()
        self._qk = self._qa if self._reduced else self._q  # the q the kinematics take
        self._stale = False
        self._qdot[:] = 0.0
        if self._qdot_r is not None:
            self._qdot_r[:] = 0.0
        self._free_steps = 0
        self.steps = 0
        self._osqp = None  # re-upload the whole problem on the first solve
        M = self.scene.object.placement
        self._probe.place_object(M)
        # Axis: tangent at the current contact (its normal; contact()'s record is not needed).
        self.kinematics_only()
        n0, n1, n2 = self._n = self._probe.measure_raw(self._c_view)[5]
        # unit_vector, then the projection, in scalars (numpy on 3-vectors costs µs per call)
        a0, a1, a2 = unit_vector("axis", axis).tolist()
        if project_axis:
            d = a0 * n0 + a1 * n1 + a2 * n2
            a0, a1, a2 = a0 - d * n0, a1 - d * n1, a2 - d * n2
        na = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if na < 1e-6 or abs(a0 * n0 + a1 * n1 + a2 * n2) > 0.5 * na:
            raise KinematicsError("axis", "is (nearly) parallel to the contact normal: no roll")
        self.axis = np.array((a0 / na, a1 / na, a2 / na))
        self._wa = self.omega * self.axis
        self._b[:3] = 0.0  # the no-slip targets of a first step (no second-order term yet)
        self._b[3:] = self._wa
        self._wa_t = tuple(self._wa.tolist())

    # ------------------------------------------------------------------ state
    @property
    def q(self) -> np.ndarray:
        """Current configuration (a copy)."""
        return self._q.copy()

    @property
    def state(self) -> HandState:
        """The hand state, synchronised to the current configuration."""
        self.sync()
        return self._state

    def sync(self) -> None:
        """Bring the caller's :class:`HandState` up to the current q."""
        if self._stale:
            self._state.update(self._q)
            self._stale = False

    # ------------------------------------------------------------------ contact
    def contact(self) -> Contact:
        """Contact of the rolling tip at the current q (coal), kinematics already computed.

        Also leaves the normal as floats in ``self._n`` (for :meth:`_read` and :meth:`_build`)."""
        contact, self._n = self._probe.measure(self._c_view)
        return contact

    @property
    def tip_rotation(self) -> np.ndarray:
        """The rolling tip frame's world rotation at the last kinematics (a live 3×3 view:
        it follows every step; copy it to keep it)."""
        return self._R_view

    @property
    def object_geometry(self) -> Any:
        """The coal shape of the object this roller measures contacts with."""
        return self._probe.object_shape

    # ------------------------------------------------------------------ the step
    def _build(self, contact: Contact, n: tuple[float, ...] | None = None) -> tuple[float, ...]:
        """Fill C, b, lb, ub (views into the OSQP arrays) for the current q and contact
        (``n``: the contact normal as floats, when the caller has them); returns b as floats."""
        return self._fill(contact.distance, tuple(contact.normal.tolist()) if n is None else n)

    def _fill(self, distance: float, n: tuple[float, ...]) -> tuple[float, ...]:
        """:meth:`_build` from the contact's signed distance (m) and normal (three floats)."""
        J = self._J  # from kinematics()
        jsel = self._jsel
        if jsel is None:
            Jb = J
        elif type(jsel) is slice:
            Jb = J[:, jsel]
        else:
            Jb = self._Jb
            J.take(jsel, axis=1, out=Jb)
        nx_, ny_, nz_ = n
        t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(nx_, ny_, nz_)  # t1 ⟂ n, t2 = n × t1
        # row(d) = dᵀ Jv − (d × r)ᵀ Jω, r = p_tip − c = −r_f n ⇒ −(d × r) = r_f (d × n);
        # t1 × n = −t2, t2 × n = t1. One slice assignment (item writes cost ~0.3 µs each).
        r = self._r
        _PACK18(  # = self._M3[:] = (...), without numpy's sequence conversion
            self._M3_buf, 0,
            t1x, t1y, t1z, -r * t2x, -r * t2y, -r * t2z,
            t2x, t2y, t2z, r * t1x, r * t1y, r * t1z,
            nx_, ny_, nz_, 0.0, 0.0, 0.0,
        )  # fmt: skip
        _matmul(self._M, Jb, out=self._C)
        dt = self.dt
        bn = -self.gap_gain * distance / dt
        if self.second_order and self.steps > 0:
            # q̇ is constant over a step, so the tip moves with the acceleration J̇q̇ of the
            # last q̇: ask for the step's *average* velocities, v + ½ dt a, to meet the
            # targets (no slip, contact, ω a) — second-order accurate integration.
            ax, ay, az, wx, wy, wz = _GFCA(self._model, self._data, self._fid, _LWA).vector.tolist()
            # material point at r = −r_f n: a_p = a_c + α × r + ω × (ω × r); the last term is
            # normal when ω ⟂ n, and α × r = −r_f α × n
            px = ax - r * (wy * nz_ - wz * ny_)
            py = ay - r * (wz * nx_ - wx * nz_)
            pz = az - r * (wx * ny_ - wy * nx_)
            h = 0.5 * dt
            wa0, wa1, wa2 = self._wa_t
            bt = (
                -h * (t1x * px + t1y * py + t1z * pz),
                -h * (t2x * px + t2y * py + t2z * pz),
                bn - h * (nx_ * ax + ny_ * ay + nz_ * az),
                wa0 - h * wx,
                wa1 - h * wy,
                wa2 - h * wz,
            )
            _PACK6(self._b_buf, 0, *bt)  # = self._b[:] = bt
        else:
            b = self._b
            b[2] = bn
            bt = tuple(b.tolist())
        if self._free_steps > 0:  # see _bounds
            self._free_steps -= 1
        else:
            self._bounds()
        return bt

    def _bounds(self) -> None:
        """lb, ub: max(−q̇max, (q_min − q)/dt) ≤ q̇ ≤ min(q̇max, (q_max − q)/dt).

        Far from the position limits they are exactly ∓q̇max, and q moves by at most
        q̇max·dt per step: after an exact evaluation that finds every position limit at least
        k steps away, the next k − 1 evaluations are skipped by ``_build`` (the arrays already
        hold ∓q̇max): this evaluates them, and sets that count.
        """
        # in floats, the operations numpy's multiply, subtract, maximum and minimum did (same
        # values, NaN propagated alike); the arrays written once each
        inv = 1.0 / self.dt
        tol = self.eps
        lb: list[float] = []
        ub: list[float] = []
        # steps until a position limit could bind: (q_min − q)/dt < −q̇max and
        # (q_max − q)/dt > q̇max hold while each changes by at most q̇max (+ solver tolerance)
        # per step
        k = math.inf
        for q, lo, hi, v in zip(self._qa.tolist(), self._lo_dt_l, self._hi_dt_l, self._vmax_l, strict=True):
            qs = q * inv
            tl = lo - qs  # (q_min − q)/dt
            th = hi - qs  # (q_max − q)/dt
            nv = -v
            lb.append(nv if nv >= tl else tl)  # np.maximum(−q̇max, tl)
            ub.append(v if v <= th else th)  # np.minimum(q̇max, th)
            shift = v * (1.0 + 1e-6) + 1e-6
            k = min(k, (-v - tl) / shift, (th - v) / shift)
        pack = self._pack_nx
        pack(self._lb_buf, 0, *lb)
        pack(self._ub_buf, 0, *ub)
        self._lb_tol = [x - tol for x in lb]
        self._ub_tol = [x + tol for x in ub]
        self._free_steps = int(k) - 1 if k >= 2.0 else 0

    def _solve_direct(self) -> np.ndarray | None:
        """The minimum-W-norm solution of C q̇ = b when it satisfies the bounds (it is then
        the QP's optimum), else None."""
        sol = self._direct()
        return None if sol is None else sol[0]

    def _direct(self) -> tuple[np.ndarray, list[float]] | None:
        """:meth:`_solve_direct`'s solution and the same as floats, or None
        (:func:`~eos_svc.kinematics.rolling_solvers.min_norm_within_bounds`)."""
        return _MIN_NORM(self._C, self._b_ext, self._wscale, self._Cw, self._lb_tol, self._ub_tol)

    def _solve_osqp(self) -> tuple[np.ndarray, int]:
        self._u[:6] = self._b
        if self._osqp is None:
            self._osqp, self._osqp_solver = cached_osqp(
                self.nx, self.eps, self.check_termination, self._P, self._qlin, self._Ax, self._l, self._u
            )
            slv = self._osqp_solver
            slv.update_data_vec(q=self._qlin, l=self._l, u=self._u)
            slv.update_data_mat(P_x=np.ascontiguousarray(np.diag(self._P)), P_i=None, A_x=self._Ax, A_i=None)
            # a new roll: start cold, not from another problem's primal/dual solution
            slv.warm_start(x=np.zeros(self.nx), y=np.zeros(6 + self.nx))
        else:
            slv = self._osqp_solver
            slv.update_data_vec(q=None, l=self._l, u=self._u)
            slv.update_data_mat(P_x=None, P_i=None, A_x=self._Ax, A_i=None)
        slv = self._osqp_solver
        slv.solve()
        info = slv.info
        if info.status_val != 1:  # OSQP_SOLVED
            raise RollingQPError(
                "OSQP did not solve the rolling QP", self.problem_copy(), "osqp", str(info.status)
            )
        return slv.solution.x, int(info.iter)

    def _solve_generic(self) -> tuple[np.ndarray, int]:
        return solve_with_backend(self.problem, self.solver)

    def build(self) -> qpsolvers.Problem:
        """The QP of the next step at the current q, without solving it (pink's ``build_ik``):
        kinematics, contact, constraint rows and bounds; returns an independent copy."""
        self._free_steps = 0
        self.kinematics()
        self._build(self.contact())
        return self.problem_copy()

    def problem_copy(self) -> qpsolvers.Problem:
        """An independent copy of the current QP (for errors and inspection)."""
        return qpsolvers.Problem(
            self._P.copy(),
            self._qlin.copy(),
            None,
            None,
            self._C.copy(),
            self._b.copy(),
            self._lb.copy(),
            self._ub.copy(),
        )

    def kinematics_only(self) -> None:
        """Tip placement at the current q (no Jacobians)."""
        pin.framesForwardKinematics(self._model, self._data, self._qk)

    def kinematics(self) -> None:
        """Forward kinematics (with the last q̇, for the second-order terms), joint Jacobians
        and the tip placement at the current q."""
        model, data = self._model, self._data
        if self.second_order:
            _FK(model, data, self._qk, self._qdk, self._zero_nv)
            _JJ(model, data)
        else:
            _JJ(model, data, self._qk)
        # getFrameJacobian also places the tip frame (data.oMf[fid], seen through _c_view and
        # _R_view): no updateFramePlacement
        self._J = _GFJ(model, data, self._fid, _LWA)

    def read_tactile(self, contact: Contact) -> TactileReading | None:
        """The sensor's reading of ``contact`` (None without a sensor).

        For a plain :class:`TactileSensor` this is the same reading (same noise model, same
        random draws, tested equal to ``TactileSensor.read``) written with scalar arithmetic:
        ``TactileSensor.read`` spends ~100 µs in ``np.cross`` and friends on 3-vectors.
        The kinematics must be those of ``contact`` (as after :meth:`contact`).
        """
        if self.tactile is None:
            return None
        return self._read(contact, tuple(contact.normal.tolist()))

    def _read(self, contact: Contact, n: tuple[float, ...]) -> TactileReading:
        sensor = self.tactile
        assert sensor is not None
        if type(sensor) is not TactileSensor or not self.fast_tactile:
            self.sync()
            return sensor.read(self._state, contact)
        return read_sphere_tip(sensor, contact, self._R_view, n, self._r)

    def _bounds_infeasible(self) -> bool:
        return bool((self._lb > self._ub).any())

    def step(self) -> RollingStep:
        """Measure the contact, read the sensor, solve the QP, integrate one ``dt``:
        :meth:`kinematics`, :meth:`contact`, the tactile reading, ``_build`` (rows, targets,
        bounds), the closed-form solve (``_direct``) or the backend, and the integration."""
        self.kinematics()
        # contact(), _read() and _direct() written out: one Python call each instead of two
        contact, n = self._probe.measure(self._c_view)
        self._n = n
        sensor = self.tactile
        if sensor is None:
            reading = None
        elif type(sensor) is TactileSensor and self.fast_tactile:
            reading = read_sphere_tip(sensor, contact, self._R_view, n, self._r)
        else:
            reading = self._read(contact, n)
        b0, b1, b2, b3, b4, b5 = self._fill(contact.distance, n)  # = _build(contact, n)
        x, it = self._solve_and_integrate()
        # ---- residuals of the equalities at the returned solution (C x in numpy, − b in
        # floats, as np.subtract would)
        res6 = self._res6
        _matmul(self._C, x, out=res6)
        r0, r1, r2, r3, r4, r5 = res6.tolist()
        r0, r1, r2, r3, r4, r5 = r0 - b0, r1 - b1, r2 - b2, r3 - b3, r4 - b4, r5 - b5
        rs: RollingStep = _new(RollingStep)  # the frozen dataclass's __init__ costs ~2 µs: fill the slots
        _S_CONTACT(rs, contact)
        _S_READING(rs, reading)
        _S_QDOT(rs, self._qdot.copy())
        _S_SLIP(rs, math.sqrt(r0 * r0 + r1 * r1))
        _S_NORMAL(rs, abs(r2))
        _S_OMEGA(rs, math.sqrt(r3 * r3 + r4 * r4 + r5 * r5))
        _S_ITER(rs, it)
        return rs

    def advance(self) -> tuple[float, bool, float, float, float, float]:
        """One :meth:`step` (the same q̇, the same integration, the same reading and random
        draws) returning only what EP1 keeps of it, as floats: ``(signed gap at the start of the
        step m, in contact, the tactile point in the tip frame (three floats, m), no-slip
        residual m/s)`` — without the step's records (its :class:`RollingStep`,
        :class:`~.scene.Contact` and :class:`~.tactile.TactileReading` and their arrays). Needs
        a sensor; with one other than a plain :class:`TactileSensor` (or ``fast_tactile``
        off) it is :meth:`step` unpacked."""
        sensor = self.tactile
        if type(sensor) is not TactileSensor or not self.fast_tactile:
            if sensor is None:
                raise KinematicsError("tactile", "advance() needs a tactile sensor")
            st = self.step()
            rd = st.reading
            assert rd is not None
            px, py, pz = rd.point_tip.tolist()
            return float(st.contact.distance), bool(rd.in_contact), px, py, pz, st.slip_speed
        self.kinematics()
        d, _, _, _, _, n = self._probe.measure_raw(self._c_view)
        self._n = n
        if type(d) is not float:
            d = float(d)
        in_contact, px, py, pz = sphere_tip_point(sensor, d, self._R_view, n, self._r)
        b0, b1, _, _, _, _ = self._fill(d, n)
        x, _ = self._solve_and_integrate()
        res6 = self._res6
        _matmul(self._C, x, out=res6)
        r0, r1, _, _, _, _ = res6.tolist()
        r0, r1 = r0 - b0, r1 - b1
        return d, in_contact, px, py, pz, math.sqrt(r0 * r0 + r1 * r1)

    def _solve_and_integrate(self) -> tuple[np.ndarray, int]:
        """Solve the QP that ``_fill`` left (closed form when the bounds are inactive, else the
        backend) and integrate ``q ← q + q̇ dt``; returns (q̇ of the active joints, iterations)."""
        sol = (
            _MIN_NORM(self._C, self._b_ext, self._wscale, self._Cw, self._lb_tol, self._ub_tol)
            if self.direct
            else None
        )
        it = 0
        if sol is None:
            if self._bounds_infeasible():
                raise RollingQPError(
                    "joint limits leave no feasible velocity",
                    self.problem_copy(),
                    self.solver,
                    "infeasible bounds",
                )
            x, it = self._solve_osqp() if self.solver == "osqp" else self._solve_generic()
            xs = x.tolist()
        else:
            x, xs = sol
        # ---- integration q ← q + q̇ dt
        sel = self._sel
        if type(sel) is slice:
            # qdot[sel] = x from the floats, into the buffer (no numpy indexing)
            self._pack_nx(self._qdot_a_buf, 0, *xs)
        else:
            self._qdot[sel] = x
            if self._qdot_r is not None:
                self._qdot_r[:] = x
        tmp = self._tmp
        np.multiply(x, self.dt, out=tmp)
        qa = self._qa
        qa += tmp
        if type(sel) is not slice:
            self._q[sel] = qa
        self._stale = True
        self.steps += 1
        return x, it

    def run(self, n: int) -> list[RollingStep]:
        """``n`` steps; returns their records."""
        return [self.step() for _ in range(n)]
