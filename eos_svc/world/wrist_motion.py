"""The wrist's guarded motions: the search's sweeps over the coverage lattice, a straight guarded
move, and the grasp stage's step toward a target that stops short of touching (world, m)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from eos_svc.world.coverage import column_counts, space_filling_order, wrist_columns
from eos_svc.world.table import clamp_above

if TYPE_CHECKING:
    from eos_svc.world.world import GraspWorld


def search_step(
    world: GraspWorld, execute: Callable[[np.ndarray, np.ndarray], bool] | None = None
) -> tuple[str, float, bool]:
    """One search move: a sweep of the next column of the coverage plan
    (:mod:`eos_svc.world.coverage`), each leg a :func:`guarded_wrist_move` that stops where the
    object enters the envelope or short of a contact; (column label "(j, k)", m moved, blocked).
    ``execute(q_from, q_to)``: a driver's execution of each planned leg (a simulated hand's,
    leg by leg, so that no leg cuts a corner through the object); True when it stopped on a
    contact, which blocks the sweep as the model's contact does."""
    p = world.params
    if not world.search_order:  # the first move, or every column swept: (again) in a new order
        world.search_order = space_filling_order(column_counts(p), world.rng, world.context.lattice)
        world.search_columns = wrist_columns(p)
    j, k = world.search_order.pop(0)
    y, z = (float(v) for v in world.search_columns[j, k])
    if world.table is not None:  # a column under the table's reach is swept as low as it allows
        z = max(z, world.wrist_xyz()[2] - (world.table_gap() - p.clearance) + 1e-6)
    x_lo, x_hi = p.search_box_lo[0], p.search_box_hi[0]
    moved = 0.0
    for leg in ((x_lo, *world.wrist_xyz()[1:]), (x_lo, y, z), (x_hi, y, z)):
        q_from = world.state.q.copy()
        length, blocked = guarded_wrist_move(world, np.array(leg), stop_when_located=True)
        if execute is not None:
            blocked = execute(q_from, world.state.q.copy()) or blocked
        moved += length
        if world.located():
            return f"({j}, {k})", moved, False
        if blocked:
            _bumped(world)
            return f"({j}, {k})", moved, True
    return f"({j}, {k})", moved, False


def _bumped(world: GraspWorld) -> None:
    """After a bump: sweep next the column that puts the grasp centre's line nearest the point of
    the object the hand bumped into (the object is there)."""
    order = world.search_order
    if not order:
        return
    witness = np.asarray(world.scene.min_distance(world.state).point_object)
    cols = world.search_columns
    want = witness[1:] - np.asarray(world.params.grasp_centre)[1:]
    n = min(range(len(order)), key=lambda i: float(np.sum((cols[order[i]] - want) ** 2)))
    order.insert(0, order.pop(n))


def guarded_wrist_move(
    world: GraspWorld, target: np.ndarray, stop_when_located: bool = False
) -> tuple[float, bool]:
    """Translate the wrist in a straight line toward ``target`` (world, m), guarded: conservative
    advancement, each sub-step at most the hand's clearance beyond ``params.clearance`` (and with
    ``stop_when_located`` the grasp centre's gap beyond the envelope, at least 0.5 mm); stops
    located, blocked (within 0.1 mm of the clearance, or the table) or at the target.
    Returns (length moved in m, blocked flag)."""
    p = world.params
    xyz = world.wrist_xyz_q
    start = world.wrist_position().copy()
    target, under_table = clamp_above(start, target, world.table_gap(), p.clearance)
    delta = np.asarray(target, dtype=float) - start
    length = float(np.linalg.norm(delta))
    if length < 1e-12:
        return 0.0, under_table
    unit = delta / length
    q = world.state.q
    travelled = 0.0
    for _ in range(500):
        if stop_when_located and world.located():
            return travelled, False
        clearance = world.exact_clearance()
        room = clearance - p.clearance
        if room < 1e-4:
            # touching distance: go on only if the move leads away from the object
            trial = min(1e-3, length - travelled)
            q[xyz] = start + unit * (travelled + trial)
            world.set_q(q)
            if world.exact_clearance() <= clearance:
                q[xyz] = start + unit * travelled
                world.set_q(q)
                return travelled, True
            step = trial
        else:
            step = min(length - travelled, room)
        if stop_when_located:
            step = min(step, max(world.object_gap_to_grasp_centre() - p.envelope_radius, 5e-4))
        travelled += step
        q[xyz] = start + unit * travelled
        world.set_q(q)
        if travelled >= length - 1e-12:
            return travelled, under_table
    return travelled, True


def step_wrist_toward(world: GraspWorld, target: np.ndarray, step: float) -> tuple[float, bool]:
    """Move the wrist up to ``step`` m toward ``target`` (world), stopping short (by bisection)
    of half the contact tolerance from the object, and of the table; (m left, stopped flag)."""
    xyz = world.wrist_xyz_q
    threshold = 0.5 * world.params.contact_tolerance
    start = world.wrist_position().copy()
    delta = np.asarray(target, dtype=float) - start
    dist = float(np.linalg.norm(delta))
    if dist < 1e-9:
        return 0.0, False
    move = min(step, dist)
    reach, under_table = clamp_above(start, start + delta * (move / dist), world.table_gap(), threshold)
    if under_table:  # the table stops the step first: move as far as it allows
        move = float(np.linalg.norm(reach - start))
    q = world.state.q.copy()

    def clear_at(fraction: float) -> bool:
        q[xyz] = start + delta * (fraction * move / dist)
        world.set_q(q)
        return world.hand_clear(threshold)

    if clear_at(1.0):
        return dist - move, under_table
    lo, hi = 0.0, 1.0  # fraction of the move that keeps the hand clear
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if clear_at(mid):
            lo = mid
        else:
            hi = mid
    clear_at(lo)
    return dist - lo * move, True
