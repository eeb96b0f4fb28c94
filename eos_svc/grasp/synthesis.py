"""Grasp synthesis on a postulated primitive (Miller, Knoop, Christensen, Allen, ICRA 2003).

Candidate palm orientations (:mod:`~eos_svc.grasp.frames`) at their best depth are simulated on
the *postulated* object (finger landings, :mod:`~eos_svc.grasp.landing`), kept when reachable,
about the centre, smaller than the hand (d/h < 1) and collision-free
(:mod:`~eos_svc.grasp.clearance`), and scored by ε (:mod:`~eos_svc.grasp.quality`); ties go to
the least wrist rotation. The rules: ``docs/planner.md`` (Grasp synthesis). SI units.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from eos_svc.grasp.candidate import GraspCandidate, diameter_angle_deg
from eos_svc.grasp.clearance import HandClearance
from eos_svc.grasp.frames import candidate_frames, palm_turn, rotation_from_rpy, rpy_from_rotation
from eos_svc.grasp.landing import sweep_landings
from eos_svc.grasp.quality import grasp_quality
from eos_svc.grasp.support import TouchSupport
from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.kinematics import HandModel
from eos_svc.objects import Sphere, SurfaceObject

if TYPE_CHECKING:
    from eos_svc.world.parameters import WorldParameters

#: cone edges of the ε that ranks candidates (the end agent judges with 8; 4 is ~10× faster)
SCORE_EDGES = 4
#: depth offsets tried, in order, about the depth that puts the opposing contact under the
#: centre (m); the best is refined by ±``DEPTH_REFINE``
DEPTH_OFFSETS = (0.0, -0.004, 0.004, -0.008, 0.008, -0.012, 0.012, -0.016, 0.016, -0.02, 0.02)
DEPTH_REFINE = 0.002
#: a depth whose predicted angle across the centre reaches this needs no other depth tried (deg)
GOOD_ENOUGH_ANGLE_DEG = 172.0
#: ε within this fraction of the best counts as equal (then the smaller wrist rotation wins)
EPSILON_TIE = 0.05
#: collision-free candidates about the centre scored by ε, the least-rotated first
SCORED = 4
#: ... on an approximate postulate, ranked by the touches' support first (:mod:`~eos_svc.grasp.support`)
SUPPORT_SCORED = 12
#: how far past a wrist joint's limit (rad) an angle still counts as at it: URDF limits are
#: written rounded (1.570796 for π/2), and a grasp from above needs a yaw of exactly π/2
LIMIT_SLACK = 1e-6
#: largest object across the grip, as a fraction of the hand height (paper §2.1: d/h < 1)
MAX_D_OVER_H = 1.0


class GraspSynthesis:
    """Candidate grasps of one hand (its closing sweeps, palm frame; world constants) on one
    postulated object, checked and scored by ε at ``friction`` μ. ``vertical_only``: the size is
    known along the vertical only; ``table_height`` (world z, m): a hand touching the table is
    rejected. ``support``: the touches of an approximate postulate, which then rank the candidates
    first (:mod:`~eos_svc.grasp.support`). :attr:`rejections` counts the rejected candidates per
    reason (in words).
    """

    def __init__(
        self,
        hand: HandModel,
        sweeps: dict[str, FingerSweep],
        params: WorldParameters,
        obj: SurfaceObject,
        friction: float,
        vertical_only: bool = False,
        table_height: float | None = None,
        support: TouchSupport | None = None,
    ) -> None:
        self.hand, self.sweeps, self.params, self.obj = hand, sweeps, params, obj
        self.friction = friction
        self.vertical_only = vertical_only
        self.opposing = hand.description.opposing_finger
        self.on_table = table_height is not None
        self.tip_radii = {f: hand.tip_radius(f) for f in hand.finger_names}
        self.clearance = HandClearance(hand, sweeps, params, obj, table_height)
        self.rejections: dict[str, int] = {}
        self.support = support

    def _reject(self, why: str) -> None:
        self.rejections[why] = self.rejections.get(why, 0) + 1

    def candidates(self) -> list[GraspCandidate]:
        """The best candidates, best first: orientations simulated from the least wrist rotation
        up; the ``SCORED`` least-rotated collision-free ones about the centre (one for a sphere)
        scored by ε, those within ``EPSILON_TIE`` of the best counted equal (least rotation
        first); with ``support``, the ``SUPPORT_SCORED`` least-rotated, ranked by the touches'
        support first. None about the centre: the collision-free one closest to it, alone."""
        wanted = 1 if isinstance(self.obj, Sphere) else (SCORED if self.support is None else SUPPORT_SCORED)
        simulated: list[GraspCandidate] = []
        kept: list[GraspCandidate] = []
        groups: dict[float, list[tuple[str, np.ndarray]]] = {}  # by wrist rotation, least first
        for label, R in candidate_frames(self.obj, self.vertical_only, self.on_table):
            groups.setdefault(round(palm_turn(R), 6), []).append((label, R))
        for group in (groups[turn] for turn in sorted(groups)):
            fresh = [c for label, R in group if (c := self._at_best_depth(label, R)) is not None]
            simulated += fresh
            for cand in sorted((c for c in fresh if c.about_centre), key=lambda c: (-c.angle_deg, c.label)):
                if self._collision_free(cand):
                    kept.append(self._scored(cand))
                    if len(kept) == wanted:
                        break
            if len(kept) == wanted:
                break
        if not kept:
            # no grasp about the centre is reachable (every orientation was simulated): the one
            # closest to it, the best the hand can do (the end agent will judge it)
            rest = sorted((c for c in simulated if not c.about_centre), key=lambda c: (-c.angle_deg, c.turn))
            if len(rest) > 0:
                self._reject("contacts not about the centre")
            return next(([self._scored(c)] for c in rest if self._collision_free(c)), [])
        if self.support is None:
            return _by_epsilon(kept)
        # the candidates with the most supported contacts first, each level by the ε rule
        counts = [self.support.rank(c, self.opposing) for c in kept]
        levels = sorted(set(counts), reverse=True)
        return [
            c for n in levels for c in _by_epsilon([k for k, m in zip(kept, counts, strict=True) if m == n])
        ]

    def score_frames(self, frames: Iterable[tuple[str, np.ndarray]]) -> list[GraspCandidate]:
        """Another sampler's ``(label, palm rotation)`` pairs, checked as :meth:`candidates` checks
        them and scored by ε, best first: the hook for grasp agents with a sampler of their own
        (``docs/extending.md``)."""
        kept = []
        for label, R in frames:
            cand = self._at_best_depth(label, R)
            if cand is not None and cand.about_centre and self._collision_free(cand):
                kept.append(self._scored(cand))
        kept.sort(key=lambda c: (-c.epsilon, c.turn))
        return kept

    def pregrasp(self, c: GraspCandidate) -> tuple[np.ndarray, float] | None:
        """The collision-free pre-grasp wrist position (world, m) before ``c`` along its
        approach and its stand-off (m), or None (:meth:`HandClearance.pregrasp`)."""
        return self.clearance.pregrasp(c)

    def wrist_rpy(self, R: np.ndarray) -> tuple[float, float, float] | None:
        """The wrist joint values for palm rotation ``R``, or None outside their limits (by more
        than :data:`LIMIT_SLACK`; within it, the limit)."""
        rpy = rpy_from_rotation(R)
        if not np.allclose(rotation_from_rpy(*rpy), R, atol=1e-9):
            return None
        widx = self.hand.wrist_q_index[3:6]
        lo, hi = self.hand.lower[widx], self.hand.upper[widx]
        a = np.asarray(rpy)
        if np.any(a < lo - LIMIT_SLACK) or np.any(a > hi + LIMIT_SLACK):
            return None
        # a limit written rounded in the URDF (1.570796 for π/2) admits the exact angle
        roll, pitch, yaw = (float(v) for v in np.clip(a, lo, hi))
        return roll, pitch, yaw

    def depth_for(self, extent: float) -> float | None:
        """Depth that puts the opposing fingertip straight under the centre when it touches:
        the palm-frame x of the opposing sweep's first sample within ``extent`` + r_f of the
        palm's x axis (None if its sweep never comes that close)."""
        sweep = self.sweeps[self.opposing]
        reach = extent + self.hand.tip_radius(self.opposing)
        inside = np.flatnonzero(np.hypot(sweep.points[:, 1], sweep.points[:, 2]) <= reach)
        return None if len(inside) == 0 else float(sweep.points[int(inside[0]), 0])

    def _at_best_depth(self, label: str, R: np.ndarray) -> GraspCandidate | None:
        """The candidate of orientation ``R`` at the depth, among the base depth +
        ``DEPTH_OFFSETS`` (then refined), whose predicted contacts lie best about the centre
        (None when it is rejected)."""
        rpy = self.wrist_rpy(R)
        if rpy is None:
            self._reject("wrist rotation out of its limits")
            return None
        extent = self.obj.half_extent(R[:, 2])
        if 2.0 * extent / self.hand.hand_height >= MAX_D_OVER_H:
            self._reject("larger than the hand height across the grip")
            return None
        base = self.depth_for(extent)
        if base is None:
            self._reject("too small for the opposing finger's sweep")
            return None
        best: GraspCandidate | None = None
        for offset in DEPTH_OFFSETS:
            cand = self._simulate(label, R, rpy, base + offset, extent)
            if cand is not None and (best is None or cand.angle_deg > best.angle_deg):
                best = cand
            if best is not None and best.angle_deg >= GOOD_ENOUGH_ANGLE_DEG:
                return best
        if best is not None:
            for step in (-DEPTH_REFINE, DEPTH_REFINE):
                cand = self._simulate(label, R, rpy, best.depth + step, extent)
                if cand is not None and cand.angle_deg > best.angle_deg:
                    best = cand
        return best

    def _simulate(
        self, label: str, R: np.ndarray, rpy: tuple[float, float, float], depth: float, extent: float
    ) -> GraspCandidate | None:
        """The candidate of orientation ``R`` at ``depth``: where each fingertip lands closing
        from open (None when the wrist cannot get there or a fingertip misses)."""
        centre = np.asarray(self.obj.placement.translation, dtype=float)
        wrist = centre - R[:, 0] * depth
        widx = self.hand.wrist_q_index[:3]
        if np.any(wrist < self.hand.lower[widx]) or np.any(wrist > self.hand.upper[widx]):
            self._reject("wrist position out of its limits")
            return None
        swept = sweep_landings(self.obj, self.sweeps, self.tip_radii, R, wrist)
        found = {f: landings.landing(0) for f, landings in swept.items()}  # closing from open
        landings = {f: hit for f, hit in found.items() if hit is not None}
        if len(landings) < len(found):
            self._reject("a fingertip misses the object")
            return None
        if self._open_gap(R, wrist) < self.params.clearance:
            # the open hand would come closer than the clearance (a parallel jaw opened hardly
            # wider than the object): its approach would stop short
            self._reject("an open fingertip passes closer than the clearance")
            return None
        others = [hit.point for f, hit in landings.items() if f != self.opposing]
        angle = diameter_angle_deg(centre, landings[self.opposing].point, others)
        return GraspCandidate(label, R, rpy, wrist, depth, extent, landings, angle, turn=palm_turn(R))

    def _open_gap(self, R: np.ndarray, wrist: np.ndarray) -> float:
        """The open fingertips' least gap to the object (m), the palm at ``wrist`` turned by ``R``."""
        names = self.hand.finger_names
        tips = np.array([R @ self.sweeps[f].points[0] + wrist for f in names])
        radii = np.array([self.tip_radii[f] for f in names])
        return float(np.min(self.obj.signed_distances(tips)[0] - radii))

    def _collision_free(self, c: GraspCandidate) -> bool:
        why = self.clearance.collision(c)
        if why is not None:
            self._reject(why)
        return why is None

    def _scored(self, c: GraspCandidate) -> GraspCandidate:
        """``c`` with the ε of its predicted contacts (``SCORE_EDGES`` cone edges, torques about
        the object's centre over its half diameter)."""
        points = np.array([hit.point for hit in c.landings.values()])
        normals = np.array([hit.normal for hit in c.landings.values()])
        obj = self.obj
        q = grasp_quality(
            points,
            normals,
            obj.placement.translation,
            self.friction,
            SCORE_EDGES,
            0.5 * obj.diameter,
            self.params.contact_patch_radius,
        )
        return dataclasses.replace(c, epsilon=q.epsilon)


def _by_epsilon(kept: list[GraspCandidate]) -> list[GraspCandidate]:
    """``kept`` best first: the best ε, and those within ``EPSILON_TIE`` (relative) of it as
    equal, the least wrist rotation first."""
    top = max(c.epsilon for c in kept)
    return sorted(kept, key=lambda c: (c.epsilon < (1.0 - EPSILON_TIE) * top, c.turn, -c.epsilon))
