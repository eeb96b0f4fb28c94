"""Grasp synthesis on a postulated primitive (Miller, Knoop, Christensen, Allen, ICRA 2003).

The planner's hand closes its fingers along the palm frame's z axis (the opposing finger
below, the others above) and approaches along its x axis; its 6-DoF wrist can place and
turn the palm anywhere in its workspace. A *candidate grasp* is a palm orientation (the
approach direction and the hand's roll about it) and a depth (the object's centre on the
palm's x axis, that far ahead of the palm). For each primitive the candidates put the
closing axis through the centre of mass across the object, as GraspIt's primitive rules do:

- sphere: about a diameter (vertical and horizontal closing, approach from the hand's side);
- ellipsoid: across each of its two shorter axes;
- cylinder and capsule: across the axis (closing along the axis' normals, approach along the
  other normal, the axis, or from the hand's side), and along the axis when it is short;
- box: across each pair of opposite faces, approach along the other face normals.

Each candidate is simulated on the *postulated* object (never the true one): every finger's
closing sweep (:class:`~eos_svc.agents.sweeps.FingerSweep`, fingertip-centre path in the palm
frame) is run against the object's signed distance until the fingertip touches — its
*landing*: sweep index, contact point and outward normal. A candidate is kept when the
wrist can take its pose (joint limits), every fingertip lands from the open hand, the
contacts lie about the centre (the end agent's Fig. 2 test with a margin), the object is
smaller than the hand height across the grip (paper §2.1: d/h < 1), and the hand is
collision-free on the postulated object at the pre-grasp, along the straight approach with
the fingers open and at the landing with only the fingertips touching (coal distances).
The kept candidates are scored by the Ferrari–Canny ε of their predicted contacts on the
postulated object (:mod:`eos_svc.agents.quality`; ``SCORE_EDGES`` cone edges for speed) and
the best is chosen; ties (a sphere's symmetric grasps) go to the least wrist rotation.

SI units throughout: metres, radians.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from eos_svc.agents.quality import grasp_quality
from eos_svc.agents.sweeps import FingerSweep
from eos_svc.kinematics import (
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    HandModel,
    Scene,
    Sphere,
    SurfaceObject,
)
from eos_svc.kinematics.gap_bounds import ball_gap_lower_bounds, hand_bound_table
from eos_svc.kinematics.norms import row_norms, vector_norm
from eos_svc.world.parameters import WorldParameters

#: cone edges of the ε that ranks candidates (the end agent judges with 8; 4 is ~10× faster)
SCORE_EDGES = 4
#: smallest predicted angle (deg) across the centre a candidate must reach (the end agent's
#: good-grasp test asks 150°; the margin absorbs the difference between postulate and object)
MIN_PREDICTED_ANGLE_DEG = 160.0
#: depth offsets tried, in order, about the depth that puts the opposing contact under the
#: centre (m); the best is refined by ±``DEPTH_REFINE``
DEPTH_OFFSETS = (0.0, -0.004, 0.004, -0.008, 0.008, -0.012, 0.012, -0.016, 0.016, -0.02, 0.02)
DEPTH_REFINE = 0.002
#: ε within this fraction of the best counts as equal (then the smaller wrist rotation wins)
EPSILON_TIE = 0.05
#: collision-free candidates scored by ε (the least-rotated first)
SCORED = 4
#: a depth whose predicted angle across the centre reaches this needs no other depth tried (deg)
GOOD_ENOUGH_ANGLE_DEG = 172.0
#: largest object across the grip, as a fraction of the hand height (paper §2.1: d/h < 1)
MAX_D_OVER_H = 1.0
#: approach-path samples checked for collisions between pre-grasp and grasp
APPROACH_SAMPLES = 4


@dataclass(frozen=True)
class Landing:
    """Where a closing fingertip first touches the object.

    Attributes:
        index: sweep sample at which the tip touches (the finger's angle is ``sweep.angles[index]``).
        angle: that joint angle (rad).
        point: contact point on the object (world, m).
        normal: the object's outward unit normal there (world).
    """

    index: int
    angle: float
    point: np.ndarray
    normal: np.ndarray

    def to_dict(self) -> dict:
        """JSON form (rounded to µm)."""
        return {
            "angle": round(self.angle, 6),
            "point": np.round(self.point, 6).tolist(),
            "normal": np.round(self.normal, 6).tolist(),
        }


@dataclass(frozen=True)
class GraspCandidate:
    """One candidate grasp on the postulated object.

    Attributes:
        label: how it grasps, in words (e.g. "across the axis, approach along the normal").
        rotation: palm orientation in the world (3×3; columns: approach x, y, closing z).
        wrist_rpy: the wrist's roll, pitch, yaw joint values giving ``rotation`` (rad).
        wrist: palm origin at the grasp (world, m).
        depth: the object's centre ahead of the palm along the approach (m).
        extent: the object's half-extent along the closing axis through its centre (m).
        landings: per finger, where its tip touches when it closes from open.
        angle_deg: angle between the opposing contact and the others' midpoint seen from the
            centre (deg; 180 = straight across).
        epsilon: Ferrari–Canny ε of the predicted contacts (``SCORE_EDGES`` cone edges).
        turn: rotation angle of the palm from the unrotated hand (rad), the tie-breaker.
    """

    label: str
    rotation: np.ndarray
    wrist_rpy: tuple[float, float, float]
    wrist: np.ndarray
    depth: float
    extent: float
    landings: dict[str, Landing]
    angle_deg: float
    epsilon: float = 0.0
    turn: float = 0.0

    @property
    def about_centre(self) -> bool:
        """The predicted contacts lie about the centre (``MIN_PREDICTED_ANGLE_DEG``)."""
        return self.angle_deg >= MIN_PREDICTED_ANGLE_DEG

    @property
    def approach(self) -> np.ndarray:
        """Unit approach direction (world): the palm's x axis."""
        return self.rotation[:, 0]

    @property
    def closing(self) -> np.ndarray:
        """Unit closing direction (world): the palm's z axis (opposing finger → the others)."""
        return self.rotation[:, 2]


# --- the postulated object's signed distance, vectorised -------------------------------
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


def sweep_gaps(
    obj: SurfaceObject, sweep: FingerSweep, tip_radius: float, rotation: np.ndarray, origin: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The sweep's fingertip centres in the world (N, 3), the palm at (``rotation``,
    ``origin``), and each one's gap to ``obj`` (signed distance less the tip radius, m)."""
    return rotated_sweep_gaps(obj, sweep.points @ rotation.T, tip_radius, origin)


def rotated_sweep_gaps(
    obj: SurfaceObject, rotated: np.ndarray, tip_radius: float, origin: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sweep_gaps` from the sweep's points already turned by the palm's rotation
    (``sweep.points @ rotation.T``, which a caller moving the palm without turning it keeps)."""
    pts = rotated + origin
    return pts, signed_distances(obj, pts) - tip_radius


def landing_from(
    obj: SurfaceObject, sweep: FingerSweep, pts: np.ndarray, gaps: np.ndarray, start: int = 0
) -> Landing | None:
    """:func:`landing` from precomputed :func:`sweep_gaps` (``pts``, ``gaps``)."""
    start = max(0, start - 1)
    hits = np.flatnonzero(gaps[start:] <= 0.0)
    if len(hits) == 0 or hits[0] == 0:
        return None
    return _landing_at(obj, sweep, pts, gaps, start + int(hits[0]))


def _landing_at(obj: SurfaceObject, sweep: FingerSweep, pts: np.ndarray, gaps: np.ndarray, k: int) -> Landing:
    """The landing between samples ``k`` − 1 (free) and ``k`` (touching)."""
    a, b = gaps[k - 1], gaps[k]
    s = a / (a - b) if a != b else 1.0  # the touching point between samples k-1 and k
    tip = pts[k - 1] + s * (pts[k] - pts[k - 1])
    point = obj.closest_surface_point(tip)
    # a sphere tip touching a convex object: the contact normal runs from the contact point to
    # the tip's centre (defined on edges and rims too, where the surface normal is not)
    out = tip - point
    length = vector_norm(out)
    normal = out / length if length > 1e-9 else obj.surface_normal(tip)
    angle = float(sweep.angles[k - 1] + s * (sweep.angles[k] - sweep.angles[k - 1]))
    return Landing(k, angle, point, normal)


class SweepLandings:
    """:func:`landing_from` for every start sample of one sweep at one palm pose, each landing
    computed once.

    The landing from ``start`` depends on ``start`` only through the first touching sample
    ``k`` at or after ``max(0, start − 1)`` (none, or that sample itself: no landing), so a
    finger closing step by step toward the same ``k`` asks for the same landing again: it is
    built once per ``k`` (as :func:`landing_from` builds it: the result is the plain one's).

    Args:
        obj: the object.
        sweep: the finger's closing sweep.
        pts: the sweep's fingertip centres at this pose (world, m; :func:`sweep_gaps`).
        gaps: their gaps to ``obj`` (m; :func:`sweep_gaps`).
    """

    def __init__(self, obj: SurfaceObject, sweep: FingerSweep, pts: np.ndarray, gaps: np.ndarray) -> None:
        self._args = (obj, sweep, pts, gaps)
        self._touching = np.flatnonzero(gaps <= 0.0).tolist()  # the touching samples, increasing
        self._by_sample: dict[int, Landing] = {}

    def first_touch(self, start: int) -> int | None:
        """The first touching sample a finger closing from ``start`` meets (None: none does, or
        it already touches there — no landing)."""
        s = max(0, start - 1)
        touching = self._touching
        i = bisect_left(touching, s)
        if i == len(touching) or touching[i] == s:
            return None
        return int(touching[i])

    def miss_lower_bound(self, start: int, tip_radius: float, point: np.ndarray) -> float:
        """A lower bound (m) of the distance from the landing from ``start`` to ``point`` (world)
        without the object's closest point: −inf when there is no landing or the object is an
        ellipsoid (whose gaps are estimates, see :func:`signed_distances`).

        The landing's contact is the closest surface point to the touching tip centre
        (:func:`_landing_at`), ``|sd(tip)|`` from it; the signed distance is 1-Lipschitz and
        exact at the bracketing samples (their gap + ``tip_radius``), so
        ``|sd(tip)| ≤ max(|gap(k−1) + r + seg|, |gap(k) + r − seg|)``, ``seg`` the samples'
        spacing, and the contact is at least ``|tip − point|`` less that from ``point``
        (less 1e-9 m for round-off)."""
        k = self.first_touch(start)
        obj, _, pts, gaps = self._args
        if k is None or isinstance(obj, Ellipsoid):
            return -math.inf
        a, b = float(gaps[k - 1]), float(gaps[k])
        s = a / (a - b) if a != b else 1.0
        p0, p1 = pts[k - 1], pts[k]
        tip = p0 + s * (p1 - p0)
        seg = vector_norm(p1 - p0)
        reach = max(abs(a + tip_radius + seg), abs(b + tip_radius - seg))
        return vector_norm(tip - point) - reach - 1e-9

    def landing(self, start: int) -> Landing | None:
        """``landing_from(obj, sweep, pts, gaps, start)``, from the memo when the same sample is
        touched first."""
        k = self.first_touch(start)
        if k is None:
            return None
        memo = self._by_sample
        hit = memo.get(k)
        if hit is None:
            hit = memo[k] = _landing_at(*self._args, k)
        return hit


def landing(
    obj: SurfaceObject,
    sweep: FingerSweep,
    tip_radius: float,
    rotation: np.ndarray,
    origin: np.ndarray,
    start: int = 0,
) -> Landing | None:
    """Where ``sweep``'s fingertip (radius ``tip_radius``) first touches ``obj`` when the
    finger closes from sample ``start`` (a finger between samples ``start`` − 1 and ``start``,
    not touching, closes from the former), the palm at (``rotation``, ``origin``) in the
    world; None when it never does, or already touches there."""
    pts, gaps = sweep_gaps(obj, sweep, tip_radius, rotation, origin)
    return landing_from(obj, sweep, pts, gaps, start)


def diameter_angle_deg(centre: np.ndarray, opposing: np.ndarray, others: list[np.ndarray]) -> float:
    """Angle (deg) between the opposing contact and the others' midpoint, seen from ``centre``
    (the end agent's Fig. 2 test)."""
    u = opposing - centre
    v = np.mean(others, axis=0) - centre
    cos = float(u @ v / max(float(np.linalg.norm(u) * np.linalg.norm(v)), 1e-12))
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


# --- wrist orientation -------------------------------------------------------------------
def rotation_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Palm rotation of the wrist joints: R = Rx(roll) · Ry(pitch) · Rz(yaw) (the URDF chain)."""
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
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


def frame(approach: np.ndarray, closing: np.ndarray) -> np.ndarray:
    """Palm rotation with x = ``approach`` and z = ``closing`` (orthonormalised), y = z × x."""
    x = approach / vector_norm(approach)
    z = closing - (closing @ x) * x
    z /= vector_norm(z)
    return np.column_stack([x, cross3(z, x), z])


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of two 3-vectors, bit for bit (the same products and differences),
    in scalar arithmetic (numpy's broadcasting costs ~10 µs here)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


# --- candidate frames per primitive ------------------------------------------------------
_EX, _EY, _EZ = np.eye(3)


def _unit_perp(v: np.ndarray, axis: np.ndarray) -> np.ndarray | None:
    """``v`` with its component along unit ``axis`` removed, normalised (None if ~parallel)."""
    w = v - (v @ axis) * axis
    n = float(np.linalg.norm(w))
    return None if n < 1e-6 else w / n


def _dedupe(vectors: list[np.ndarray | None], signed: bool) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for v in vectors:
        if v is None:
            continue
        if all((abs(v @ u) if not signed else v @ u) < 0.999 for u in out):
            out.append(v)
    return out


def closing_axes(obj: SurfaceObject, vertical_only: bool = False) -> list[tuple[str, np.ndarray]]:
    """The closing axes (unsigned, world) through the centre of mass for ``obj``'s kind, with
    a word on each. ``vertical_only``: the postulate's size is known along the vertical only."""
    if vertical_only:
        return [("across the vertical", _EZ)]
    A = obj.placement.rotation
    a1, a2, a3 = A[:, 0], A[:, 1], A[:, 2]
    if isinstance(obj, Sphere):
        return [("about a vertical diameter", _EZ), ("about a horizontal diameter", _EY)]
    if isinstance(obj, Ellipsoid):
        order = np.argsort(np.asarray(obj.radii))
        words = ("shortest", "middle")
        return [(f"across its {w} axis", A[:, int(i)]) for w, i in zip(words, order[:2], strict=True)]
    if isinstance(obj, (Cylinder, Capsule)):
        across = _dedupe([a1, a2, _unit_perp(_EZ, a3), _unit_perp(_EY, a3)], signed=False)
        axes = [("across the axis", g) for g in across]
        total = obj.length + (2.0 * obj.radius if isinstance(obj, Capsule) else 0.0)
        if total <= 2.0 * obj.radius:  # short: also along the axis (on the end faces)
            axes.append(("along the axis", a3))
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
        for i in range(3):
            for sign in (1.0, -1.0):
                options.append(_unit_perp(sign * A[:, i], closing))
        if isinstance(obj, (Cylinder, Capsule)):
            axis = A[:, 2]
            options.append(_unit_perp(np.cross(closing, axis), closing))
    return _dedupe(options, signed=True)


def candidate_frames(obj: SurfaceObject, vertical_only: bool = False) -> Iterator[tuple[str, np.ndarray]]:
    """(label, palm rotation) of every candidate orientation: each closing axis in both senses
    (the opposing finger on either side), each approach across it."""
    for words, g in closing_axes(obj, vertical_only):
        for x in approach_axes(obj, g):
            for sign in (1.0, -1.0):
                yield words, frame(x, sign * g)


def palm_turn(R: np.ndarray) -> float:
    """Rotation angle of palm orientation ``R`` from the unrotated hand (rad)."""
    return math.acos(max(-1.0, min(1.0, 0.5 * (float(np.trace(R)) - 1.0))))


# --- the synthesis -----------------------------------------------------------------------
class GraspSynthesis:
    """Candidate grasps of one hand on one postulated object, checked and scored.

    Args:
        hand: the hand model.
        sweeps: its fingers' closing sweeps (palm frame).
        params: world constants (approach stand-off, clearance).
        obj: the postulated object.
        friction: Coulomb μ for ε.
        vertical_only: the postulate's size is known along the vertical only (grasp across it).
    """

    def __init__(
        self,
        hand: HandModel,
        sweeps: dict[str, FingerSweep],
        params: WorldParameters,
        obj: SurfaceObject,
        friction: float,
        vertical_only: bool = False,
    ) -> None:
        self.hand = hand
        self.sweeps = sweeps
        self.params = params
        self.obj = obj
        self.friction = friction
        self.vertical_only = vertical_only
        self.scene = Scene(hand, obj)  # the imagined scene: the hand and the postulated object
        self.state = hand.state(hand.neutral())
        self.opposing = hand.description.opposing_finger
        widx = hand.wrist_q_index
        # the wrist rotation's limits widened by 1e-9 rad (as floats, see wrist_rpy)
        self._rpy_lo = (hand.lower[widx[3:6]] - 1e-9).tolist()
        self._rpy_hi = (hand.upper[widx[3:6]] + 1e-9).tolist()
        self._xyz_lo, self._xyz_hi = hand.lower[widx[:3]], hand.upper[widx[:3]]
        tips = {hand.tip_geometry_id(f) for f in hand.finger_names}
        geometries = hand.collision_model.geometryObjects
        self._all_geometries = list(range(len(geometries)))
        self._body_geometries = [g for g in self._all_geometries if g not in tips]
        # per collision geometry, how to bound its gap to the object's bounding ball from below
        # (eos_svc.kinematics.gap_bounds): a geometry whose bound reaches a threshold needs no
        # exact query (see _clear)
        self._bound_table = hand_bound_table(hand)
        oMg = self.state.geometry_data.oMg  # live views of the placements, current after update
        self._placements = [(oMg[g].translation, oMg[g].rotation) for g in self._all_geometries]
        self._obj_centre = tuple(float(v) for v in obj.placement.translation)
        self._obj_radius = 0.5 * float(obj.diameter)
        self.rejections: dict[str, int] = {}
        self._tip_radius = {f: hand.tip_radius(f) for f in hand.finger_names}
        # per (finger, palm rotation's bytes): the finger's sweep turned by it (see _simulate)
        self._rotated: dict[tuple[str, bytes], np.ndarray] = {}
        # per closing direction's bytes: the object's half-extent along it (see half_extent_along)
        self._extents: dict[bytes, float] = {}
        # what _configuration needs of the hand, read once
        self._neutral = hand.neutral()
        self._wrist_xyz, self._wrist_rot = widx[:3], widx[3:6]
        self._finger_q = [(f, hand.finger_q_index(f), float(sweeps[f].angles[0])) for f in hand.finger_names]
        self._q_lower, self._q_upper = hand.lower, hand.upper

    def _reject(self, why: str) -> None:
        self.rejections[why] = self.rejections.get(why, 0) + 1

    def wrist_rpy(self, R: np.ndarray) -> tuple[float, float, float] | None:
        """The wrist joint values for palm rotation R, or None outside their limits."""
        rpy = rpy_from_rotation(R)
        # np.allclose(rotation_from_rpy(*rpy), R, atol=1e-9) (rtol 1e-5), in scalar arithmetic
        back = rotation_from_rpy(*rpy).ravel().tolist()
        if not all(abs(a - b) <= 1e-9 + 1e-5 * abs(b) for a, b in zip(back, R.ravel().tolist(), strict=True)):
            return None
        for value, lo, hi in zip(rpy, self._rpy_lo, self._rpy_hi, strict=True):
            if value < lo or value > hi:
                return None
        return rpy

    def half_extent_along(self, direction: np.ndarray) -> float:
        """:func:`half_extent` of the postulated object along the unit ``direction`` (m),
        computed once per direction (bit for bit the same vector): the candidate frames share
        their closing axis across several approaches."""
        key = direction.tobytes()
        hit = self._extents.get(key)
        if hit is None:
            hit = self._extents[key] = half_extent(self.obj, direction)
        return hit

    def depth_for(self, extent: float) -> float | None:
        """Depth that puts the opposing fingertip straight under the centre when it touches:
        the palm-frame x of the opposing sweep's first sample within ``extent`` + r_f of the
        palm's x axis (None if its sweep never comes that close)."""
        sweep = self.sweeps[self.opposing]
        reach = extent + self.hand.tip_radius(self.opposing)
        inside = np.flatnonzero(np.hypot(sweep.points[:, 1], sweep.points[:, 2]) <= reach)
        return None if len(inside) == 0 else float(sweep.points[int(inside[0]), 0])

    def candidates(self) -> list[GraspCandidate]:
        """The best candidates, best first.

        Candidate orientations are simulated (landings, angle about the centre) from the least
        wrist rotation up, a group of equal rotations at a time; of those about the centre,
        the ``SCORED`` least-rotated that are collision-free are scored by ε; the best ε wins,
        and candidates within ``EPSILON_TIE`` (relative) of it count as equal, the least wrist
        rotation first. When none about the centre is collision-free, the collision-free one
        closest to it is returned alone (the best the hand can do; its ``about_centre`` is
        False). The orientations rotated more than the last one scored are never simulated:
        the choice is that of :meth:`candidates_eager`, which simulates them all first."""
        return self._choose(self._turn_groups())

    def candidates_eager(self) -> list[GraspCandidate]:
        """:meth:`candidates` with every orientation simulated before any is checked and
        scored (the plain version :meth:`candidates` is tested against)."""
        # every frame in one group, in candidate_frames' order (_choose sorts by turn within it)
        return self._choose([self._frames()])

    def _turn_groups(self) -> list[list[tuple[int, str, np.ndarray]]]:
        """The candidate frames ``(index, label, R)`` in groups of equal wrist rotation
        (:func:`palm_turn` rounded to 1e-6 rad), the least-rotated group first, each group in
        :func:`candidate_frames`' order."""
        groups: dict[float, list[tuple[int, str, np.ndarray]]] = {}
        for frame in self._frames():
            groups.setdefault(round(palm_turn(frame[2]), 6), []).append(frame)
        return [groups[turn] for turn in sorted(groups)]

    def _frames(self) -> list[tuple[int, str, np.ndarray]]:
        """The candidate frames ``(index, label, R)`` in :func:`candidate_frames`' order."""
        return [(i, label, R) for i, (label, R) in enumerate(candidate_frames(self.obj, self.vertical_only))]

    def _simulated(self, label: str, R: np.ndarray) -> GraspCandidate | None:
        """The candidate of one orientation at its best depth (None when it is rejected)."""
        rpy = self.wrist_rpy(R)
        if rpy is None:
            self._reject("wrist rotation out of its limits")
            return None
        extent = self.half_extent_along(R[:, 2])
        if 2.0 * extent / self.hand.hand_height >= MAX_D_OVER_H:
            self._reject("larger than the hand height across the grip")
            return None
        base = self.depth_for(extent)
        if base is None:
            self._reject("too small for the opposing finger's sweep")
            return None
        centre = np.asarray(self.obj.placement.translation, dtype=float)
        return self._best_depth(label, R, rpy, centre, base, extent)

    def _choose(self, groups: list[list[tuple[int, str, np.ndarray]]]) -> list[GraspCandidate]:
        """The choice of :meth:`candidates`, simulating ``groups`` of frames in turn until
        enough collision-free candidates about the centre are scored."""
        obj = self.obj
        # a sphere's grasps about its diameters are all alike (ε too, by symmetry): the first,
        # least-rotated one that is collision-free is the choice
        wanted = 1 if isinstance(obj, Sphere) else SCORED
        simulated: list[GraspCandidate] = []
        kept: list[GraspCandidate] = []
        about_count = 0
        for group in groups:
            fresh = [c for _, label, R in group if (c := self._simulated(label, R)) is not None]
            simulated.extend(fresh)
            about = [c for c in fresh if c.about_centre]
            about_count += len(about)
            about.sort(key=lambda c: (round(c.turn, 6), -c.angle_deg, c.label))
            for cand in about:
                if self._collision_free(cand):
                    kept.append(self._score(cand))
                    if len(kept) == wanted:
                        break
            if len(kept) == wanted:
                break
        if not kept:
            # no grasp about the centre is reachable: the one closest to it, the best the hand
            # can do (the end agent will judge it)
            if about_count < len(simulated):
                self._reject("contacts not about the centre")
            rest = sorted((c for c in simulated if not c.about_centre), key=lambda c: (-c.angle_deg, c.turn))
            for cand in rest:
                if self._collision_free(cand):
                    return [self._score(cand)]
            return []
        top = max(c.epsilon for c in kept)
        kept.sort(key=lambda c: (c.epsilon < (1.0 - EPSILON_TIE) * top, c.turn, -c.epsilon))
        return kept

    def _best_depth(
        self,
        label: str,
        R: np.ndarray,
        rpy: tuple[float, float, float],
        centre: np.ndarray,
        base: float,
        extent: float,
    ) -> GraspCandidate | None:
        """The depth, among ``base`` + ``DEPTH_OFFSETS`` (then refined), whose predicted
        contacts lie best about the centre (None when no depth lands every fingertip)."""
        best: GraspCandidate | None = None
        for offset in DEPTH_OFFSETS:
            cand = self._simulate(label, R, rpy, centre, base + offset, extent)
            if cand is not None and (best is None or cand.angle_deg > best.angle_deg):
                best = cand
            if best is not None and best.angle_deg >= GOOD_ENOUGH_ANGLE_DEG:
                return best
        if best is not None:
            for step in (-DEPTH_REFINE, DEPTH_REFINE):
                cand = self._simulate(label, R, rpy, centre, best.depth + step, extent)
                if cand is not None and cand.angle_deg > best.angle_deg:
                    best = cand
        return best

    def _simulate(
        self,
        label: str,
        R: np.ndarray,
        rpy: tuple[float, float, float],
        centre: np.ndarray,
        depth: float,
        extent: float,
    ) -> GraspCandidate | None:
        wrist = centre - R[:, 0] * depth
        if (wrist < self._xyz_lo).any() or (wrist > self._xyz_hi).any():
            self._reject("wrist position out of its limits")
            return None
        landings: dict[str, Landing] = {}
        key = R.tobytes()
        for finger in self.hand.finger_names:
            # landing(obj, sweep, r_f, R, wrist), the sweep turned by R once per orientation
            sweep = self.sweeps[finger]
            rotated = self._rotated.get((finger, key))
            if rotated is None:
                rotated = self._rotated[(finger, key)] = sweep.points @ R.T
            pts, gaps = rotated_sweep_gaps(self.obj, rotated, self._tip_radius[finger], wrist)
            hit = landing_from(self.obj, sweep, pts, gaps)
            if hit is None:
                self._reject("a fingertip misses the object")
                return None
            landings[finger] = hit
        others = [landings[f].point for f in landings if f != self.opposing]
        angle = diameter_angle_deg(centre, landings[self.opposing].point, others)
        return GraspCandidate(label, R, rpy, wrist, depth, extent, landings, angle, turn=palm_turn(R))

    def _configuration(
        self, c: GraspCandidate, wrist: np.ndarray, angles: dict[str, float] | None
    ) -> np.ndarray:
        """The hand at ``wrist`` turned as ``c``, each finger at ``angles`` (open when None)."""
        q = self._neutral.copy()
        q[self._wrist_xyz] = wrist
        q[self._wrist_rot] = c.wrist_rpy
        for finger, idx, open_angle in self._finger_q:
            q[idx] = open_angle if angles is None else angles[finger]
        out: np.ndarray = np.clip(q, self._q_lower, self._q_upper)
        return out

    def _clear(self, q: np.ndarray, threshold: float, skip_tips: bool) -> bool:
        """Whether every collision geometry of the hand at ``q`` (the fingertips skipped when
        asked) is at least ``threshold`` m from the postulated object. A geometry whose lower
        bound (:func:`~eos_svc.kinematics.gap_bounds.ball_gap_lower_bounds`) reaches the
        threshold needs no exact query (its exact gap is at least the bound)."""
        state = self.state
        state.update(q)
        state.geometry_data  # noqa: B018 -- brings the placements (and self._placements) up to date
        geometries = self._body_geometries if skip_tips else self._all_geometries
        bounds = ball_gap_lower_bounds(
            self._bound_table, self._placements, geometries, self._obj_centre, self._obj_radius
        )
        return all(lower >= threshold or self.scene.gap(state, gid) >= threshold for lower, gid in bounds)

    def pregrasp(self, c: GraspCandidate) -> tuple[np.ndarray, float] | None:
        """The collision-free pre-grasp wrist position (world, m) before ``c`` along its
        approach, and its stand-off (m): ``approach_distance``, lengthened by 1 cm up to 4
        times if needed; None when none is clear."""
        stand_off = self.params.approach_distance
        for _ in range(4):
            pre = c.wrist - stand_off * c.approach
            inside = np.all(pre >= self._xyz_lo) and np.all(pre <= self._xyz_hi)
            if inside and self._clear(self._configuration(c, pre, None), self.params.clearance, False):
                return pre, stand_off
            stand_off += 0.01
        return None

    def _collision_free(self, c: GraspCandidate) -> bool:
        pre = self.pregrasp(c)
        if pre is None:
            self._reject("no collision-free pre-grasp")
            return False
        start = pre[0]
        # the approach with the fingers open: every sample from the pre-grasp to the grasp
        for s in np.linspace(0.0, 1.0, APPROACH_SAMPLES + 1)[1:]:
            q = self._configuration(c, start + s * (c.wrist - start), None)
            if not self._clear(q, 0.5 * self.params.contact_tolerance, False):
                self._reject("the approach collides")
                return False
        # the closing: only the fingertips may touch, part of the way and at the landing
        hand = self.hand
        for fraction in (0.5, 1.0):
            angles = {}
            for finger in hand.finger_names:
                lo = float(self.sweeps[finger].angles[0])
                angles[finger] = lo + fraction * (c.landings[finger].angle - lo)
            if not self._clear(self._configuration(c, c.wrist, angles), 0.0, True):
                self._reject("a link or the palm touches before the fingertips")
                return False
        return True

    def _score(self, c: GraspCandidate) -> GraspCandidate:
        points = np.array([c.landings[f].point for f in self.hand.finger_names])
        normals = np.array([c.landings[f].normal for f in self.hand.finger_names])
        q = grasp_quality(
            points,
            normals,
            self.obj.placement.translation,
            self.friction,
            SCORE_EDGES,
            0.5 * self.obj.diameter,
        )
        return GraspCandidate(
            c.label,
            c.rotation,
            c.wrist_rpy,
            c.wrist,
            c.depth,
            c.extent,
            c.landings,
            c.angle_deg,
            epsilon=q.epsilon,
            turn=c.turn,
        )
