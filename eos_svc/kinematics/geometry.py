"""Small geometry on 3-vectors: the tangent basis of a normal, one convention everywhere.

For a unit normal ``n``, ``t1`` is a preferred world axis projected on the plane ⟂ ``n`` and
normalised (world y when ``n`` is within ~25° of it) and ``t2 = n × t1``: ``(t1, t2, n)`` is
right-handed.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from eos_svc.errors import ValidationError

__all__ = ["tangent_basis", "tangent_pair", "unit_vector"]

#: |n_k| at or above which the preferred axis e_k is too close to n and world y is used
NEAR_AXIS = 0.9


def tangent_pair(
    nx: float, ny: float, nz: float, prefer: int = 0
) -> tuple[float, float, float, float, float, float]:
    """``t1`` and ``t2`` (six floats) of the unit normal ``(nx, ny, nz)``; ``prefer`` is the
    index of the preferred world axis (0 = x, 2 = z)."""
    if prefer not in (0, 2):
        raise ValidationError("prefer", f"must be 0 (world x) or 2 (world z), got {prefer!r}")
    k = prefer if abs(nz if prefer == 2 else nx) < NEAR_AXIS else 1
    nk = (nx, ny, nz)[k]
    tx, ty, tz = -nk * nx, -nk * ny, -nk * nz  # e_k − n_k n
    if k == 0:
        tx += 1.0
    elif k == 1:
        ty += 1.0
    else:
        tz += 1.0
    s = 1.0 / math.sqrt(tx * tx + ty * ty + tz * tz)
    tx, ty, tz = tx * s, ty * s, tz * s
    return tx, ty, tz, ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx


def tangent_basis(n: ArrayLike, prefer: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``(t1, t2)`` as arrays for the unit normal ``n`` (see the module docstring)."""
    x, y, z = np.asarray(n, dtype=float).reshape(3).tolist()
    t = tangent_pair(x, y, z, prefer)
    return np.array(t[:3]), np.array(t[3:])


def unit_vector(name: str, v: object) -> np.ndarray:
    """``v`` normalised (a new array); :class:`~eos_svc.errors.ValidationError` naming ``name``
    unless it is a finite non-zero 3-vector."""
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape == (3,) and np.all(np.isfinite(a)) and np.linalg.norm(a) >= 1e-12:
        out: np.ndarray = a / np.linalg.norm(a)
        return out
    raise ValidationError(name, f"must be a finite non-zero 3-vector, got {v!r}")
