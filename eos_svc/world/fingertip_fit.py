"""Does the object fit between this hand's fingertips along some axis?

The hand closes its fingers across the grip (the palm frame's z axis: the opposing finger on
one side, the others on the other). Its *opening* is the widest gap across the grip at which
every finger, closing from open, still reaches a contact with its fingertip:

* across **flat faces** (a box's, a cylinder's end faces): the tip must touch the face before
  any link of its finger does. Each finger's closing sweep is walked from open; a sample
  counts when a slab whose face is at the tip's height, reaching a given half depth either
  side of the tip along the approach (:data:`DEPTHS`), clears every link of that finger
  (coal distances). The flat opening at that depth is twice the smallest, over the fingers,
  of the largest such tip height: a deeper face meets the links sooner.
* across **curved surfaces** (sphere, ellipsoid, a cylinder's or capsule's side): the surface
  falls away from the links, so only the tips' own reach counts, capped by the grasp rule
  the planner plans with (paper §2.1: d/h < 1, :data:`~eos_svc.grasp.synthesis.MAX_D_OVER_H`).

Fingers that close side by side in planes apart from the palm's x–z plane (G1 Dex3's index and
middle, 57 mm apart) also need the object wide enough across them: a finger whose tip path
never comes nearer that plane than the object's half extent across it (plus the tip's radius)
misses it (:attr:`FingertipOpening.side_reach`).

A grip across an axis also needs room behind its contacts: the object's centre sits under the
opposing fingertip's contact, which lies at a depth ahead of the palm that the opposing
finger's sweep fixes (:meth:`FingertipOpening.room`); along some approach across the grip the
object must not reach back past it to the palm.

:func:`fit_refusal` is the one rule: admission (:mod:`eos_svc.world.admission`) refuses what it
refuses, and the random-draw experiment counts the same rule. SI units: metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np

from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.grasp.synthesis import MAX_D_OVER_H
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import ObjectSpec

#: half-size of the test slab across the hand (m): wider than any hand
_FAR = 1.0
#: half depths (along the approach, either side of the contacts) at which the flat opening is
#: measured (m)
DEPTHS: tuple[float, ...] = tuple(round(0.01 * k, 3) for k in range(1, 21))


@dataclass(frozen=True)
class FingertipOpening:
    """The widest openings of one hand across its grip (m) and the room behind its contacts.

    Attributes:
        flat_by_depth: per half depth of :data:`DEPTHS`, the widest gap between two parallel
            faces that deep every fingertip touches before its links.
        curved: widest convex width every fingertip reaches (≤ MAX_D_OVER_H × hand height).
        opposing_offaxis: the opposing finger's closing sweep: each sample's tip-centre
            distance from the palm's x axis (m), in closing order.
        opposing_x: the same samples' depth ahead of the palm frame (m).
        palm_front: the largest x of the hand's geometries that are not on a finger (m).
        tip_radius: the opposing fingertip's radius (m).
        side_reach: the least half extent across the fingers' closing planes (the palm's y
            axis) that every fingertip reaches: over the fingers, the largest of the tip path's
            least distance from the palm's x–z plane less the tip radius (m; ≤ 0 when every
            path crosses that plane).
    """

    flat_by_depth: tuple[float, ...]
    curved: float
    opposing_offaxis: tuple[float, ...]
    opposing_x: tuple[float, ...]
    palm_front: float
    tip_radius: float
    side_reach: float = 0.0

    @classmethod
    def build(
        cls, hand: HandModel, sweeps: dict[str, FingerSweep], links: dict[str, list[int]]
    ) -> FingertipOpening:
        """The opening of ``hand`` from its closing ``sweeps`` and each finger's ``links``
        (collision geometry ids), wrist at its neutral pose (palm = world)."""
        state = hand.state(hand.neutral())
        palm = state.palm_placement()
        geometries = hand.collision_model.geometryObjects
        flat_half = np.full(len(DEPTHS), math.inf)
        reach_half = math.inf
        for finger, sweep in sweeps.items():
            r = hand.tip_radius(finger)
            side = 1.0 if float(np.mean(sweep.points[:, 2])) >= 0.0 else -1.0
            idx = hand.finger_q_index(finger)
            q = hand.neutral()
            heights = side * sweep.points[:, 2] - r
            order = np.argsort(-heights)  # the widest tip heights first
            best = np.full(len(DEPTHS), -math.inf)
            for k in order.tolist():
                open_depths = [j for j in range(len(DEPTHS)) if best[j] == -math.inf]
                if not open_depths or heights[k] <= 0.0:
                    break
                q[idx] = sweep.angles[k]
                state.update(q)
                placements = [state.geometry_data.oMg[g] for g in links[finger]]
                for j in open_depths:
                    # the face: a slab of the tip's height across the grip, DEPTHS[j] either side
                    # of the tip along the approach; the tip touches it first when no link does
                    slab = coal.Box(2.0 * DEPTHS[j], 2.0 * _FAR, 2.0 * float(heights[k]))
                    centre = palm.act(np.array([float(sweep.points[k, 0]), 0.0, 0.0]))
                    pose = coal.Transform3s(np.array(palm.rotation), centre)
                    pairs = zip(links[finger], placements, strict=True)
                    if all(_distance(geometries[g].geometry, m, slab, pose) > 0.0 for g, m in pairs):
                        best[j] = float(heights[k])
            flat_half = np.minimum(flat_half, best)
            reach_half = min(reach_half, float(np.max(heights)))
        moving = {g for ids in links.values() for g in ids}
        tips = {hand.tip_geometry_id(f) for f in hand.finger_names}
        state.update(hand.neutral())
        front = -math.inf
        for g, obj in enumerate(geometries):
            if g in moving or g in tips:
                continue
            obj.geometry.computeLocalAABB()
            m = state.geometry_data.oMg[g]
            corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
            lo, hi = np.asarray(obj.geometry.aabb_local.min_), np.asarray(obj.geometry.aabb_local.max_)
            points = (lo + corners * (hi - lo)) @ np.asarray(m.rotation).T + np.asarray(m.translation)
            front = max(front, float(np.max((points - palm.translation) @ palm.rotation[:, 0])))
        opposing = sweeps[hand.description.opposing_finger]
        cap = MAX_D_OVER_H * hand.hand_height  # the grasp rule the planner plans with
        return cls(
            flat_by_depth=tuple(max(0.0, min(2.0 * float(v), cap)) for v in flat_half),
            curved=max(0.0, min(2.0 * reach_half, cap)),
            opposing_offaxis=tuple(np.hypot(opposing.points[:, 1], opposing.points[:, 2]).tolist()),
            opposing_x=tuple(opposing.points[:, 0].tolist()),
            palm_front=front if math.isfinite(front) else 0.0,
            tip_radius=hand.tip_radius(hand.description.opposing_finger),
            side_reach=max(
                float(np.min(np.abs(sweep.points[:, 1]))) - hand.tip_radius(f) for f, sweep in sweeps.items()
            ),
        )

    @property
    def flat(self) -> float:
        """The widest opening across flat faces of the shallowest object (m)."""
        return self.flat_by_depth[0]

    def flat_at(self, half_depth: float) -> float:
        """The widest opening across flat faces reaching ``half_depth`` either side of the
        contacts along the approach (m; the next deeper grid value of :data:`DEPTHS`)."""
        j = int(np.searchsorted(DEPTHS, half_depth - 1e-12))
        return self.flat_by_depth[min(j, len(DEPTHS) - 1)] if j < len(DEPTHS) else self.flat_by_depth[-1]

    def limit(self, surface: str, half_depth: float = 0.0) -> float:
        """The widest opening across a ``"flat"`` or a ``"curved"`` surface (m); a flat face
        reaching ``half_depth`` either side of the contacts (m)."""
        return self.flat_at(half_depth) if surface == "flat" else self.curved

    def room(self, width: float) -> float:
        """How far behind its contacts an object of ``width`` across the grip may reach before it
        meets the palm (m): the opposing tip's depth where its sweep first comes within
        ``width``/2 + r_f of the palm's axis, less the palm's front. −inf when it never does."""
        reach = 0.5 * width + self.tip_radius
        for off, x in zip(self.opposing_offaxis, self.opposing_x, strict=True):
            if off <= reach:
                return x - self.palm_front
        return -math.inf


def _distance(a: coal.ShapeBase, ta: object, b: coal.ShapeBase, tb: coal.Transform3s) -> float:
    """coal's distance between a placed geometry (its Pinocchio placement ``ta``) and ``b`` (m)."""
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    pose = coal.Transform3s(np.array(ta.rotation), np.array(ta.translation))  # type: ignore[attr-defined]
    coal.distance(a, pose, b, tb, req, res)
    return float(res.min_distance)


@dataclass(frozen=True)
class GripAxis:
    """One axis an object may be gripped across: its width (m), the surface the tips meet
    (``"flat"`` or ``"curved"``), the half extents along the approaches across it (m; the
    smallest is used) and the size field that sets the width."""

    width: float
    surface: str
    approach_halves: tuple[float, ...]
    field: str


def grip_axes(spec: ObjectSpec) -> list[GripAxis]:
    """The axes ``spec`` may be gripped across, as the grasp synthesis tries them
    (:func:`~eos_svc.grasp.frames.closing_axes`): a sphere about a diameter; an ellipsoid across
    each axis; a cylinder or capsule across its axis (and a short cylinder along it, on its
    end faces); a box across each pair of faces."""
    s = spec.size
    if spec.shape == "sphere":
        r = s["radius"]
        return [GripAxis(2.0 * r, "curved", (r,), "object.radius")]
    if spec.shape == "ellipsoid":
        radii = list(s["radii"])
        return [
            GripAxis(2.0 * radii[i], "curved", tuple(radii[j] for j in range(3) if j != i), "object.radii")
            for i in range(3)
        ]
    if spec.shape == "cylinder":
        r, length = s["radius"], s["length"]
        axes = [GripAxis(2.0 * r, "curved", (r, 0.5 * length), "object.radius")]
        if length <= 2.0 * r:
            axes.append(GripAxis(length, "flat", (r,), "object.length"))
        return axes
    if spec.shape == "capsule":
        r, length = s["radius"], s["length"]
        return [GripAxis(2.0 * r, "curved", (r, 0.5 * length + r), "object.radius")]
    if spec.shape == "mesh":
        return _mesh_grip_axes(spec)
    sizes = list(s["size"])
    return [
        GripAxis(sizes[i], "flat", tuple(0.5 * sizes[j] for j in range(3) if j != i), "object.size")
        for i in range(3)
    ]


def _mesh_grip_axes(spec: ObjectSpec) -> list[GripAxis]:
    """A mesh gripped as a box across its principal axes (the grasp synthesis' rule for a mesh):
    its convex hull's extents along them, flat faces (the conservative opening)."""
    from eos_svc.grasp.postulate import make_object

    obj = make_object(spec)
    V = np.asarray(obj.hull.vertices) @ obj.principal_axes()  # type: ignore[attr-defined]
    sizes = (V.max(axis=0) - V.min(axis=0)).tolist()
    return [
        GripAxis(sizes[i], "flat", tuple(0.5 * sizes[j] for j in range(3) if j != i), "object.scale")
        for i in range(3)
    ]


def grip_sides(axis: GripAxis) -> list[tuple[float, float]]:
    """(half extent along the approach, half extent across the fingers) of each way the hand may
    take a grip across ``axis``: either perpendicular half as the approach, the other across."""
    halves = axis.approach_halves
    if len(halves) == 1:
        return [(halves[0], halves[0])]
    a, b = halves[0], halves[1]
    return [(a, b), (b, a)]


def fits_across(axis: GripAxis, opening: FingertipOpening, clearance: float) -> bool:
    """Whether a grip across ``axis`` fits: its width below the opening for its surface, and
    along some approach the object's half extent within the room behind the contacts and its
    half extent across the fingers at least :attr:`FingertipOpening.side_reach`."""
    if axis.width >= opening.limit(axis.surface, min(axis.approach_halves)):
        return False
    room = opening.room(axis.width) - clearance
    return any(depth <= room and side >= opening.side_reach for depth, side in grip_sides(axis))


def fit_refusal(spec: ObjectSpec, opening: FingertipOpening, clearance: float) -> tuple[str, str] | None:
    """None when ``spec`` fits between the fingertips along some axis (:func:`fits_across`);
    else the refusal: the size field of its thinnest axis and the reason, naming the limits."""
    axes = grip_axes(spec)
    if any(fits_across(a, opening, clearance) for a in axes):
        return None

    def share(a: GripAxis) -> float:  # the width as a share of its opening (inf: no opening)
        limit = opening.limit(a.surface, min(a.approach_halves))
        return a.width / limit if limit > 0.0 else math.inf

    thinnest = min(axes, key=lambda a: (share(a), a.width))
    limit = opening.limit(thinnest.surface, min(thinnest.approach_halves))
    if thinnest.width >= limit:
        why = (
            f"its thinnest grip is {thinnest.width * 1000:.1f} mm across {thinnest.surface} surfaces, "
            f"not below the widest opening at which every fingertip still reaches a contact "
            f"({limit * 1000:.1f} mm across {thinnest.surface} surfaces"
            + (f" {min(thinnest.approach_halves) * 1000:.0f} mm deep" if thinnest.surface == "flat" else "")
            + ")"
        )
    elif all(side < opening.side_reach for _depth, side in grip_sides(thinnest)):
        side = max(side for _depth, side in grip_sides(thinnest))
        why = (
            f"across its thinnest grip ({thinnest.width * 1000:.1f} mm) it is {2.0 * side * 1000:.1f} mm "
            f"wide across the fingers, narrower than the {2.0 * opening.side_reach * 1000:.1f} mm "
            f"between the fingertips of the fingers closing side by side (a fingertip would miss it)"
        )
    else:
        room = opening.room(thinnest.width) - clearance
        why = (
            f"across its thinnest grip ({thinnest.width * 1000:.1f} mm) it reaches "
            f"{min(thinnest.approach_halves) * 1000:.1f} mm behind the contacts, more than the "
            f"{room * 1000:.1f} mm before the palm"
        )
    reason = f"the {spec.shape} fits between the fingertips along no axis: {why}; no grasp exists"
    return thinnest.field, reason
