"""Candidate palm orientations per primitive, and the wrist angles that give them.

The hand closes its fingers along the palm frame's z axis (the opposing finger below, the
others above) and approaches along its x axis. A candidate orientation puts the closing axis
through the object's centre of mass across the object, as GraspIt's primitive rules do
(Miller, Knoop, Christensen, Allen, ICRA 2003):

- sphere: about a diameter (vertical and horizontal closing, approach from the hand's side);
- ellipsoid: across each of its two shorter axes;
- cylinder and capsule: across the axis (closing along the axis' normals, approach along the
  other normal, the axis, or from the hand's side), and along the axis when it is short;
- box: across each pair of opposite faces, approach along the other face normals.

Each closing axis is taken in both senses (the opposing finger on either side), with every
approach across it. Angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from eos_svc.objects import Box, Capsule, Cylinder, Ellipsoid, Sphere, SurfaceObject

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


def _unit_perp(v: np.ndarray, axis: np.ndarray) -> np.ndarray | None:
    """``v`` with its component along unit ``axis`` removed, normalised (None if ~parallel)."""
    w = v - (v @ axis) * axis
    n = float(np.linalg.norm(w))
    return None if n < 1e-6 else w / n


def _distinct(vectors: list[np.ndarray | None], signed: bool) -> list[np.ndarray]:
    """The unit ``vectors`` (Nones skipped) without near-repeats (cosine ≥ 0.999; of either sign
    unless ``signed``), in order."""
    out: list[np.ndarray] = []
    for v in vectors:
        if v is not None and all((v @ u if signed else abs(v @ u)) < 0.999 for u in out):
            out.append(v)
    return out


def closing_axes(obj: SurfaceObject, vertical_only: bool = False) -> list[tuple[str, np.ndarray]]:
    """The closing axes (unsigned, world) through the centre of mass for ``obj``'s kind, with
    a word on each. ``vertical_only``: the postulate's size is known along the vertical only."""
    if vertical_only:
        return [("across the vertical", _EZ)]
    A = obj.placement.rotation
    if isinstance(obj, Sphere):
        return [("about a vertical diameter", _EZ), ("about a horizontal diameter", _EY)]
    if isinstance(obj, Ellipsoid):
        order = np.argsort(np.asarray(obj.radii))
        words = ("shortest", "middle")
        return [(f"across its {w} axis", A[:, int(i)]) for w, i in zip(words, order[:2], strict=True)]
    if isinstance(obj, (Cylinder, Capsule)):
        axis = A[:, 2]
        across = _distinct([A[:, 0], A[:, 1], _unit_perp(_EZ, axis), _unit_perp(_EY, axis)], signed=False)
        axes = [("across the axis", g) for g in across]
        total = obj.length + (2.0 * obj.radius if isinstance(obj, Capsule) else 0.0)
        if total <= 2.0 * obj.radius:  # short: also along the axis (on the end faces)
            axes.append(("along the axis", axis))
        return axes
    if isinstance(obj, Box):
        return [(f"across faces {name}", A[:, i]) for i, name in enumerate(("±x", "±y", "±z"))]
    raise TypeError(f"obj: no grasp rule for {type(obj).__name__}")


def approach_axes(obj: SurfaceObject, closing: np.ndarray) -> list[np.ndarray]:
    """Approach directions (signed, world, ⟂ ``closing``): the object's own axes across the
    grip and the direction nearest the hand's unrotated approach (+x)."""
    A = obj.placement.rotation
    options: list[np.ndarray | None] = [_unit_perp(_EX, closing)]
    if not isinstance(obj, Sphere):
        options += [_unit_perp(sign * A[:, i], closing) for i in range(3) for sign in (1.0, -1.0)]
        if isinstance(obj, (Cylinder, Capsule)):
            options.append(_unit_perp(np.cross(closing, A[:, 2]), closing))
    return _distinct(options, signed=True)


def candidate_frames(obj: SurfaceObject, vertical_only: bool = False) -> Iterator[tuple[str, np.ndarray]]:
    """(label, palm rotation) of every candidate orientation: each closing axis in both senses
    (the opposing finger on either side), each approach across it."""
    for words, g in closing_axes(obj, vertical_only):
        for x in approach_axes(obj, g):
            for sign in (1.0, -1.0):
                yield words, frame(x, sign * g)
