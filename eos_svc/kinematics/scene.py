"""Contact queries between the hand's collision geometry and one object (coal).

Signed distances (negative = penetration), witness points and the normal, in world
coordinates (m). For a separated sphere fingertip, coal's sphere–primitive algorithms give
exact witnesses and normal (sphere, box, capsule, cylinder; GJK-accurate, a few µm, for the
ellipsoid — ``Scene(..., exact_tips=True)`` makes those exact too). When a sphere fingertip
penetrates the object, the contact comes from the object's analytic closest point instead:
coal's penetration depth is approximate for curved shapes (its sphere–cylinder depth ignores
the caps; EPA converges to a tolerance).
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from eos_svc.objects import SurfaceObject

from ._slots import slot_setters
from .hand import HandModel, HandState, KinematicsError

__all__ = ["Contact", "Scene"]


@dataclass(frozen=True, slots=True)
class Contact:
    """Closest-point result between one hand geometry and the object.

    Attributes:
        finger: finger name (or the geometry name for :meth:`Scene.distance`).
        distance: signed distance, m (negative = penetration depth).
        point_tip: world witness point on the hand geometry (fingertip surface), m.
        point_object: world witness point on the object surface, m.
        normal: world unit normal, from the object toward the fingertip.
    """

    finger: str
    distance: float
    point_tip: np.ndarray
    point_object: np.ndarray
    normal: np.ndarray


_new = object.__new__
_SET_FINGER, _SET_DISTANCE, _SET_POINT_TIP, _SET_POINT_OBJECT, _SET_NORMAL = slot_setters(
    Contact, "finger", "distance", "point_tip", "point_object", "normal"
)


def _fast_contact(
    finger: str, distance: float, point_tip: np.ndarray, point_object: np.ndarray,
    normal: np.ndarray,
) -> Contact:
    """Contact(...) without the frozen dataclass __init__ (which costs ~2 µs): fills the slots
    directly. The instance is still frozen for its users."""
    c: Contact = _new(Contact)
    _SET_FINGER(c, finger)
    _SET_DISTANCE(c, distance)
    _SET_POINT_TIP(c, point_tip)
    _SET_POINT_OBJECT(c, point_object)
    _SET_NORMAL(c, normal)
    return c


class Scene:
    """A hand and one object. Reuses coal requests/results/transforms across calls.

    Args:
        hand: the hand model.
        obj: the object.
        exact_tips: when True, sphere-fingertip contacts always come from the object's
            analytic closest point (exact witnesses, slower: ~10–50 µs); when False (default)
            from coal (~1–5 µs), whose GJK witness on curved objects such as the ellipsoid is
            within a few µm tangentially (distance within ~1e-8 m).
    """

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
        # coal distance functors (object–point probe; object–hand geometry by id, made on first
        # use): the query coal.distance makes, without its per-call dispatch (≈ 2 µs a query)
        self._point_distance = coal.ComputeDistance(self._obj_geom, self._point)
        self._gap_distance: dict[int, coal.ComputeDistance] = {}
        self._tip_gmodel: pin.GeometryModel | None = None  # built by the first tip_contacts
        self._tip_model_tried = False
        self.set_object_placement(obj.placement)
        # the hand's collision shapes by geometry id (reading them through the geometry model's
        # vector from Python costs ~3 µs a query)
        self._hand_shapes = [go.geometry for go in hand.collision_model.geometryObjects]
        # Per finger: frame id, radius, sphere shape (from the URDF when it is a sphere), and
        # a coal distance functor object–tip (cheaper per call than coal.distance; it holds
        # raw pointers to both shapes, which self._tips and self.object keep alive).
        self._tips: dict[str, tuple[int, float, coal.ShapeBase, bool]] = {}
        self._functors: dict[str, coal.ComputeDistance] = {}
        for name in hand.finger_names:
            gid = hand.tip_geometry_id(name)
            r = hand.tip_radius(name)
            geom = hand.collision_model.geometryObjects[gid].geometry if gid is not None else None
            is_sphere = geom is None or isinstance(geom, coal.Sphere)
            shape = geom if geom is not None else coal.Sphere(r)
            self._tips[name] = (hand.tip_frame_id(name), r, shape, is_sphere)
            self._functors[name] = coal.ComputeDistance(self._obj_geom, shape)

    def _build_tip_model(self) -> None:
        """Every sphere fingertip against the object in one Pinocchio call: a GeometryModel of
        the tips and the object (on the universe joint), one (object, tip) collision pair per
        finger, so that ``pin.computeDistances`` runs all the coal queries (see
        :meth:`tip_contacts`). Built on first use (≈ 0.2 ms); not when a fingertip is not a
        sphere."""
        self._tip_model_tried = True
        hand = self.hand
        if not all(self._tips[f][3] for f in hand.finger_names):
            return
        gm = pin.GeometryModel()
        for name in hand.finger_names:
            fid, _, shape, _ = self._tips[name]
            gid = hand.tip_geometry_id(name)
            if gid is not None:
                go = hand.collision_model.geometryObjects[gid]
                joint, frame, placement = go.parentJoint, go.parentFrame, go.placement
            else:  # the tip sphere is centred on the tip frame
                f = hand.model.frames[fid]
                joint, frame, placement = f.parentJoint, fid, f.placement
            gm.addGeometryObject(pin.GeometryObject(f"{name}_tip", joint, frame, placement, shape))
        self._obj_gid = gm.addGeometryObject(
            pin.GeometryObject("object", 0, 0, pin.SE3(self.object.placement), self._obj_geom)
        )
        for k in range(len(hand.finger_names)):
            gm.addCollisionPair(pin.CollisionPair(self._obj_gid, k))
        gd = pin.GeometryData(gm)
        for req in gd.distanceRequests:
            req.enable_signed_distance = True
            req.gjk_tolerance = self._req.gjk_tolerance
        self._tip_gmodel, self._tip_gdata = gm, gd
        # per finger: name, radius, and its DistanceResult (a reference into the GeometryData)
        self._tip_batch = [
            (name, self._tips[name][1], gd.distanceResults[k])
            for k, name in enumerate(hand.finger_names)
        ]

    def set_object_placement(self, placement: pin.SE3) -> None:
        """Move the object (world ← object). Use this rather than assigning
        ``obj.placement``: the scene caches the coal transform."""
        self.object.placement = pin.SE3(placement)
        self._tf_obj.setTransform(
            np.asarray(placement.rotation, dtype=float),
            np.asarray(placement.translation, dtype=float),
        )
        if self._tip_gmodel is not None:
            self._tip_gmodel.geometryObjects[self._obj_gid].placement = pin.SE3(placement)

    def contact(self, state: HandState, finger: str) -> Contact:
        """Closest points between finger ``finger``'s tip and the object."""
        try:
            _, r, shape, is_sphere = self._tips[finger]
        except KeyError:
            from .hand import UnknownNameError

            raise UnknownNameError(
                "finger", f"unknown finger {finger!r}; known: {self.hand.finger_names}"
            ) from None
        res = self._res
        res.clear()
        if is_sphere:
            c = state._tips[finger][3]  # live view of the tip centre (world)
            if self.exact_tips:
                return self._analytic_sphere_contact(finger, c.copy(), r)
            self._tf_tip.setTranslation(c)
            self._functors[finger](self._tf_obj, self._tf_tip, self._req, res)
            d = res.min_distance
            if d < 0.0:  # penetration: coal's EPA / sphere-cylinder depth is approximate
                return self._analytic_sphere_contact(finger, c.copy(), r)
            # coal's sphere–primitive witnesses and normal (object → tip) are exact for the
            # sphere, box, capsule and cylinder; GJK-accurate (~µm) for the ellipsoid.
            return _fast_contact(
                finger, d, res.getNearestPoint2(), res.getNearestPoint1(), res.normal.copy()
            )
        gid = self.hand.tip_geometry_id(finger)
        assert gid is not None
        coal.distance(
            self.object.geometry, self._tf_obj, shape, state.geometry_data.oMg[gid], self._req, res
        )
        return Contact(
            finger, res.min_distance, res.getNearestPoint2(), res.getNearestPoint1(), res.normal.copy()
        )

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
        """:meth:`contact` of every finger, in ``hand.finger_names`` order (world frame, m):
        signed distance, witness points on the tip and the object, normal object → tip.

        One ``pin.updateGeometryPlacements`` + ``pin.computeDistances`` over (object, tip)
        collision pairs instead of one coal query per finger: the same coal algorithms, so the
        same contacts (exactly for sphere, box, cylinder and capsule objects; the ellipsoid's GJK
        witness within µm), except that the tip sphere sits at its collision geometry's
        placement, which :class:`HandModel` checks to be the tip frame within 1e-6 m.
        Penetrating tips take the exact analytic path, as in :meth:`contact`. The first call
        builds the tips' geometry model (≈ 0.2 ms). With ``exact_tips`` or a non-sphere
        fingertip it is :meth:`contact` per finger. Every returned array is the contact's own.

        Raises:
            KinematicsError: ``state`` belongs to another hand model.
        """
        if state.hand is not self.hand:
            raise KinematicsError("state", "belongs to another hand model than the scene's")
        gm = self._tip_gmodel
        if gm is None or self.exact_tips:
            if not (self._tip_model_tried or self.exact_tips):
                self._build_tip_model()
                return self.tip_contacts(state)
            return tuple(self.contact(state, f) for f in self.hand.finger_names)
        gd = self._tip_gdata
        pin.updateGeometryPlacements(self.hand.model, state.data, gm, gd)
        pin.computeDistances(gm, gd)
        return tuple(
            _fast_contact(
                finger, d, res.getNearestPoint2(), res.getNearestPoint1(), res.normal.copy()
            )
            if (d := res.min_distance) >= 0.0
            # penetration: the exact contact, as in contact()
            else self._analytic_sphere_contact(finger, state._tips[finger][3].copy(), r)
            for finger, r, res in self._tip_batch
        )

    def contacts(self, state: HandState) -> dict[str, Contact]:
        """:meth:`contact` for every finger."""
        return dict(zip(self.hand.finger_names, self.tip_contacts(state), strict=True))

    def distance(self, state: HandState, geometry_name: str) -> Contact:
        """Closest points between any hand collision geometry (by name) and the object;
        ``Contact.finger`` holds the geometry name."""
        gid = self.hand.geometry_id(geometry_name)
        return self._geometry_distance(state, gid)

    def gap(self, state: HandState, gid: int) -> float:
        """Signed distance (m) between hand collision geometry ``gid`` and the object, without
        witness points (the cheap query for guarded motions)."""
        functor = self._gap_distance.get(gid)
        if functor is None:
            functor = self._gap_distance[gid] = coal.ComputeDistance(self._obj_geom, self._hand_shapes[gid])
        res = self._res
        res.clear()
        functor(self._tf_obj, state.geometry_data.oMg[gid], self._req, res)
        return float(res.min_distance)

    def point_gap(self, point: np.ndarray) -> float:
        """Signed distance (m) from a world point to the object's surface (negative inside)."""
        self._tf_point.setTranslation(np.asarray(point, dtype=float))
        res = self._res
        res.clear()
        self._point_distance(self._tf_obj, self._tf_point, self._req, res)
        return float(res.min_distance)

    def _geometry_distance(self, state: HandState, gid: int) -> Contact:
        go = self.hand.collision_model.geometryObjects[gid]
        res = self._res
        res.clear()
        coal.distance(
            self.object.geometry,
            self._tf_obj,
            go.geometry,
            state.geometry_data.oMg[gid],
            self._req,
            res,
        )
        return Contact(
            go.name, res.min_distance, res.getNearestPoint2(), res.getNearestPoint1(), res.normal.copy()
        )

    def min_distance(self, state: HandState) -> Contact:
        """The closest of all hand collision geometries to the object."""
        best: Contact | None = None
        for gid in range(self.hand.collision_model.ngeoms):
            c = self._geometry_distance(state, gid)
            if best is None or c.distance < best.distance:
                best = c
        assert best is not None
        return best
