"""A finger's guarded closing step: close by a joint increment, stop at first touch (regula falsi
on the closing gap), and tell a fingertip's touch from a link's."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from eos_svc.world.world import GraspWorld


def close_finger_step(world: GraspWorld, finger: str, dtheta: float) -> tuple[str, float]:
    """Close ``finger`` by ``dtheta`` rad per joint, stopping at first touch; (event, new angle):
    ``"moved"``, ``"touched"`` (the step cut at the contact by regula falsi), ``"link"`` (another
    part of the finger, or the table, touched first) or ``"limit"`` (no touch to the limit)."""
    tol = world.params.contact_tolerance
    idx = world.context.finger_q[finger]
    q0 = world.state.q
    f0 = world.memo.get(("closing", finger))  # the closing gap at q0, when known
    q1, at_limit = world.state.close_finger(finger, dtheta)
    world.set_q(q1)
    if world.table_gap() < 0.5 * tol:  # the finger would touch the table: stay, as at a link's touch
        world.set_q(q0)
        return "link", world.finger_angle(finger)
    f1 = closing_gap(world, finger)
    if f1 > 0.0:  # nothing touches at the end of the step
        return ("limit" if at_limit else "moved"), world.finger_angle(finger)
    if f0 is None:  # the closing gap at the start of the step (the bracket's other end)
        world.set_q(q0)
        f0 = closing_gap(world, finger)
    # First touch inside the step: regula falsi (Illinois) on the step fraction for the
    # closing gap, converging to a tip within [tol/2, tol] of the object (or a link just
    # touching), a handful of distance queries instead of a long bisection.
    a, fa, b, fb = 0.0, f0, 1.0, f1
    side = 0
    s_ok = 0.0
    for _ in range(40):
        frac = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        q = q0.copy()
        q[idx] = q0[idx] + frac * (q1[idx] - q0[idx])
        world.set_q(q)
        fs = closing_gap(world, finger)
        if fs >= 0.0:
            s_ok = frac
            if fs <= 0.5 * tol:
                break
            a, fa = frac, fs
            if side == 1:
                fb *= 0.5
            side = 1
        else:
            b, fb = frac, fs
            if side == -1:
                fa *= 0.5
            side = -1
        if b - a < 1e-9:
            break
    q = q0.copy()
    q[idx] = q0[idx] + s_ok * (q1[idx] - q0[idx])
    world.set_q(q)
    event = "touched" if world.tip_distance(finger) <= tol else "link"
    return event, world.finger_angle(finger)


def closing_gap(world: GraspWorld, finger: str) -> float:
    """How far ``finger`` may still close before something touches (m): the tip's
    distance beyond half the contact tolerance, or a link's distance, whichever is less
    (memoised per hand pose)."""
    memo = world.memo
    key = ("closing", finger)
    value = memo.get(key)
    if value is None:
        tip = world.tip_distance(finger) - 0.5 * world.params.contact_tolerance
        value = memo[key] = world.min_gap(world.context.links[finger], tip)
    return value
