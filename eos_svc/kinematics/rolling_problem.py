"""The formulation of one rolling-without-sliding step: a QP over joint velocities.

For a sphere fingertip (radius r_f) touching the object with unit normal ``n`` (object →
fingertip) and signed gap ``d``, the step asks of the joint velocities ``q̇`` of the active joints
(the wrist, then the rolling finger)::

    minimise    ½ q̇ᵀ W q̇
    subject to  t₁ᵀ J_p q̇ = 0,  t₂ᵀ J_p q̇ = 0          no slip of the material point at the contact
                nᵀ J_p q̇ = −β d / dt                   keep contact, the gap corrected by β per step
                J_ω q̇ = ω a                            roll about the fixed tangent axis a, no spin
                max(−q̇_max, (q_min − q)/dt) ≤ q̇ ≤ min(q̇_max, (q_max − q)/dt)

``J = [J_v; J_ω]`` is the tip frame's Jacobian (LOCAL_WORLD_ALIGNED), ``J_p = J_v − [p]ₓ J_ω`` the
Jacobian of the material point at ``p = −r_f n`` from the tip centre, ``(t₁, t₂, n)`` the tangent
frame of :func:`~eos_svc.kinematics.geometry.tangent_pair`. The equality rows are ``M J`` with

    M = [[t₁ᵀ, −r_f t₂ᵀ], [t₂ᵀ, r_f t₁ᵀ], [nᵀ, 0], [0, I₃]]

(the rows ``[dᵀ, (p × d)ᵀ]`` for d = t₁, t₂, n: ``p × t₁ = −r_f t₂``, ``p × t₂ = r_f t₁``).
Second order: ``q̇`` is held for ``dt``, so the targets are asked
of the step's average velocity ``M (J q̇ + ½ dt J̇ q̇_prev)``, i.e. ``b − ½ dt M J̇ q̇_prev``; the
slip per step is then O(dt³) instead of O(dt²).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import qpsolvers

from .geometry import tangent_pair
from .scene import Contact

__all__ = ["JointBox", "contact_rows", "rolling_problem"]


@dataclass(frozen=True)
class JointBox:
    """Position and velocity limits of the active joints (rad or m, rad/s or m/s)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray


def contact_rows(normal: np.ndarray, radius: float) -> np.ndarray:
    """The 6×6 ``M`` of the module docstring: ``M [v; ω]`` is (t₁·v_p, t₂·v_p, n·v_p, ω) for the tip
    twist ``[v; ω]`` (centre velocity, angular velocity, world axes) and the material point at the
    contact, ``radius`` m from the centre along −``normal``."""
    nx, ny, nz = normal.tolist()
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(nx, ny, nz)
    r = radius
    return np.array(
        (
            (t1x, t1y, t1z, -r * t2x, -r * t2y, -r * t2z),
            (t2x, t2y, t2z, r * t1x, r * t1y, r * t1z),
            (nx, ny, nz, 0.0, 0.0, 0.0),
            (0.0, 0.0, 0.0, 1.0, 0.0, 0.0),
            (0.0, 0.0, 0.0, 0.0, 1.0, 0.0),
            (0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        )
    )


def rolling_problem(
    jacobian: np.ndarray,
    drift: np.ndarray | None,
    contact: Contact,
    radius: float,
    omega_axis: tuple[float, float, float],
    q: np.ndarray,
    box: JointBox,
    cost: np.ndarray,
    dt: float,
    gap_gain: float,
) -> qpsolvers.Problem:
    """The QP of one step (module docstring) as a :class:`qpsolvers.Problem` over the active joints.

    Args:
        jacobian: the tip frame's 6×nx Jacobian over the active joints (LOCAL_WORLD_ALIGNED).
        drift: ``J̇ q̇_prev`` (the tip's classical acceleration at the last q̇ with q̈ = 0, 6,
            LOCAL_WORLD_ALIGNED), or None for first-order targets.
        contact: the measured contact (its normal, object → tip, and signed gap, m).
        radius: the tip sphere's radius, m. omega_axis: ω a, the commanded angular velocity, rad/s.
        q: the active joints' positions; box: their limits; cost: W (nx×nx, diagonal).
        dt: the step, s; gap_gain: β in (0, 1].
    """
    M = contact_rows(contact.normal, radius)
    wx, wy, wz = omega_axis
    target = np.array((0.0, 0.0, -gap_gain * contact.distance / dt, wx, wy, wz))
    if drift is not None:
        target -= (0.5 * dt) * (M @ drift)
    # the velocity limits, tightened so that q + q̇ dt stays within the position limits
    lb = np.maximum(-box.velocity, (box.lower - q) / dt)
    ub = np.minimum(box.velocity, (box.upper - q) / dt)
    return qpsolvers.Problem(cost, np.zeros(len(q)), A=M @ jacobian, b=target, lb=lb, ub=ub)
