"""The contact of a sphere fingertip with the object, measured by one ``coal.ComputeDistance``
functor (the rolling QP measures the same pair at every step); the normal runs from the
object's witness point to the sphere centre.
"""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from .scene import Contact

__all__ = ["SphereTipProbe"]


class SphereTipProbe:
    """Signed distance, witness points and normal between ``finger``'s sphere tip (``radius``
    m) and one object's coal shape (placed by :meth:`place_object`)."""

    def __init__(self, finger: str, radius: float, object_shape: Any) -> None:
        self.finger = finger
        self.radius = radius
        # the functor holds raw pointers to both shapes: keep them referenced
        self.tip_shape = coal.Sphere(radius)
        self.object_shape = object_shape
        self._distance = coal.ComputeDistance(object_shape, self.tip_shape)
        self._tf_obj = coal.Transform3s()
        self._tf_tip = coal.Transform3s()
        self._request = coal.DistanceRequest()
        self._request.enable_signed_distance = True
        self._request.gjk_tolerance = 1e-12
        self._result = coal.DistanceResult()

    def place_object(self, placement: pin.SE3) -> None:
        """Set the object's world placement."""
        self._tf_obj.setTransform(np.asarray(placement.rotation), np.asarray(placement.translation))

    def measure(self, centre: np.ndarray) -> Contact:
        """The contact with the tip sphere centred at ``centre`` (world, m)."""
        self._tf_tip.setTranslation(centre)
        res = self._result
        res.clear()  # a result at distance <= 0 would satisfy the next request as it is
        dist = float(self._distance(self._tf_obj, self._tf_tip, self._request, res))
        p_obj = res.getNearestPoint1()
        (cx, cy, cz), (px, py, pz) = centre.tolist(), p_obj.tolist()
        dx, dy, dz = cx - px, cy - py, cz - pz  # on floats: numpy costs ~0.3 µs a call on 3-vectors
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        # the tip centre outside the object: the normal through it (exact); else coal's
        if norm > 1e-12 and dist > -0.5 * self.radius:
            nx, ny, nz = dx / norm, dy / norm, dz / norm
        else:
            nx, ny, nz = res.normal.tolist()
        r = self.radius
        tip = np.array((cx - r * nx, cy - r * ny, cz - r * nz))
        return Contact(self.finger, dist, tip, p_obj, np.array((nx, ny, nz)))
