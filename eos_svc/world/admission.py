"""Admission: refuse, before any planning, the objects the grasp planner cannot plan for.

:func:`check_plannable` is called first by :func:`eos_svc.agents.plan`, by ``eos plan`` and by
the Zenoh service at admission, so a request the planner would refuse is refused at the edge
with a :class:`~eos_svc.errors.ValidationError` naming the field and the reason. Three tests,
each a real geometric query on the hand's model (coal distances, Pinocchio kinematics):

* **reach** (``object.position``): the search moves the wrist inside the axis-aligned box
  [``search_box_lo``, ``search_box_hi``] (world, m) without turning it, so the grasp centre
  sweeps that box shifted by ``grasp_centre``. The object is *located* when its surface comes
  within ``envelope_radius`` of the grasp centre; if the coal distance between the object and
  the swept box exceeds ``envelope_radius``, no wrist position ever locates it.
* **overlap** (``object.position``): at the start configuration (``hand.neutral()``) the
  object must clear every hand collision geometry by ``clearance`` (coal distances).
* **size** (the size field that sets the object's smallest width): two fingertips can touch
  opposite sides of an object only if its smallest width is at most the hand's *span*, the
  largest distance between the surfaces of two fingertips over the fingers' joint ranges
  (:func:`hand_span`). Wider in every direction: no grasp exists.
"""

from __future__ import annotations

import functools
import itertools
import math
import struct
import threading
from collections import OrderedDict
from collections.abc import Hashable

import coal
import numpy as np

from eos_svc.agents.postulate import make_object
from eos_svc.agents.sweeps import forward_reach
from eos_svc.errors import ValidationError
from eos_svc.kinematics import HandModel
from eos_svc.kinematics.hand_cache import PerHandCache
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world.coverage import centre_in_grasp_box, findable
from eos_svc.world.parameters import WorldParameters

#: joint samples per finger joint when measuring the hand's span (a grid over the joint range)
SPAN_SAMPLES = 7

#: per hand: its span, neutral geometry and forward reach (see _hand_data)
_PER_HAND: PerHandCache[tuple[HandModel, float, list[_Geometry], float]] = PerHandCache(keep=8)


class _Geometry:
    """One hand collision geometry at the start configuration, with its bounding sphere (world)."""

    __slots__ = ("centre", "centre_xyz", "name", "radius", "shape", "transform")

    def __init__(self, name: str, shape: coal.ShapeBase, transform: coal.Transform3s) -> None:
        shape.computeLocalAABB()
        self.name = name
        self.shape = shape
        self.transform = transform
        self.centre = transform.transform(np.asarray(shape.aabb_center, dtype=float))
        self.radius = float(shape.aabb_radius)
        self.centre_xyz = (float(self.centre[0]), float(self.centre[1]), float(self.centre[2]))


def hand_span(hand: HandModel) -> float:
    """Largest distance between the surfaces of two fingertips, over each finger's joint range (m).

    Every finger's joints are sampled on a grid of :data:`SPAN_SAMPLES` values per joint
    (wrist at the origin); the span is the largest centre distance of two different fingers'
    tips minus both tip radii. An object wider than this in every direction cannot be touched
    on opposite sides by two fingertips.
    """
    return _hand_data(hand)[1]


def _hand_data(hand: HandModel) -> tuple[HandModel, float, list[_Geometry], float]:
    """(hand, span, its collision geometries at the start configuration, its forward reach),
    built once per hand."""
    return _PER_HAND.get((hand,), lambda: _build_hand_data(hand))


def _build_hand_data(hand: HandModel) -> tuple[HandModel, float, list[_Geometry], float]:
    from eos_svc.agents import planner  # planner imports this module: resolve at call time

    reach = forward_reach(hand, planner.finger_sweeps(hand))
    return hand, _measure_span(hand), _neutral_placements(hand), reach


def _measure_span(hand: HandModel) -> float:
    state = hand.state(hand.neutral())
    tips: dict[str, np.ndarray] = {}
    for finger in hand.finger_names:
        limits = hand.finger_joint_limits(finger)
        grids = [np.linspace(lo, hi, SPAN_SAMPLES) for _idx, lo, hi in limits]
        points = []
        for values in itertools.product(*grids):
            q = hand.neutral()
            for (idx, _lo, _hi), v in zip(limits, values, strict=True):
                q[idx] = v
            state.update(q)
            points.append(state.tip_position(finger).copy())
        tips[finger] = np.asarray(points)
    span = 0.0
    for a, b in itertools.combinations(hand.finger_names, 2):
        pa, pb = tips[a], tips[b]
        d = np.sqrt(((pa[:, None, :] - pb[None, :, :]) ** 2).sum(axis=2)).max()
        span = max(span, float(d) - hand.tip_radius(a) - hand.tip_radius(b))
    return span


def _neutral_placements(hand: HandModel) -> list[_Geometry]:
    state = hand.state(hand.neutral())
    out = []
    for gid, go in enumerate(hand.collision_model.geometryObjects):
        m = state.geometry_data.oMg[gid]
        out.append(
            _Geometry(go.name, go.geometry, coal.Transform3s(np.array(m.rotation), np.array(m.translation)))
        )
    return out


@functools.lru_cache(maxsize=16)
def _swept_box(params: WorldParameters) -> tuple[list[float], list[float]]:
    """The box the grasp centre sweeps during the search (world, m): ``search_box`` + ``grasp_centre``."""
    lo = [a + b for a, b in zip(params.search_box_lo, params.grasp_centre, strict=True)]
    hi = [a + b for a, b in zip(params.search_box_hi, params.grasp_centre, strict=True)]
    return lo, hi


def smallest_width(spec: ObjectSpec) -> tuple[float, str]:
    """The object's smallest width (m) and the size field that sets it (``object.<field>``)."""
    s = spec.size
    if spec.shape in ("sphere", "capsule"):
        return 2.0 * s["radius"], "object.radius"
    if spec.shape == "ellipsoid":
        return 2.0 * min(s["radii"]), "object.radii"
    if spec.shape == "cylinder":
        if s["length"] < 2.0 * s["radius"]:
            return s["length"], "object.length"
        return 2.0 * s["radius"], "object.radius"
    return min(s["size"]), "object.size"


def _distance(
    a: coal.ShapeBase, ta: coal.Transform3s, b: coal.ShapeBase, tb: coal.Transform3s
) -> coal.DistanceResult:
    """coal's signed distance between two placed shapes (a fresh result: callers run in parallel)."""
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    res = coal.DistanceResult()
    coal.distance(a, ta, b, tb, req, res)
    return res


#: verdicts kept per (hand, world parameters) pair (most recently used kept)
VERDICTS_KEPT = 256


class _Verdicts:
    """The last :data:`VERDICTS_KEPT` verdicts of one (hand, parameters) pair, by object: ``()``
    (plannable) or the refusal's ``(field, reason)``. Thread-safe; least recently used dropped
    first."""

    __slots__ = ("_entries", "_lock")

    def __init__(self) -> None:
        self._entries: OrderedDict[Hashable, tuple[str, ...]] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: Hashable) -> tuple[str, ...] | None:
        """The verdict kept for ``key``, or ``None`` when there is none."""
        with self._lock:
            try:
                self._entries.move_to_end(key)
            except KeyError:
                return None
            return self._entries[key]

    def put(self, key: Hashable, verdict: tuple[str, ...]) -> None:
        with self._lock:
            self._entries[key] = verdict
            while len(self._entries) > VERDICTS_KEPT:
                self._entries.popitem(last=False)

    def __len__(self) -> int:
        return len(self._entries)


#: per (hand, parameters) pair (owners compared by identity): its verdicts
_VERDICTS: PerHandCache[_Verdicts] = PerHandCache(keep=8)


_pack_pose = struct.Struct("6d").pack


def _object_key(spec: ObjectSpec) -> Hashable:
    """Everything of an object the verdict depends on (shape, size, pose), hashable; the pose as
    its 48 bytes, so that -0.0 and 0.0 (equal floats, written differently in a reason) differ."""
    return (spec.shape, tuple(spec.size.items()), _pack_pose(*spec.position, *spec.rpy))


def check_plannable(
    request: PlanRequest, hand: HandModel | None = None, params: WorldParameters | None = None
) -> None:
    """Raise :class:`ValidationError` if the planner cannot plan ``request`` (see the module doc).

    The verdict depends only on the object, the hand and the parameters: the last
    :data:`VERDICTS_KEPT` of each (hand, parameters) pair are kept, so an object asked for again
    (the same object, another seed) is answered without the geometric queries, bit for bit as
    they answer.

    Args:
        request: a validated plan request.
        hand: the hand (default: hand3x3, cached).
        params: world constants (default: ``WorldParameters.for_hand(hand)``).

    Raises:
        ValidationError: ``object.position`` when the object is out of reach or overlaps the
            hand at its start configuration; the size field when it is wider than the hand's
            span in every direction.
    """
    PlannableCheck(hand, params)(request)


class PlannableCheck:
    """:func:`check_plannable` with the hand and its parameters resolved once: call it with a
    request. What the service runs at admission (:func:`default_check`): a kept verdict costs a
    key and a dictionary lookup.

    Args:
        hand: the hand (default: hand3x3, cached).
        params: world constants (default: ``WorldParameters.for_hand(hand)``).
    """

    __slots__ = ("_verdicts", "hand", "params")

    def __init__(self, hand: HandModel | None = None, params: WorldParameters | None = None) -> None:
        from eos_svc.agents import planner  # planner imports this module: resolve at call time

        self.hand = hand or planner.default_hand()
        self.params = params or planner.parameters_for(self.hand)
        self._verdicts = _VERDICTS.get((self.hand, self.params), _Verdicts)

    def __call__(self, request: PlanRequest) -> None:
        """Raise :class:`ValidationError` if the planner cannot plan ``request``."""
        spec = request.obj
        key = _object_key(spec)
        verdict = self._verdicts.get(key)
        if verdict is None:
            verdict = plannable_verdict(spec, self.hand, self.params)
            self._verdicts.put(key, verdict)
        if verdict:
            field, reason = verdict
            raise ValidationError(field, reason)


@functools.cache
def default_check() -> PlannableCheck:
    """The admission check of the default hand (hand3x3) and its parameters, one per process."""
    return PlannableCheck()


def plannable_verdict(spec: ObjectSpec, hand: HandModel, params: WorldParameters) -> tuple[str, ...]:
    """The admission verdict on ``spec`` computed afresh (no kept verdicts): ``()`` when the
    planner can plan it, else the refusal's ``(field, reason)`` (see :func:`check_plannable`)."""
    try:
        _check_object(spec, hand, params)
    except ValidationError as exc:
        return exc.field, exc.reason
    return ()


def _check_object(spec: ObjectSpec, hand: HandModel, params: WorldParameters) -> None:
    """The three tests of the module doc; raises the refusal."""
    _, span, geometries, reach_ahead = _hand_data(hand)

    width, size_field = smallest_width(spec)
    if width > span:
        raise ValidationError(
            size_field,
            f"the {spec.shape}'s smallest width {width:.3f} m exceeds the hand's span {span:.3f} m "
            "(widest opening between two fingertips): no grasp exists",
        )

    # Reach. The centre lies in the object, so the object's gap to the swept box is at most the
    # centre's distance to it and at least that minus the bounding radius: coal only in between.
    centre = spec.position
    radius = 0.5 * _diameter(spec)
    lo, hi = _swept_box(params)
    outside = [max(lo[i] - centre[i], 0.0, centre[i] - hi[i]) for i in range(3)]
    centre_gap = math.sqrt(sum(d * d for d in outside))
    shape: coal.ShapeBase | None = None
    tf_obj: coal.Transform3s | None = None
    if centre_gap > params.envelope_radius:
        gap, axis = centre_gap - radius, max(range(3), key=outside.__getitem__)
        if gap <= params.envelope_radius:  # undecided by the bounds: the exact distance
            shape, tf_obj = _coal_object(spec)
            res = _distance(
                shape,
                tf_obj,
                coal.Box(*(np.subtract(hi, lo))),
                coal.Transform3s(np.eye(3), 0.5 * np.add(lo, hi)),
            )
            gap = float(res.min_distance)
            separation = np.abs(np.asarray(res.getNearestPoint1()) - np.asarray(res.getNearestPoint2()))
            axis = int(np.argmax(separation))
        if gap > params.envelope_radius:
            pos = ", ".join(f"{v:.3f}" for v in centre)
            raise ValidationError(
                f"object.position[{axis}]",  # the axis it is farthest out along
                f"out of reach: the object at [{pos}] m stays ≥ {gap:.3f} m from every grasp-centre "
                f"position the search can reach ([{lo[0]:.3f}, {hi[0]:.3f}] x [{lo[1]:.3f}, {hi[1]:.3f}] "
                f"x [{lo[2]:.3f}, {hi[2]:.3f}] m), more than the envelope radius {params.envelope_radius} m",
            )

    # Overlap: only the hand geometries whose bounding spheres come within clearance of the object's.
    cx, cy, cz = centre
    reach = radius + params.clearance
    for g in geometries:
        gx, gy, gz = g.centre_xyz
        if math.sqrt((gx - cx) ** 2 + (gy - cy) ** 2 + (gz - cz) ** 2) - g.radius > reach:
            continue  # the bounding spheres are apart (plain floats: 13 of them cost less than numpy)
        if shape is None or tf_obj is None:
            shape, tf_obj = _coal_object(spec)
        d = float(_distance(shape, tf_obj, g.shape, g.transform).min_distance)
        if d < params.clearance:
            raise ValidationError(
                "object.position",
                f"the object overlaps the hand at its start configuration ({g.name}: "
                f"distance {d * 1000:.1f} mm < clearance {params.clearance * 1000:.1f} mm); "
                "place it in front of the open hand",
            )

    # Findable: the search sweeps a lattice of columns and guarantees to locate only objects that
    # come near a sweep line and lie ahead of the fingers' reach from the rear of the box.
    rear_limit = params.search_box_lo[0] + reach_ahead + params.clearance
    surely = centre[0] - radius > rear_limit and centre_in_grasp_box(np.asarray(centre), params)
    if not surely and not findable(make_object(spec), params, reach_ahead):
        pos = ", ".join(f"{v:.3f}" for v in centre)
        raise ValidationError(
            "object.position",
            f"the search cannot be sure to find the object at [{pos}] m: it must come within "
            f"{params.envelope_radius} m of a sweep line and lie wholly ahead of x = "
            f"{rear_limit:.3f} m "
            "(what the fingers reach from the rear of the search box)",
        )


def _coal_object(spec: ObjectSpec) -> tuple[coal.ShapeBase, coal.Transform3s]:
    """The object's coal shape and placement (as :func:`eos_svc.agents.postulate.make_object` builds)."""
    obj = make_object(spec)
    return obj.geometry, coal.Transform3s(
        np.array(obj.placement.rotation), np.array(obj.placement.translation)
    )


def _diameter(spec: ObjectSpec) -> float:
    """Diameter of the smallest sphere about the object's centre that contains it (m)."""
    s = spec.size
    if spec.shape == "sphere":
        return 2.0 * s["radius"]
    if spec.shape == "ellipsoid":
        return 2.0 * max(s["radii"])
    if spec.shape == "cylinder":
        return 2.0 * math.hypot(s["radius"], 0.5 * s["length"])
    if spec.shape == "capsule":
        return 2.0 * s["radius"] + s["length"]
    return float(np.linalg.norm(s["size"]))
