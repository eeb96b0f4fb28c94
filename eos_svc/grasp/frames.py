"""Candidate palm orientations per primitive, and the wrist angles that give them.

The hand closes along the palm frame's z axis and approaches along its x axis. A candidate puts
the closing axis through the object's centre across it (the kind's own rule, GraspIt's:
Miller, Knoop, Christensen, Allen, ICRA 2003), in both senses, with every approach across it;
on a table also from above, never from under it nor closing vertically. Angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from eos_svc.objects import SurfaceObject
from eos_svc.objects.base import distinct_units, perpendicular_unit

_EX, _EY, _EZ = np.eye(3)


def rotation_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Palm rotation of the wrist joints: R = Rx(roll) · Ry(pitch) · Rz(yaw) (the URDF chain)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    out: np.ndarray = rx @ ry @ rz
    return out


def rpy_from_rotation(R: np.ndarray) -> tuple[float, float, float]:
    """The wrist's roll, pitch, yaw for palm rotation ``R`` (inverse of :func:`rotation_from_rpy`;
    pitch in [−π/2, π/2])."""
    pitch = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    yaw = math.atan2(-float(R[0, 1]), float(R[0, 0]))
    roll = math.atan2(-float(R[1, 2]), float(R[2, 2]))
    return roll, pitch, yaw


def palm_turn(R: np.ndarray) -> float:
    """Rotation angle of palm orientation ``R`` from the unrotated hand (rad)."""
    return math.acos(max(-1.0, min(1.0, 0.5 * (float(np.trace(R)) - 1.0))))


def frame(approach: np.ndarray, closing: np.ndarray) -> np.ndarray:
    """Palm rotation with x = ``approach`` and z = ``closing`` (orthonormalised), y = z × x."""
    x = approach / math.sqrt(float(approach @ approach))
    z = closing - float(closing @ x) * x
    z /= math.sqrt(float(z @ z))
    (x0, x1, x2), (z0, z1, z2) = x.tolist(), z.tolist()
    y = [z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0]  # z × x
    return np.array([[x0, y[0], z0], [x1, y[1], z1], [x2, y[2], z2]])


def closing_axes(obj: SurfaceObject, vertical_only: bool = False) -> list[tuple[str, np.ndarray]]:
    """The closing axes (unsigned, world) through the centre of mass, with a word on each: the
    object kind's own rule (:meth:`~eos_svc.objects.base.SurfaceObject.closing_axes`).
    ``vertical_only``: the postulate's size is known along the vertical only."""
    if vertical_only:
        return [("across the vertical", _EZ)]
    return obj.closing_axes()


#: on a table: a closing axis this close to the vertical (|z component|) is not tried, nor an
#: approach climbing more steeply than this (from under the table)
STEEP = 0.9
RISING = 0.2


def approach_axes(obj: SurfaceObject, closing: np.ndarray, on_table: bool = False) -> list[np.ndarray]:
    """Approach directions (signed, world, ⟂ ``closing``): the direction nearest the hand's
    unrotated approach (+x), then the kind's own
    (:meth:`~eos_svc.objects.base.SurfaceObject.approach_options`); ``on_table``: also the
    downward one (from above), and none rising more than :data:`RISING` (from under it)."""
    down = [perpendicular_unit(-_EZ, closing)] if on_table else []
    options = [perpendicular_unit(_EX, closing), *obj.approach_options(closing), *down]
    axes = distinct_units(options, signed=True)
    return [x for x in axes if not on_table or float(x[2]) <= RISING]


def candidate_frames(
    obj: SurfaceObject, vertical_only: bool = False, on_table: bool = False
) -> Iterator[tuple[str, np.ndarray]]:
    """(label, palm rotation) of every candidate orientation: each closing axis in both senses
    (the opposing finger on either side), each approach across it; ``on_table``: from above
    too, no closing axis steeper than :data:`STEEP` (see the module docstring)."""
    for words, g in closing_axes(obj, vertical_only):
        if on_table and abs(float(g[2])) > STEEP:
            continue
        for x in approach_axes(obj, g, on_table):
            label = f"{words} from above" if on_table and float(x[2]) < -STEEP else words
            for sign in (1.0, -1.0):
                yield label, frame(x, sign * g)
