"""Contact queries between the hand's collision geometry and one object (coal): signed distances
(negative = penetration), witness points and the normal, world coordinates (m).
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from eos_svc.objects import SurfaceObject

from .hand import HandModel, HandState, KinematicsError, UnknownNameError

__all__ = ["Contact", "Scene"]


@dataclass(slots=True)
class Contact:
    """Closest points of one hand geometry (``finger``: the finger's or the geometry's name) and
    the object: signed ``distance`` (m, negative = penetration), world witness points on the hand
    and on the object (m), and the world unit ``normal`` from the object toward the hand."""

    finger: str
    distance: float
    point_tip: np.ndarray
    point_object: np.ndarray
    normal: np.ndarray


class Scene:
    """A hand and one object (coal requests, results and transforms reused across calls).
    ``exact_tips``: sphere-fingertip contacts from the object's analytic closest point (exact,
    ~10× slower) instead of coal's (GJK: within a few µm tangentially on an ellipsoid)."""

    def __init__(self, hand: HandModel, obj: SurfaceObject, exact_tips: bool = False) -> None:
        if not isinstance(hand, HandModel):
            raise KinematicsError("hand", f"must be a HandModel, got {type(hand).__name__}")
        if not isinstance(obj, SurfaceObject):
            raise KinematicsError("obj", f"must be a SurfaceObject, got {type(obj).__name__}")
        self.hand = hand
        self.object = obj
        self._obj_geom = obj.geometry
        self.exact_tips = bool(exact_tips)
        self._req = coal.DistanceRequest()
        self._req.enable_signed_distance = True
        self._req.gjk_tolerance = 1e-8  # curved shapes (ellipsoid): ~1e-8 m instead of ~4e-7 m
        self._res = coal.DistanceResult()
        self._tf_obj = coal.Transform3s()
        self._tf_tip = coal.Transform3s()
        self._point = coal.Sphere(1e-9)  # a point probe for point_gap
        self._tf_point = coal.Transform3s()
        self.set_object_placement(obj.placement)
        # the hand's collision shapes by geometry id (reading them through the geometry model's
        # vector from Python costs ~3 µs a query)
        self._hand_shapes = [go.geometry for go in hand.collision_model.geometryObjects]
        # per finger: radius, tip shape (a sphere of that radius when the tip has no geometry)
        self._tips: dict[str, tuple[float, coal.ShapeBase, bool]] = {}
        for name in hand.finger_names:
            gid, r = hand.tip_geometry_id(name), hand.tip_radius(name)
            shape = coal.Sphere(r) if gid is None else self._hand_shapes[gid]
            self._tips[name] = (r, shape, isinstance(shape, coal.Sphere))

    def set_object_placement(self, placement: pin.SE3) -> None:
        """Move the object (world ← object). Use this rather than assigning
        ``obj.placement``: the scene caches the coal transform."""
        self.object.placement = pin.SE3(placement)
        self._tf_obj.setTransform(
            np.asarray(placement.rotation, dtype=float),
            np.asarray(placement.translation, dtype=float),
        )

    def contact(self, state: HandState, finger: str) -> Contact:
        """Closest points between finger ``finger``'s tip and the object."""
        if finger not in self._tips:
            raise UnknownNameError("finger", f"unknown finger {finger!r}; known: {self.hand.finger_names}")
        r, shape, is_sphere = self._tips[finger]
        res = self._res
        res.clear()
        if is_sphere:
            c = state.tip_centre_view(finger)  # the tip centre (world)
            if self.exact_tips:
                return self._analytic_sphere_contact(finger, c.copy(), r)
            self._tf_tip.setTranslation(c)
            coal.distance(self._obj_geom, self._tf_obj, shape, self._tf_tip, self._req, res)
            d = res.min_distance
            if d < 0.0:  # penetration: coal's EPA / sphere-cylinder depth is approximate
                return self._analytic_sphere_contact(finger, c.copy(), r)
            # coal's sphere–primitive witnesses and normal (object → tip) are exact for the
            # sphere, box, capsule and cylinder; GJK-accurate (~µm) for the ellipsoid.
            return Contact(finger, d, res.getNearestPoint2(), res.getNearestPoint1(), res.normal.copy())
        gid = self.hand.tip_geometry_id(finger)
        assert gid is not None
        return self._geometry_distance(state, gid, finger)

    def _analytic_sphere_contact(self, finger: str, c: np.ndarray, r: float) -> Contact:
        """Exact contact of a sphere (centre c, radius r) from the object's analytic closest
        point; used when the sphere penetrates the object."""
        obj = self.object
        p_obj, sd = obj.closest_point_and_distance(c)
        diff = c - p_obj
        nd = float(np.linalg.norm(diff))
        # outward from the object through the centre; centre on the surface: surface normal
        n = obj.surface_normal(p_obj) if nd <= 1e-12 else diff / (nd if sd >= 0.0 else -nd)
        return Contact(finger, sd - r, c - r * n, p_obj, n)

    def tip_contacts(self, state: HandState) -> tuple[Contact, ...]:
        """:meth:`contact` of every finger, in ``hand.finger_names`` order (:class:`KinematicsError`
        when ``state`` belongs to another hand model)."""
        if state.hand is not self.hand:
            raise KinematicsError("state", "belongs to another hand model than the scene's")
        return tuple(self.contact(state, f) for f in self.hand.finger_names)

    def distance(self, state: HandState, geometry_name: str) -> Contact:
        """Closest points between any hand collision geometry (by name) and the object;
        ``Contact.finger`` holds the geometry name."""
        return self._geometry_distance(state, self.hand.geometry_id(geometry_name))

    def gap(self, state: HandState, gid: int) -> float:
        """Signed distance (m) between hand collision geometry ``gid`` and the object, without
        witness points (the cheap query for guarded motions)."""
        res = self._res
        res.clear()
        coal.distance(
            self._obj_geom, self._tf_obj, self._hand_shapes[gid], state.geometry_data.oMg[gid], self._req, res
        )
        return float(res.min_distance)

    def point_gap(self, point: np.ndarray) -> float:
        """Signed distance (m) from a world point to the object's surface (negative inside)."""
        self._tf_point.setTranslation(np.asarray(point, dtype=float))
        res = self._res
        res.clear()
        coal.distance(self._obj_geom, self._tf_obj, self._point, self._tf_point, self._req, res)
        return float(res.min_distance)

    def _geometry_distance(self, state: HandState, gid: int, name: str | None = None) -> Contact:
        """Closest points of hand geometry ``gid`` and the object (``Contact.finger``: ``name``,
        default the geometry's name)."""
        go = self.hand.collision_model.geometryObjects[gid]
        res = self._res
        res.clear()
        oMg = state.geometry_data.oMg[gid]
        coal.distance(self.object.geometry, self._tf_obj, go.geometry, oMg, self._req, res)
        nearest_hand, nearest_object = res.getNearestPoint2(), res.getNearestPoint1()
        return Contact(name or go.name, res.min_distance, nearest_hand, nearest_object, res.normal.copy())

    def min_distance(self, state: HandState) -> Contact:
        """The closest of all hand collision geometries to the object."""
        best: Contact | None = None
        for gid in range(self.hand.collision_model.ngeoms):
            c = self._geometry_distance(state, gid)
            if best is None or c.distance < best.distance:
                best = c
        assert best is not None
        return best
