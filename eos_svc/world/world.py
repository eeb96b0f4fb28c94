"""The simulated hand and its world, as the grasp agents see and move it.

:class:`GraspWorld` holds the hand (Pinocchio), the scene (coal), the tactile
sensor and the run's random generator, and offers the few guarded motions the
agents make: a search move of the hand over a coverage lattice, a wrist step toward a target, a
finger closing step that stops at first touch. Agents keep what they *know* on
the board; the world is what they act on.

Conventions (hand3x3 and every hand the planner takes): world z up; the palm
frame's x axis is the approach direction and its z axis the closing direction
(the opposing finger below, the others above). The wrist keeps its rotation at
zero in the search and while EP1 explores (the palm frame is then the world
frame shifted by the wrist's translation, the hand approaching along +x);
grasp_points turns it to the chosen grasp's orientation. SI units. What depends
on the hand is derived from it:
:meth:`WorldParameters.for_hand` (grasp centre, search box, hand bound:
:mod:`eos_svc.world.parameters`), :func:`~eos_svc.agents.sweeps.build_sweeps`
(closing paths), :attr:`GraspWorld.probe` (which finger explores the object's top and bottom,
and at which angle: :mod:`eos_svc.world.probing`). The cheap lower bounds on hand–object
gaps that spare most exact coal queries are :mod:`eos_svc.kinematics.gap_bounds`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import coal
import numpy as np

from eos_svc.agents.sweeps import FingerSweep, build_sweeps, finger_link_geometries
from eos_svc.kinematics import HandModel, HandState, Scene, SurfaceObject, TactileSensor
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.gap_bounds import BOUND_MARGIN, ball_gap_lower_bounds, hand_bound_table
from eos_svc.kinematics.hand_cache import PerHandCache
from eos_svc.kinematics.hand_state import read_only
from eos_svc.world.coverage import SpaceFillingOrder, column_counts, wrist_columns
from eos_svc.world.parameters import WorldParameters
from eos_svc.world.probe_pose import probe_pose
from eos_svc.world.probing import ProbeChoice, ProbeOutcome, densify


@dataclass
class GraspWorld:
    """The hand, the object and the run's randomness; guarded motions for the agents."""

    hand: HandModel
    scene: Scene
    state: HandState
    sensor: TactileSensor
    rng: np.random.Generator
    params: WorldParameters = field(default_factory=WorldParameters)
    estimator: CurvatureEstimator = field(default_factory=CurvatureEstimator)
    sweeps: dict[str, FingerSweep] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.sweeps:
            self.sweeps = build_sweeps(self.hand, resolution=0.01)
        self._wrist_q = self.hand.wrist_q_index
        self._wrist_xyz = self._wrist_q[:3]  # the wrist's x, y, z joints' q indices
        self._grasp_centre = np.asarray(self.params.grasp_centre, dtype=float)
        self.version = 0  # bumped on every move; derived quantities are memoised per version
        self._memo: dict[object, Any] = {}
        # derived from the hand alone, once (see _HandDerived). self._bounds: a cheap lower bound
        # per hand geometry on its distance to the object (the object taken as its bounding
        # ball): a min over geometries skips the exact queries that cannot be the minimum (the
        # result is the same; see eos_svc.kinematics.gap_bounds). self._tip_bound serves
        # _closing_clear, self._palm_at_wrist_xyz _deferred_wrist_move.
        derived = _derived_for(self.hand, self.sweeps)
        self._links = derived.links
        self.probe = derived.probe
        self._bounds = derived.bounds
        self._palm_at_wrist_xyz = derived.palm_at_wrist_xyz
        self._angle_q = derived.angle_q
        self._finger_q = derived.finger_q
        self._tip_bound = derived.tip_bound
        # The object's bounding ball for the guarded motions' lower bounds. The object is fixed
        # for a world's lifetime (a plan never moves it); moving it with
        # scene.set_object_placement would need these refreshed (_refresh_object_bound).
        self._refresh_object_bound()
        # the search's lattice order, drawn from rng at the first search move (see search_step)
        self._search_order: SpaceFillingOrder | None = None
        self._search_columns = np.empty((0, 0, 2))

    def _refresh_object_bound(self) -> None:
        """Re-read the object's bounding ball (centre, m; radius, m) from the scene."""
        self._obj_centre = tuple(float(x) for x in self.scene.object.placement.translation)
        self._obj_radius = 0.5 * float(self.scene.object.diameter)

    # --- reading the world -------------------------------------------------------
    @property
    def obj(self) -> SurfaceObject:
        """The object."""
        return self.scene.object

    def wrist_position(self) -> np.ndarray:
        """World position of the wrist (= palm origin), m."""
        return self.state.q[self._wrist_xyz]

    def grasp_centre_world(self) -> np.ndarray:
        """World position of the grasp centre between the fingers, m."""
        translation, rotation = self.palm_views()  # the wrist may be turned
        out: np.ndarray = translation + rotation @ self._grasp_centre
        return out

    def palm_views(self) -> tuple[np.ndarray, np.ndarray]:
        """Live views of the palm frame's world translation (m) and rotation in the current
        state: they follow every move (reading ``data.oMf[i]`` from Python costs µs; do not
        modify them, copy what must outlive a move)."""
        return self.state.frame_views(self.hand.palm_frame_id)

    def object_gap_to_grasp_centre(self) -> float:
        """Distance from the grasp centre to the object surface, m (negative inside; memoised)."""
        memo = self._memo
        value = memo.get("gap")
        if value is None:
            value = memo["gap"] = self.scene.point_gap(self.grasp_centre_world())
        return value

    def located(self) -> bool:
        """The object is in the hand's envelope (see :class:`WorldParameters`)."""
        return self.object_gap_to_grasp_centre() <= self.params.envelope_radius

    def tip_distance(self, finger: str) -> float:
        """Signed fingertip–object distance, m (memoised per hand pose)."""
        memo = self._memo
        value = memo.get(finger)
        if value is None:
            value = memo[finger] = float(self.scene.contact(self.state, finger).distance)
        return value

    def touching(self, finger: str) -> bool:
        """Whether ``finger``'s tip touches the object."""
        return self.tip_distance(finger) <= self.params.contact_tolerance

    def hand_clearance(self) -> float:
        """Smallest distance between any hand geometry and the object, m (memoised).

        When the object is farther from the grasp centre than ``hand_bound`` no hand
        geometry can be near it; the lower bound (gap − hand_bound) is returned without
        a collision query.
        """
        memo = self._memo
        value = memo.get("clearance")
        if value is None:
            gap = self.object_gap_to_grasp_centre()
            if gap > self.params.hand_bound + self.params.clearance:
                value = gap - self.params.hand_bound
            else:
                value = self._min_gap(range(len(self._bounds)), math.inf)
            memo["clearance"] = value
        return value

    def hand_clear(self, threshold: float) -> bool:
        """``hand_clearance() >= threshold``, without the exact collision queries when the
        geometries' lower bounds (see :meth:`_min_gap`) already reach ``threshold``."""
        value = self._memo.get("clearance")
        if value is None:
            gap = self.object_gap_to_grasp_centre()
            if gap <= self.params.hand_bound + self.params.clearance:  # the exact case
                bounds = self._lower_bounds(range(len(self._bounds)))
                if min(bounds)[0] >= threshold:  # every exact gap ≥ its bound ≥ threshold
                    return True
                value = self._memo["clearance"] = self._min_of(bounds, math.inf)
            else:
                value = self.hand_clearance()
        return bool(value >= threshold)

    def finger_angle(self, finger: str) -> float:
        """The finger's (common) joint angle, rad (its first joint)."""
        return self.q_list()[self._angle_q[finger]]

    def q_list(self) -> list[float]:
        """The hand's configuration as a list of floats (memoised per hand pose; do not modify)."""
        memo = self._memo
        value = memo.get("q")
        if value is None:
            value = memo["q"] = self.state.q.tolist()
        return value

    def wrist_xyz(self) -> tuple[float, float, float]:
        """:meth:`wrist_position` as a tuple of floats (memoised per hand pose)."""
        memo = self._memo
        value = memo.get("wrist")
        if value is None:
            x, y, z = self.wrist_position().tolist()
            value = memo["wrist"] = (x, y, z)
        return value

    # --- moving it -----------------------------------------------------------------
    def set_q(self, q: np.ndarray) -> None:
        """Move the hand to ``q`` (validated by the hand model)."""
        self.state.update(q)
        self.version += 1
        self._memo.clear()

    def sync(self) -> None:
        """Forget memoised values after ``state`` was moved directly (prefer
        :meth:`direct_motion`, which cannot forget to)."""
        self.version += 1
        self._memo.clear()

    @contextlib.contextmanager
    def direct_motion(self) -> Iterator[HandState]:
        """``with world.direct_motion() as state:`` — move ``state`` directly inside (e.g. EP1's
        rolling QP integrates it); on leaving, normally or by an exception, the world forgets
        what it had memoised about the old pose."""
        try:
            yield self.state
        finally:
            self.sync()

    def search_step(self) -> tuple[str, float, bool]:
        """One search move: a sweep of the next column of the coverage plan in this run's
        seeded space-filling order (:mod:`eos_svc.world.coverage`): back to the box's rear
        (−x), across to the column (y, z), forward through the box (+x), each leg a guarded
        straight move (:meth:`guarded_wrist_move`) that stops where the object enters the
        envelope or short of a contact.

        Returns:
            (label of the column "(j, k)", length moved in m, blocked flag).
        """
        p = self.params
        if self._search_order is None:
            self._search_order = SpaceFillingOrder(column_counts(p), self.rng)
            self._search_columns = wrist_columns(p)
        if not self._search_order:  # every column swept: sweep them again
            self._search_order = SpaceFillingOrder(column_counts(p), self.rng)
        j, k = self._search_order.take()
        y, z = (float(v) for v in self._search_columns[j, k])
        x_lo, x_hi = p.search_box_lo[0], p.search_box_hi[0]
        moved = 0.0
        for leg in (
            (x_lo, *self.wrist_xyz()[1:]),
            (x_lo, y, z),
            (x_hi, y, z),
        ):
            length, blocked = self.guarded_wrist_move(np.array(leg), stop_when_located=True)
            moved += length
            if self.located():
                return f"({j}, {k})", moved, False
            if blocked:
                self._bumped()
                return f"({j}, {k})", moved, True
        return f"({j}, {k})", moved, False

    def _bumped(self) -> None:
        """After a bump: sweep next the column that puts the grasp centre's line nearest the
        point of the object the hand bumped into (the object is there)."""
        if not self._search_order:
            return
        order = self._search_order.pending()
        witness = np.asarray(self.scene.min_distance(self.state).point_object)
        cols = self._search_columns
        want = witness[1:] - np.asarray(self.params.grasp_centre)[1:]
        n = min(range(len(order)), key=lambda i: float(np.sum((cols[order[i]] - want) ** 2)))
        self._search_order.move_to_front(n)

    def guarded_wrist_move(self, target: np.ndarray, stop_when_located: bool = False) -> tuple[float, bool]:
        """Translate the wrist in a straight line toward ``target`` (world, m), guarded.

        Conservative advancement: each sub-step is at most the hand's clearance beyond
        ``params.clearance`` (a translation changes every hand–object distance by at most its
        length, so no sub-step can bring the hand closer than that) and, with
        ``stop_when_located``, at most the grasp centre's gap beyond the envelope (floored at
        0.5 mm). Stops when the object is located, when the hand is within 0.1 mm of the
        clearance (blocked) or at the target.

        Returns:
            (length moved in m, blocked flag).
        """
        p = self.params
        start = self.wrist_position().copy()
        delta = np.asarray(target, dtype=float) - start
        length = float(np.linalg.norm(delta))
        if length < 1e-12:
            return 0.0, False
        unit = delta / length
        q = self.state.q
        if self._palm_at_wrist_xyz:
            return self._deferred_wrist_move(q, start, unit, length, stop_when_located)
        travelled = 0.0
        for _ in range(500):
            if stop_when_located and self.located():
                return travelled, False
            clearance = self.exact_clearance()
            room = clearance - p.clearance
            if room < 1e-4:
                # touching distance: go on only if the move leads away from the object
                trial = min(1e-3, length - travelled)
                q[self._wrist_xyz] = start + unit * (travelled + trial)
                self.set_q(q)
                if self.exact_clearance() <= clearance:
                    q[self._wrist_xyz] = start + unit * travelled
                    self.set_q(q)
                    return travelled, True
                step = trial
            else:
                step = min(length - travelled, room)
            if stop_when_located:
                step = min(step, max(self.object_gap_to_grasp_centre() - p.envelope_radius, 5e-4))
            travelled += step
            q[self._wrist_xyz] = start + unit * travelled
            self.set_q(q)
            if travelled >= length - 1e-12:
                return travelled, False
        return travelled, True

    def _deferred_wrist_move(
        self, q: np.ndarray, start: np.ndarray, unit: np.ndarray, length: float, stop_when_located: bool
    ) -> tuple[float, bool]:
        """:meth:`guarded_wrist_move`'s loop (the same steps, the same result bit for bit) that
        moves the hand model only where a sub-step needs more than the grasp centre's gap.

        Far from the object a sub-step is fixed by the grasp centre's gap alone, and for a hand
        whose palm origin is the wrist's x, y, z joint values bit for bit
        (:func:`palm_origin_is_wrist_xyz`) that gap needs no forward kinematics: the grasp
        centre is ``wrist + R @ grasp_centre``, the palm's rotation ``R`` unchanged by a
        translation — exactly what :meth:`grasp_centre_world` computes after a move. The hand
        model is updated (:meth:`set_q`) only for an exact clearance, near touching and at the
        end, where it is left as the plain loop leaves it.
        """
        p = self.params
        wrist_xyz = self._wrist_xyz
        offset = self.palm_views()[1] @ self._grasp_centre  # the grasp centre from the palm origin
        far = p.clearance + 5e-3  # exact_clearance's threshold beyond the hand bound
        travelled = 0.0
        pending: np.ndarray | None = None  # the wrist position the hand model is not at yet
        gap = 0.0
        for _ in range(500):
            if pending is not None:
                gap = self.scene.point_gap(pending + offset)
                if (stop_when_located and gap <= p.envelope_radius) or gap - p.hand_bound <= far:
                    self.set_q(q)  # the hand model at q: the plain loop from here
                    pending = None
            if pending is None:
                if stop_when_located and self.located():
                    return travelled, False
                gap = self.object_gap_to_grasp_centre()
                clearance = self.exact_clearance()
            else:  # far and not located (checked above)
                clearance = gap - p.hand_bound
            room = clearance - p.clearance
            if room < 1e-4:
                # touching distance: go on only if the move leads away from the object
                trial = min(1e-3, length - travelled)
                q[wrist_xyz] = start + unit * (travelled + trial)
                self.set_q(q)
                if self.exact_clearance() <= clearance:
                    q[wrist_xyz] = start + unit * travelled
                    self.set_q(q)
                    return travelled, True
                step = trial
                gap = self.object_gap_to_grasp_centre()
            else:
                step = min(length - travelled, room)
            if stop_when_located:
                step = min(step, max(gap - p.envelope_radius, 5e-4))
            travelled += step
            pending = start + unit * travelled
            q[wrist_xyz] = pending
            if travelled >= length - 1e-12:
                self.set_q(q)
                return travelled, False
        if pending is not None:
            self.set_q(q)
        return travelled, True

    def guarded_probe(
        self, finger: str, start: np.ndarray, direction: np.ndarray, travel: float, angle: float
    ) -> ProbeOutcome:
        """Move ``finger``'s tip in a straight line from ``start`` along ``direction`` (world,
        m) for at most ``travel`` m, stopping at first touch (EP2's guarded move).

        The hand is placed with its wrist rotation at zero, ``finger`` at joint angle
        ``angle`` and every other finger opened, so that the tip's centre is at ``start``
        (backed off along ``−direction`` by up to 3 × 2 cm when the hand would not be clear
        there). Conservative advancement: each sub-step is at most the tip's gap beyond half
        the contact tolerance and the other geometries' gap beyond half the contact tolerance
        (a link may pass a face closer than ``clearance``: a straight finger's links ride 2 mm
        above the face its tip touches), so only the tip can touch, and it never pushes the
        object. The start's clearance is taken as the other geometries' exact minimum and the
        tip's exact gap (the first sub-step's bound of the others, exact); after that the others'
        exact gaps are queried only when their lower bound (the last exact value less the
        distance moved: :func:`_probe_floor_after`) does not already fix the sub-step (the same
        steps as querying them every sub-step).

        Returns:
            the outcome: touched (tip centre, sensed normal), missed or blocked (another part
            of the hand would touch first, or the wrist's limits), the last two with the
            tip-centre samples of the free path.
        """
        p = self.params
        hand = self.hand
        d = np.asarray(direction, dtype=float)
        d = d / math.sqrt(d.dot(d))  # = d / np.linalg.norm(d) (sqrt of the dot product)
        pose = probe_pose(hand, finger, angle)  # wrist rotation 0, the fingers set (kept per angle)
        q = self.state.q
        pose.apply(q)
        self.set_q(q)
        state = self.state
        offset = state.tip_position(finger) - self.wrist_position()
        xyz = self._wrist_xyz
        lo, hi = pose.wrist_lo, pose.wrist_hi
        start = np.asarray(start, dtype=float)
        tip_gid = hand.tip_geometry_id(finger)
        others = pose.others
        for back in (0.0, 0.02, 0.04, 0.06):
            wrist = start - back * d - offset
            wx, wy, wz = wrist.tolist()  # np.any(wrist < lo) or np.any(wrist > hi), in floats
            if wx < lo[0] or wy < lo[1] or wz < lo[2] or wx > hi[0] or wy > hi[1] or wz > hi[2]:
                return ProbeOutcome("blocked", finger, why="outside the wrist's workspace")
            q[xyz] = wrist
            self.set_q(q)
            # The hand's clearance as the other geometries' exact minimum and the tip's exact
            # gap: their minimum is exact_clearance's exact value (the same gaps), and where
            # exact_clearance takes its plain bound (gap − hand_bound > clearance + 5 mm) the
            # exact minimum is above the threshold too — the same decision; the first sub-step
            # below then has ``other`` without a query.
            others_gap = self._min_gap(others, math.inf)
            clearance = others_gap if tip_gid is None else min(self.scene.gap(state, tip_gid), others_gap)
            if clearance >= p.clearance:
                travel += back
                break
        else:
            return ProbeOutcome("blocked", finger, why="no clear start")
        tol = p.contact_tolerance
        half_tol = 0.5 * tol
        # the wrist's start and the direction as floats: each sub-step's wrist0 + d · travelled
        # in floats (the same products and sums numpy's would be), written item by item
        w0, w1, w2 = q[xyz].tolist()
        d0, d1, d2 = d.tolist()
        i0, i1, i2 = pose.wrist_xyz
        travelled = 0.0
        tip = state.tip_centre_view(finger)  # live view of the tip centre (world)
        free = [tip.copy()]
        contact_of = self.scene.contact
        # ``other`` at the start pose (exact), then a lower bound of it (_probe_floor_after)
        floor = others_gap - half_tol
        exact = True  # floor is the exact ``other`` of the current pose
        for _ in range(300):
            contact = contact_of(state, finger)  # = tip_distance's query (the pose is new)
            tip_gap = float(contact.distance)
            if tip_gap <= tol:
                reading = self.sensor.read(state, contact)
                M = state.data.oMf[hand.tip_frame_id(finger)]
                normal = -(M.rotation @ reading.normal_tip)
                return ProbeOutcome(
                    "touched", finger, centre=M.translation.copy(), normal=normal, travelled=travelled
                )
            room = travel - travelled
            tip_room = tip_gap - half_tol
            need = room if room <= tip_room else tip_room  # = min(room, tip_room)
            if floor >= need and floor >= 1e-5:
                # the other geometries can neither block nor limit this step (their gap, less
                # half the tolerance, is ≥ floor ≥ need): the step min(room, tip_room, other)
                # is need, without their exact queries
                step = need
            else:
                other = floor if exact else self._min_gap(others, math.inf) - half_tol
                if other < 1e-5:
                    return ProbeOutcome(
                        "blocked",
                        finger,
                        free=densify(np.array(free)),
                        travelled=travelled,
                        why="another part of the hand would touch first",
                    )
                step = min(room, tip_room, other)
                floor = other
            travelled += step
            q[i0], q[i1], q[i2] = w0 + d0 * travelled, w1 + d1 * travelled, w2 + d2 * travelled
            self.set_q(q)
            free.append(tip.copy())
            if travelled >= travel - 1e-12:
                break
            floor = _probe_floor_after(floor, step)
            exact = False
        return ProbeOutcome("missed", finger, free=densify(np.array(free)), travelled=travelled)

    def exact_clearance(self) -> float:
        """:meth:`hand_clearance`, exact whenever the object is within 5 mm of the hand's
        bound (the plain lower bound ``gap − hand_bound`` beyond that), m."""
        gap = self.object_gap_to_grasp_centre()
        if gap - self.params.hand_bound > self.params.clearance + 5e-3:
            return gap - self.params.hand_bound
        memo = self._memo
        value = memo.get("exact_clearance")
        if value is None:
            value = memo["exact_clearance"] = self._min_gap(range(len(self._bounds)), math.inf)
        return value

    def step_wrist_toward(self, target: np.ndarray, step: float) -> tuple[float, bool]:
        """Move the wrist up to ``step`` m toward ``target`` (world), guarded.

        Stops short (by bisection) where any hand geometry would come within half the
        contact tolerance of the object, so the hand never pushes the object.

        Returns:
            (distance left to the target in m, stopped-by-contact flag).
        """
        start = self.wrist_position()
        delta = np.asarray(target, dtype=float) - start
        dist = float(np.linalg.norm(delta))
        if dist < 1e-9:
            return 0.0, False
        move = min(step, dist)
        if self._palm_at_wrist_xyz:
            return self._deferred_step_toward(start, delta, dist, move)
        q0 = self.state.q
        q = q0.copy()
        q[self._wrist_xyz] = start + delta * (move / dist)
        self.set_q(q)
        if self.hand_clear(0.5 * self.params.contact_tolerance):
            return dist - move, False
        lo, hi = 0.0, 1.0  # fraction of the move that keeps the hand clear
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            q[self._wrist_xyz] = start + delta * (mid * move / dist)
            self.set_q(q)
            if self.hand_clear(0.5 * self.params.contact_tolerance):
                lo = mid
            else:
                hi = mid
        q[self._wrist_xyz] = start + delta * (lo * move / dist)
        self.set_q(q)
        return dist - lo * move, True

    def _deferred_step_toward(
        self, start: np.ndarray, delta: np.ndarray, dist: float, move: float
    ) -> tuple[float, bool]:
        """:meth:`step_wrist_toward`'s step and bisection (the same poses tried, the same result
        bit for bit) that moves the hand model only to the poses where
        :meth:`_clear_after_translation` cannot tell whether the hand is clear, and at the end."""
        threshold = 0.5 * self.params.contact_tolerance
        wrist_xyz = self._wrist_xyz
        q = self.state.q

        def clear_at(xyz: np.ndarray) -> bool:
            verdict = self._clear_after_translation(xyz, threshold)
            if verdict is None:
                q[wrist_xyz] = xyz
                self.set_q(q)
                verdict = self.hand_clear(threshold)
            return verdict

        xyz = start + delta * (move / dist)
        if clear_at(xyz):
            q[wrist_xyz] = xyz
            self.set_q(q)
            return dist - move, False
        lo, hi = 0.0, 1.0  # fraction of the move that keeps the hand clear
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            if clear_at(start + delta * (mid * move / dist)):
                lo = mid
            else:
                hi = mid
        q[wrist_xyz] = start + delta * (lo * move / dist)
        self.set_q(q)
        return dist - lo * move, True

    def _clear_after_translation(self, xyz: np.ndarray, threshold: float) -> bool | None:
        """:meth:`hand_clear` ``(threshold)`` with the wrist translated to ``xyz`` (world, m)
        from the current pose, when it is decided without moving the hand model; else None.

        For a hand whose palm origin is the wrist's x, y, z (:func:`palm_origin_is_wrist_xyz`)
        the grasp centre's gap there is the one :meth:`hand_clear` would read, bit for bit.
        Where the hand is near the object, the geometries' lower bounds at ``xyz`` are those of
        the current placements against the object's bounding ball shifted back by the
        translation (a translation moves every geometry by it, up to round-off:
        :data:`TRANSLATED_BOUND_SLACK` covers that); bounds reaching ``threshold`` prove the
        hand clear (True), as in :meth:`hand_clear`. Otherwise it takes the exact queries at
        ``xyz`` (None).
        """
        p = self.params
        translation, rotation = self.palm_views()
        gap = self.scene.point_gap(xyz + rotation @ self._grasp_centre)
        if gap > p.hand_bound + p.clearance:  # hand_clear's far case: the gap decides
            return bool(gap - p.hand_bound >= threshold)
        dx, dy, dz = (xyz - translation).tolist()  # the translation from the current pose
        ox, oy, oz = self._obj_centre
        bounds = self._lower_bounds(range(len(self._bounds)), (ox - dx, oy - dy, oz - dz))
        if min(bounds)[0] - TRANSLATED_BOUND_SLACK >= threshold:
            return True
        return None

    def close_finger_step(self, finger: str, dtheta: float) -> tuple[str, float]:
        """Close ``finger`` by ``dtheta`` rad per joint, stopping at first touch.

        Returns:
            (event, new angle): event is ``"moved"``, ``"touched"`` (the tip reached the
            object; the step was cut at the contact by regula falsi), ``"link"`` (another part
            of the finger touched first: not a precision grip) or ``"limit"`` (the joint
            limit was reached without touching).
        """
        tol = self.params.contact_tolerance
        idx = self._finger_q[finger]
        q0 = self.state.q
        f0 = self._memo.get(("closing", finger))  # the closing gap at q0, when known
        q1, at_limit = self.state.close_finger(finger, dtheta)
        self.set_q(q1)
        if self._closing_clear(finger):
            return ("limit" if at_limit else "moved"), self.finger_angle(finger)
        f1 = self._closing_gap(finger)
        if f0 is None:  # the closing gap at the start of the step (the bracket's other end)
            self.set_q(q0)
            f0 = self._closing_gap(finger)
        # First touch inside the step: regula falsi (Illinois) on the step fraction for the
        # closing gap, converging to a tip within [tol/2, tol] of the object (or a link just
        # touching), a handful of distance queries instead of a long bisection.
        a, fa, b, fb = 0.0, f0, 1.0, f1
        side = 0
        s_ok = 0.0
        for _ in range(40):
            frac = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
            q = q0.copy()
            q[idx] = q0[idx] + frac * (q1[idx] - q0[idx])
            self.set_q(q)
            fs = self._closing_gap(finger)
            if fs >= 0.0:
                s_ok = frac
                if fs <= 0.5 * tol:
                    break
                a, fa = frac, fs
                if side == 1:
                    fb *= 0.5
                side = 1
            else:
                b, fb = frac, fs
                if side == -1:
                    fa *= 0.5
                side = -1
            if b - a < 1e-9:
                break
        q = q0.copy()
        q[idx] = q0[idx] + s_ok * (q1[idx] - q0[idx])
        self.set_q(q)
        event = "touched" if self.tip_distance(finger) <= tol else "link"
        return event, self.finger_angle(finger)

    def _closing_gap(self, finger: str) -> float:
        """How far ``finger`` may still close before something touches (m): the tip's
        distance beyond half the contact tolerance, or a link's distance, whichever is less
        (memoised per hand pose)."""
        memo = self._memo
        key = ("closing", finger)
        value = memo.get(key)
        if value is None:
            tip = self.tip_distance(finger) - 0.5 * self.params.contact_tolerance
            value = memo[key] = self._min_gap(self._links[finger], tip)
        return value

    def _closing_clear(self, finger: str) -> bool:
        """``_closing_gap(finger) > 0``, proved without collision queries when the tip's and
        the links' lower bounds allow (the tip's: its centre's distance to the object's
        bounding ball, less its radius), else from the exact closing gap."""
        value = self._memo.get(("closing", finger))
        if value is None:
            tip = self._tip_bound.get(finger)
            if tip is not None:
                tx, ty, tz = self._frame_translation(tip[0]).tolist()
                ox, oy, oz = self._obj_centre
                dx, dy, dz = tx - ox, ty - oy, tz - oz
                lower = math.sqrt(dx * dx + dy * dy + dz * dz) - tip[1] - self._obj_radius - BOUND_MARGIN
                if lower > 0.5 * self.params.contact_tolerance and all(
                    bound > 0.0 for bound, _ in self._lower_bounds(self._links[finger])
                ):
                    return True
            value = self._closing_gap(finger)
        return bool(value > 0.0)

    def _frame_translation(self, frame_id: int) -> np.ndarray:
        """Live view of a frame's world translation in the current state (do not modify)."""
        return self.state.frame_views(frame_id)[0]

    def _min_gap(self, geometry_ids: Iterable[int], best: float) -> float:
        """min(best, exact gap of every geometry in ``geometry_ids``) (m), skipping the exact
        query of a geometry whose lower bound already reaches the minimum (the bound is the
        distance from the object's bounding ball to the geometry's primitive, see
        :func:`~eos_svc.kinematics.gap_bounds.shape_bound`; a skipped geometry's gap is ≥ its
        bound ≥ the minimum, so the result is the min over every geometry)."""
        return self._min_of(self._lower_bounds(geometry_ids), best)

    def _min_of(self, bounds: list[tuple[float, int]], best: float) -> float:
        """:meth:`_min_gap` from the geometries' ``(lower bound, id)`` (sorted in place)."""
        bounds.sort()
        state = self.state
        for lower, gid in bounds:
            if lower >= best:
                break
            gap = self.scene.gap(state, gid)
            if gap < best:
                best = gap
        return best

    def _lower_bounds(
        self, geometry_ids: Iterable[int], centre: tuple[float, float, float] | None = None
    ) -> list[tuple[float, int]]:
        """``(lower bound of the gap, id)`` of every geometry in ``geometry_ids`` (m), to the
        object's bounding ball (about ``centre`` instead of the object's, when given)."""
        state = self.state
        state.geometry_data  # noqa: B018 -- brings the placements (and the views below) up to date
        views = state.geometry_views()  # live views of every geometry's placement
        about = self._obj_centre if centre is None else centre
        return ball_gap_lower_bounds(self._bounds, views, geometry_ids, about, self._obj_radius)


class _HandDerived(NamedTuple):
    """What a world derives from its hand and sweeps alone (shared read-only by every plan)."""

    #: per finger: its link geometries (what stops a closing finger as "link")
    links: dict[str, list[int]]
    #: which finger explores the object's top and bottom, at which angle
    probe: ProbeChoice
    #: per hand geometry: how to bound its gap to the object's bounding ball from below
    bounds: list[tuple[int, Any, Any, float]]
    #: :func:`palm_origin_is_wrist_xyz`
    palm_at_wrist_xyz: bool
    #: per finger: the q index of its first joint (its angle)
    angle_q: dict[str, int]
    #: per finger: its joints' q indices (read-only)
    finger_q: dict[str, np.ndarray]
    #: per finger with a sphere tip: its tip frame id and radius (m)
    tip_bound: dict[str, tuple[int, float]]


#: per hand and sweeps: what a world derives from them alone (see _derived_for)
_DERIVED: PerHandCache[_HandDerived] = PerHandCache(keep=8)


def _derived_for(hand: HandModel, sweeps: dict[str, FingerSweep]) -> _HandDerived:
    """:class:`_HandDerived` of ``hand`` and ``sweeps``, computed once per hand and sweeps (they
    never change; every plan's world shares them read-only)."""
    return _DERIVED.get(
        (hand, sweeps),
        lambda: _HandDerived(
            links=finger_link_geometries(hand),
            probe=ProbeChoice.for_hand(hand, sweeps),
            bounds=hand_bound_table(hand),
            palm_at_wrist_xyz=palm_origin_is_wrist_xyz(hand),
            angle_q={f: hand.finger_joint_limits(f)[0][0] for f in hand.finger_names},
            finger_q={f: read_only(hand.finger_q_index(f)) for f in hand.finger_names},
            tip_bound=_sphere_tips(hand),
        ),
    )


def _sphere_tips(hand: HandModel) -> dict[str, tuple[int, float]]:
    """Per finger whose tip is a sphere (no tip geometry, or a coal sphere): its tip frame id and
    radius (m)."""
    geometries = hand.collision_model.geometryObjects
    tips: dict[str, tuple[int, float]] = {}
    for f in hand.finger_names:
        gid = hand.tip_geometry_id(f)
        if gid is None or isinstance(geometries[gid].geometry, coal.Sphere):
            tips[f] = (hand.tip_frame_id(f), float(hand.tip_radius(f)))
    return tips


def palm_origin_is_wrist_xyz(hand: HandModel) -> bool:
    """Whether the palm frame's world origin is the wrist's x, y, z joint values bit for bit in
    every configuration: the model's first six joints are the wrist (prismatic along x, y, z,
    then revolute about x, y, z, each the previous one's child, at identity placements) and the
    palm frame sits on the sixth at the identity. Pinocchio then composes every translation
    from exact products by 1 and 0 (a sum with a zero can only turn −0.0 into 0.0). Also
    requires every collision geometry to move with the wrist's translation."""
    model = hand.model
    wrist = [int(i) for i in hand.wrist_q_index]
    kinds = ("PX", "PY", "PZ", "RX", "RY", "RZ")
    if model.njoints < 7 or len(wrist) != 6:
        return False
    for j, kind in enumerate(kinds, start=1):
        joint = model.joints[j]
        if (
            joint.shortname() != f"JointModel{kind}"
            or joint.idx_q != wrist[j - 1]
            or model.parents[j] != j - 1
            or not model.jointPlacements[j].isIdentity()
        ):
            return False
    palm = model.frames[hand.palm_frame_id]
    # every collision geometry moves with the wrist's translation (hangs below its x, y, z
    # joints): what the translated bounds of the deferred moves assume of the whole hand
    moves_with_wrist = all(go.parentJoint >= 3 for go in hand.collision_model.geometryObjects)
    return bool(palm.parentJoint == 6 and palm.placement.isIdentity() and moves_with_wrist)


#: what the lower bounds of a translated hand (see GraspWorld._clear_after_translation) give up
#: for computing the placements as the current ones moved by the translation (m): their
#: round-off, ~1e-16 m on hand-sized coordinates
TRANSLATED_BOUND_SLACK = 1e-12


#: what a guarded probe's bound of the other geometries' gaps gives up per metre moved and in all
#: (m): coal's distances are exact to ~1e-15 m for primitives and to its GJK tolerance (1e-8 m,
#: relative) for curved shapes; the wrist's translation is exact to ~1e-16 m
_PROBE_FLOOR_SLACK = (1e-6, 1e-7)


def _probe_floor_after(floor: float, step: float) -> float:
    """A lower bound of every hand geometry's gap to the object (m, less a constant) after a
    pure wrist translation by ``step`` m from a pose where it was ``floor``: a translation
    changes each distance by at most its length (less the slack of the distance queries'
    accuracy, :data:`_PROBE_FLOOR_SLACK`). :meth:`GraspWorld.guarded_probe` skips the exact
    queries of the other geometries while this bound alone fixes its step."""
    per_metre, constant = _PROBE_FLOOR_SLACK
    return floor - step * (1.0 + per_metre) - constant
