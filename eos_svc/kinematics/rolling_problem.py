"""The formulation of one rolling-without-sliding step: a QP over joint velocities q̇ of the active
joints (the wrist, then the rolling finger), as ``docs/ep1.md`` derives it::

    minimise ½ q̇ᵀ W q̇  subject to  M (J q̇ + ½ dt J̇ q̇_prev) = (0, 0, −β d/dt, ω a),  lb ≤ q̇ ≤ ub

``J`` is the tip frame's Jacobian (LOCAL_WORLD_ALIGNED), ``M`` (:func:`contact_rows`) picks the
no-slip rows (t₁, t₂) and the contact-keeping row (n) of the material point at the contact and
the angular velocity (ω a: roll about the tangent axis a, no spin).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import qpsolvers

from .geometry import tangent_pair
from .scene import Contact

__all__ = [
    "JointBox",
    "StepQP",
    "contact_rows",
    "step_qp",
    "steps_at_speed_limits",
    "velocity_bounds",
]

#: the most a solver's q̇ may exceed a velocity bound, as a fraction of the limit (plus 1e-6):
#: what :func:`steps_at_speed_limits` allows for each step
SPEED_MARGIN = 0.01


@dataclass(frozen=True)
class JointBox:
    """Position and velocity limits of the active joints (rad or m, rad/s or m/s)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray

    @cached_property
    def position_limits(self) -> np.ndarray:
        """``[lower; upper]`` (2×n), derived once per box."""
        return np.stack((self.lower, self.upper))

    @cached_property
    def velocity_floor(self) -> np.ndarray:
        """``−velocity``, derived once per box."""
        return -self.velocity


@dataclass(slots=True)
class StepQP:
    """The QP of one step as plain arrays: minimise ``½ xᵀ diag(weights) x`` subject to
    ``A x = b`` and ``lb ≤ x ≤ ub`` (x: the active joints' velocities, SI)."""

    weights: np.ndarray
    A: np.ndarray
    b: np.ndarray
    lb: np.ndarray
    ub: np.ndarray

    def problem(self) -> qpsolvers.Problem:
        """The same QP as a :class:`qpsolvers.Problem` (for a qpsolvers backend)."""
        return qpsolvers.Problem(
            np.diag(self.weights), np.zeros(len(self.weights)), A=self.A, b=self.b, lb=self.lb, ub=self.ub
        )


def contact_rows(normal: np.ndarray, radius: float) -> np.ndarray:
    """The 6×6 ``M`` of the module docstring: ``M [v; ω]`` is (t₁·v_p, t₂·v_p, n·v_p, ω) for the tip
    twist ``[v; ω]`` (centre velocity, angular velocity, world axes) and the material point at the
    contact, ``radius`` m from the centre along −``normal``."""
    nx, ny, nz = normal.tolist()
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(nx, ny, nz)
    r = radius
    return np.array(
        (
            t1x, t1y, t1z, -r * t2x, -r * t2y, -r * t2z,
            t2x, t2y, t2z, r * t1x, r * t1y, r * t1z,
            nx, ny, nz, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        )
    ).reshape(6, 6)  # fmt: skip


def velocity_bounds(q: np.ndarray, box: JointBox, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(lb, ub)``: the velocity limits, tightened so that ``q + q̇ dt`` stays within the position
    limits."""
    reach = (box.position_limits - q) / dt  # the velocities that reach each position limit in dt
    return np.maximum(box.velocity_floor, reach[0]), np.minimum(box.velocity, reach[1])


def steps_at_speed_limits(q: np.ndarray, box: JointBox, dt: float) -> int:
    """How many steps from ``q``, this one included, :func:`velocity_bounds` surely stays the
    velocity limits ``∓q̇max`` (no position limit within a step's reach): 0 when a position limit
    binds now. Each step moves a joint by at most ``q̇ dt`` with ``|q̇| ≤ q̇max`` (plus
    :data:`SPEED_MARGIN` for a solver's tolerance), so its slack ``(q − q_min)/dt − q̇max`` (and
    ``(q_max − q)/dt − q̇max``) falls by at most that much per step."""
    slack = np.minimum((q - box.lower) / dt, (box.upper - q) / dt) - box.velocity
    per_step = box.velocity * (1.0 + SPEED_MARGIN) + 1e-6
    steps = float((slack / per_step).min())
    return int(steps) + 1 if steps >= 0.0 else 0


def step_qp(
    jacobian: np.ndarray,
    drift: np.ndarray | None,
    contact: Contact,
    radius: float,
    omega_axis: tuple[float, float, float],
    bounds: tuple[np.ndarray, np.ndarray],
    weights: np.ndarray,
    dt: float,
    gap_gain: float,
) -> StepQP:
    """The QP of one step (module docstring) from the tip frame's 6×nx Jacobian over the active
    joints, ``drift`` = ``J̇ q̇_prev`` (None: first-order targets), the measured contact, the tip
    radius (m), ``omega_axis`` = ω a (rad/s), the velocity ``bounds``, W's diagonal, ``dt`` (s)
    and β."""
    M = contact_rows(contact.normal, radius)
    wx, wy, wz = omega_axis
    gap_target = -gap_gain * contact.distance / dt
    if drift is None:
        b = np.array((0.0, 0.0, gap_target, wx, wy, wz))
    else:  # b − ½ dt M J̇ q̇_prev, on floats (the same roundings as on arrays)
        h = 0.5 * dt
        m0, m1, m2, m3, m4, m5 = M.dot(drift).tolist()
        b = np.array((0.0 - h * m0, 0.0 - h * m1, gap_target - h * m2, wx - h * m3, wy - h * m4, wz - h * m5))
    lb, ub = bounds
    return StepQP(weights, M.dot(jacobian), b, lb, ub)
