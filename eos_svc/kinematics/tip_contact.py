"""The contact of a sphere fingertip with the object, measured by coal with reused objects.

:class:`SphereTipProbe` keeps one ``coal.ComputeDistance`` functor, its transforms, request and
result for one fingertip and one object (the rolling step measures the same pair every step:
building them costs more than the query). Its contact is
:meth:`~eos_svc.kinematics.scene.Scene.contact`'s for that pair (the rolling tests compare the
contacts of the steps with closed forms).
"""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from ._slots import slot_setters
from .scene import Contact

__all__ = ["SphereTipProbe"]

_new = object.__new__
_SC_FINGER, _SC_DISTANCE, _SC_POINT_TIP, _SC_POINT_OBJECT, _SC_NORMAL = slot_setters(
    Contact, "finger", "distance", "point_tip", "point_object", "normal"
)


class SphereTipProbe:
    """Signed distance, witness points and normal between a sphere tip and one object.

    Args:
        finger: the finger's name (written into each :class:`Contact`).
        radius: the tip sphere's radius, m.
        object_shape: the object's coal shape; place it with :meth:`place_object`.
    """

    __slots__ = ("dist", "finger", "object_shape", "radius", "req", "res", "tf_obj", "tf_tip", "tip_shape")

    def __init__(self, finger: str, radius: float, object_shape: Any) -> None:
        self.finger = finger
        self.radius = radius
        # keep the shapes referenced: the functor holds raw pointers to them
        self.tip_shape = coal.Sphere(radius)
        self.object_shape = object_shape
        self.dist = coal.ComputeDistance(object_shape, self.tip_shape)
        self.tf_obj = coal.Transform3s()
        self.tf_tip = coal.Transform3s()
        self.req = coal.DistanceRequest()
        self.req.enable_signed_distance = True
        self.req.gjk_tolerance = 1e-12
        self.res = coal.DistanceResult()

    def place_object(self, placement: pin.SE3) -> None:
        """Set the object's world placement."""
        self.tf_obj.setTransform(np.asarray(placement.rotation), np.asarray(placement.translation))

    def measure(self, centre: np.ndarray) -> tuple[Contact, tuple[float, float, float]]:
        """The contact with the tip sphere centred at ``centre`` (world, m), and its normal
        (object → tip) as floats."""
        d, p_obj, cx, cy, cz, n = self.measure_raw(centre)
        nx_, ny_, nz_ = n
        r = self.radius
        contact: Contact = _new(Contact)  # slots filled directly (see _slots)
        _SC_FINGER(contact, self.finger)
        _SC_DISTANCE(contact, d)
        _SC_POINT_TIP(contact, np.array((cx - r * nx_, cy - r * ny_, cz - r * nz_)))
        _SC_POINT_OBJECT(contact, p_obj)
        _SC_NORMAL(contact, np.array(n))
        return contact, n

    def measure_raw(
        self, centre: np.ndarray
    ) -> tuple[float, np.ndarray, float, float, float, tuple[float, float, float]]:
        """:meth:`measure`'s numbers without the :class:`Contact` (the rolling step of EP1 needs
        only the gap and the normal): ``(signed distance m, object witness point (world, m),
        the centre as three floats, the normal object → tip as three floats)``."""
        c = centre
        self.tf_tip.setTranslation(c)
        res = self.res
        res.clear()  # needed: a result at distance <= 0 would satisfy the next request as is
        d = self.dist(self.tf_obj, self.tf_tip, self.req, res)  # = res.min_distance
        p_obj = res.getNearestPoint1()
        cx, cy, cz = c.tolist()
        ox, oy, oz = p_obj.tolist()
        dx, dy, dz = cx - ox, cy - oy, cz - oz
        nn = math.sqrt(dx * dx + dy * dy + dz * dz)
        if nn > 1e-12 and d > -0.5 * self.radius:  # tip centre outside the object
            s = 1.0 / nn
            n = (dx * s, dy * s, dz * s)
        else:
            nx_, ny_, nz_ = np.asarray(res.normal, dtype=float).tolist()
            n = (nx_, ny_, nz_)
        return d, p_obj, cx, cy, cz, n
