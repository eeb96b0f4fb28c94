"""Resting poses: the orientation nearest a drawn one in which an object can rest on a table.

A random orientation is no pose an object on a table rests in (a box on an edge, a capsule on
its end): in the Drake world such an object topples before the plan starts, away from the pose
the request gave. :func:`resting_rpy` turns a drawn orientation by the smallest rotation that
makes it a stable resting pose on a horizontal table, its heading kept:

- a sphere: any orientation rests;
- a box: the local axis nearest the vertical made vertical (it lies on the face nearest the
  table);
- an ellipsoid: its shortest axis made vertical (the only stable rest: its centre of mass
  lowest);
- a cylinder: upright on an end when its axis is within 45° of the vertical, else lying on its
  side (the axis made horizontal);
- a capsule: lying (its axis made horizontal: on a hemispherical end it would topple).

Conventions: ``rpy`` roll, pitch, yaw (rad), R = Rz(yaw) Ry(pitch) Rx(roll), as
:class:`~eos_svc.schema.request.ObjectSpec`; cylinders' and capsules' axes are local z.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

UP = np.array([0.0, 0.0, 1.0])


def _turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector ``a`` to unit vector ``b`` (3×3)."""
    axis = np.cross(a, b)
    sin, cos = float(np.linalg.norm(axis)), float(np.clip(a @ b, -1.0, 1.0))
    if sin < 1e-12:
        if cos > 0.0:
            return np.eye(3)
        other = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        axis = np.cross(a, other)
        return np.asarray(pin.AngleAxis(math.pi, axis / np.linalg.norm(axis)).matrix())
    return np.asarray(pin.AngleAxis(math.atan2(sin, cos), axis / sin).matrix())


def _vertical(axis: np.ndarray) -> np.ndarray:
    """The vertical nearest ``axis`` (up or down)."""
    return UP if axis[2] >= 0.0 else -UP


def _horizontal(axis: np.ndarray) -> np.ndarray:
    """``axis`` projected on the horizontal plane, unit (x when it is vertical)."""
    flat = np.array([axis[0], axis[1], 0.0])
    norm = float(np.linalg.norm(flat))
    return flat / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])


def resting_rotation(shape: str, size: Mapping[str, Any], rotation: np.ndarray) -> np.ndarray:
    """The resting orientation (3×3) nearest ``rotation`` for an object of ``shape`` and ``size``
    (its :class:`~eos_svc.schema.request.ObjectSpec` size fields); see the module docstring."""
    R = np.asarray(rotation, dtype=float)
    if shape == "sphere":
        return R
    if shape == "box":
        i = int(np.argmax(np.abs(R[2, :])))
        axis = R[:, i]
        return _turn(axis, _vertical(axis)) @ R
    if shape == "ellipsoid":
        axis = R[:, int(np.argmin(np.asarray(size["radii"], dtype=float)))]
        return _turn(axis, _vertical(axis)) @ R
    if shape in ("cylinder", "capsule"):
        axis = R[:, 2]
        upright = shape == "cylinder" and abs(float(axis[2])) >= math.cos(math.radians(45.0))
        return _turn(axis, _vertical(axis) if upright else _horizontal(axis)) @ R
    raise ValueError(f"shape: no resting pose known for {shape!r}")


def resting_rpy(shape: str, size: Mapping[str, Any], rpy: Sequence[float]) -> tuple[float, float, float]:
    """:func:`resting_rotation` of the orientation ``rpy`` (rad), as roll, pitch, yaw (rad)."""
    R = resting_rotation(shape, size, np.asarray(pin.rpy.rpyToMatrix(*map(float, rpy))))
    r, p, y = (float(v) for v in pin.rpy.matrixToRpy(R))
    return (r, p, y)
