"""The postulated object's geometry as grasp synthesis needs it, per primitive kind: the signed
distance of many points at once, and the half-extent from the centre along a direction.

SI units: metres.
"""

from __future__ import annotations

import numpy as np

from eos_svc.kinematics import Box, Capsule, Cylinder, Ellipsoid, Sphere, SurfaceObject
from eos_svc.kinematics.norms import row_norms


def signed_distances(obj: SurfaceObject, points: np.ndarray) -> np.ndarray:
    """Signed distance (m, negative inside) of each world point in ``points`` (N, 3) to
    ``obj``'s surface. Exact for every primitive but the ellipsoid, whose distance is the
    first-order estimate ``k0 (k0 − 1) / k1`` (exact on the surface, within a few % of it
    one fingertip radius away; the contacts themselves are projected exactly)."""
    M = obj.placement
    p = (np.asarray(points, dtype=float) - M.translation) @ M.rotation  # local coordinates
    if isinstance(obj, Sphere):
        out: np.ndarray = row_norms(p) - obj.radius
        return out
    if isinstance(obj, Ellipsoid):
        r = np.asarray(obj.radii)
        k0 = row_norms(p / r)
        k1 = np.maximum(row_norms(p / (r * r)), 1e-12)
        out = k0 * (k0 - 1.0) / k1
        return out
    if isinstance(obj, Cylinder):
        dr = np.hypot(p[:, 0], p[:, 1]) - obj.radius
        dz = np.abs(p[:, 2]) - 0.5 * obj.length
        outside = np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0))
        out = np.where((dr <= 0.0) & (dz <= 0.0), np.maximum(dr, dz), outside)
        return out
    if isinstance(obj, Capsule):
        z = np.clip(p[:, 2], -0.5 * obj.length, 0.5 * obj.length)
        out = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2 + (p[:, 2] - z) ** 2) - obj.radius
        return out
    if isinstance(obj, Box):
        q = np.abs(p) - 0.5 * np.asarray(obj.size)
        outside = row_norms(np.maximum(q, 0.0))
        out = outside + np.minimum(np.max(q, axis=1), 0.0)
        return out
    raise TypeError(f"obj: no signed distance for {type(obj).__name__}")


def half_extent(obj: SurfaceObject, direction: np.ndarray) -> float:
    """Distance from the object's centre to its surface along the unit ``direction`` (m)."""
    if isinstance(obj, Ellipsoid):  # exact: the ray meets x²/a² + y²/b² + z²/c² = 1
        local = obj.placement.rotation.T @ direction
        return float(1.0 / np.linalg.norm(local / np.asarray(obj.radii)))
    c = obj.placement.translation
    reach = 0.5 * obj.diameter + 1e-3
    t = np.linspace(reach / 256, reach, 256)
    sd = signed_distances(obj, c + t[:, None] * direction)
    outside = sd > 0.0
    k = int(np.argmax(outside)) if np.any(outside) else len(t) - 1
    if k == 0:
        return float(t[0])
    # linear interpolation of the zero crossing between samples k-1 and k
    a, b = sd[k - 1], sd[k]
    return float(t[k - 1] + (t[k] - t[k - 1]) * (-a / (b - a) if b != a else 0.0))
