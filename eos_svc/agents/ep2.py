"""ep2: the exploratory procedure EP2 as an agent — guarded probes of more of the surface.

EP1 feels the curvature at one contact; EP2 (Charlebois, Gupta and Payandeh, ICRA 1996) gathers
more of the surface. Each action is a round of guarded probes
(:func:`~eos_svc.world.probe_motion.guarded_probe`): a fingertip moves straight toward the
object and stops at first touch (a point and a noisy normal); a probe that touches nothing tells
where the object is not. An **active round** (:mod:`eos_svc.agents.probe_choice`) probes the
lines where post_shape's candidates disagree most; a **round over the whole surface** (no line
to probe, or after :data:`MAX_ACTIVE_ROUNDS`) probes the front, sides, top and bottom around
the current estimate — the faces the fit leaves open first — and slides over the top until the
tip drops over an edge. On a table every probe is the opposing finger's and none comes from
below. The detail is in docs/planner.md.

Opportunistic sub-rating: right after post_shape asked for the surface (``needs: "surface"``),
1 − confidence (floor :data:`RATING_FLOOR`); 0 after :data:`MAX_ROUNDS` whole-surface rounds.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.probe_choice import next_probes, seed_probes
from eos_svc.agents.probe_plan import Probe, front_probe, side_probe, targeted_probes, top_probe
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys

if TYPE_CHECKING:
    from eos_svc.kinematics import HandModel

#: most EP2 rounds over the whole surface in one plan
MAX_ROUNDS = 5
#: most active-touch rounds in one plan
MAX_ACTIVE_ROUNDS = 8
#: most lines an active-touch round probes
ROUND_PROBES = 2
#: the most informative lines an active-touch round ranks (tried in order while lines are blocked)
RANKED_LINES = 12
#: lowest opportunistic sub-rating while post_shape asks for the surface
RATING_FLOOR = 0.05
#: how far outside the estimated surface a probe starts (m)
STANDOFF = 0.03
#: step of a slide over the top (m): below the fingertip's radius less its links' (so that
#: over an edge some step lands the tip on the edge before a link touches the face)
SLIDE_STEP = 0.003
#: most steps of one slide
SLIDE_STEPS = 30
#: a slide keeps the contact of every this many steps (and its last, on the edge)
SLIDE_KEEP = 6
#: most steps of a slide toward an open face
MAX_SLIDE_STEPS = 90
#: on a table: how far back from the front face the scan from above reaches (m), in how many rows
SCAN_DEPTH = 0.16
SCAN_ROWS = 7


def estimate_box(board: Board) -> tuple[np.ndarray, np.ndarray] | None:
    """(centre, half extents along x, y, z) of the object as known now (world, m): the postulate's
    bounds, else from EP1's top and bottom and the approach point, as deep and wide as high."""
    shape = board.get(keys.SHAPE) or {}
    bounds = shape.get("bounds")
    if bounds is not None:
        lo, hi = np.asarray(bounds[0], dtype=float), np.asarray(bounds[1], dtype=float)
        return 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 0.005)
    contacts = board.get(keys.EP1_CONTACT, {})
    if "top" not in contacts or "bottom" not in contacts:
        return None
    top, bottom = np.asarray(contacts["top"]["point"]), np.asarray(contacts["bottom"]["point"])
    half = max(0.5 * float(top[2] - bottom[2]), 0.005)
    centre = 0.5 * (top + bottom)
    approach = board.get(keys.APPROACH)
    if approach is not None:
        centre[0] = float(approach["point"][0]) + half
    return centre, np.array([half, half, half])


def touch_entry(hand: HandModel, face: str, finger: str, centre: np.ndarray, normal: np.ndarray) -> dict:
    """One entry of ``ep2_touches``: the ``face`` probed, the ``finger``, its tip ``centre`` at the
    touch (world, m) and the sensed outward ``normal``, the tip's radius (m)."""
    return {
        "face": face,
        "finger": finger,
        "centre": np.asarray(centre).round(7).tolist(),
        "normal": np.asarray(normal).round(6).tolist(),
        "radius": hand.tip_radius(finger),
    }


class EP2Agent(GraspAgent):
    """Probes the object's front, sides, top and bottom with guarded fingertip moves."""

    reads = frozenset({keys.SHAPE, keys.EP1_CONTACT, keys.APPROACH, keys.EP2_TOUCHES, keys.EP2_FREE})
    writes = frozenset({keys.EP2_TOUCHES, keys.EP2_FREE, keys.EP2_RUNS})

    def __init__(self, default: float, world: HandDriver) -> None:
        super().__init__("ep2", (INFO,), default, world)
        self.rounds = 0  # rounds over the whole surface
        self.active_rounds = 0

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = board.get(keys.SHAPE)
        if shape is None or shape.get("needs") != "surface" or self.rounds >= MAX_ROUNDS:
            return 0.0
        if not (ctx.changed(keys.SHAPE) or ctx.last_agent == "post_shape"):  # it has pondered what EP2 felt
            return 0.0
        return max(RATING_FLOOR, min(1.0, 1.0 - float(shape["confidence"])))

    def plan_round(self, centre: np.ndarray, half: np.ndarray) -> list[Probe]:
        """The probes of a round over the whole surface around the estimate (docs/planner.md)."""
        world = self.world
        bottom = world.probe_finger("bottom")
        straight = world.probe.angles
        rng = world.rng
        f = (lambda base: base) if self.rounds == 0 else (lambda base: base * float(rng.uniform(0.6, 1.2)))
        cx, cy, cz = centre.tolist()
        hx, hy, hz = half.tolist()
        ez = np.array([0.0, 0.0, 1.0])
        probes: list[Probe] = []
        # front: along +x at the centre and off it
        for dy, dz in (
            (0.0, 0.0),
            (0.0, f(0.5) * hz),
            (0.0, -f(0.5) * hz),
            (f(0.5) * hy, 0.0),
            (-f(0.5) * hy, 0.0),
        ):
            probes.append(front_probe(world, centre, half, dy, dz, STANDOFF))
        # sides: along +y (from −y) and −y (from +y), the leading finger of each, straight; in
        # front of the widest section (the links trail the tip toward −x)
        for sign in (+1, -1):
            for dx in (-f(0.25) * hx, -f(0.6) * hx):
                probes.append(side_probe(world, centre, half, sign, dx, STANDOFF))
        # top: along −z (straight finger, its links trailing toward −x: in front of the apex);
        # bottom: along +z with the opposing finger
        for dx, dy in ((-f(0.25) * hx, f(0.6) * hy), (-f(0.25) * hx, -f(0.6) * hy)):
            probes.append(top_probe(world, centre, half, dx, dy, STANDOFF))
        for dx in () if world.support_height is not None else (-f(0.4) * hx,):  # none under a support
            start = np.array([cx + dx, cy, cz - hz - STANDOFF])
            probes.append(Probe("bottom", bottom, start, ez, 2.0 * hz + STANDOFF, straight[bottom]))
        if world.table_height is not None:
            probes += self.table_scan(centre, half, f)
        return probes

    def table_scan(self, centre: np.ndarray, half: np.ndarray, f: Callable[[float], float]) -> list[Probe]:
        """On a table, probes straight down on a grid from the front face back :data:`SCAN_DEPTH` m
        (or four half extents) and across the width, the finger opened to its limit: a height map
        reaching the back the other probes cannot."""
        world = self.world
        finger = world.probe_finger("top")
        cx, cy, cz = centre.tolist()
        hx, hy, hz = half.tolist()
        depth = max(SCAN_DEPTH, 4.0 * hx)
        top = cz + hz + STANDOFF
        travel = top - float(world.table_height)  # type: ignore[arg-type]
        # the opposing finger opened to its limit: its tip below its links, which rise behind it
        opened = float(world.hand.lower[world.hand.finger_q_index(finger)].max())
        out = []
        for x in np.linspace(cx - hx, cx - hx + depth, SCAN_ROWS)[1:]:
            for dy in (-f(0.5) * hy, 0.0, f(0.5) * hy):
                start = np.array([x, cy + dy, top])
                out.append(Probe("top", finger, start, np.array([0.0, 0.0, -1.0]), travel, opened))
        return out

    def slide_plan(self, board: Board, faces: list[dict]) -> list[tuple[np.ndarray, int]]:
        """(horizontal axis, most steps) of each slide: :meth:`slide_axes`, or toward each open face
        with a horizontal normal, far enough to pass it."""
        if not faces:
            return [(axis, SLIDE_STEPS) for axis in self.slide_axes(board)]
        out = []
        for face in faces:
            n = np.asarray(face["normal"], dtype=float)
            h = np.array([n[0], n[1], 0.0])
            norm = float(np.linalg.norm(h))
            if norm > 0.5:
                steps = min(MAX_SLIDE_STEPS, SLIDE_STEPS + int(4.0 * float(face["half"]) / SLIDE_STEP))
                out.append((h / norm, steps))
        return out

    def slide(
        self, start: np.ndarray, axis: np.ndarray, steps: int = SLIDE_STEPS
    ) -> tuple[list[tuple[np.ndarray, np.ndarray]], list[np.ndarray]]:
        """Drag the top finger from the tip centre ``start`` along the horizontal ``axis``: every
        SLIDE_STEP a guarded probe down from 2 mm above the last contact. Returns the contacts
        (tip centre, sensed normal) up to where the tip dropped by more than a step (an edge),
        and the free tip path of the probe that ended the slide."""
        world = self.world
        finger = world.probe_finger("top")
        angle = world.probe.angles[finger]
        out: list[tuple[np.ndarray, np.ndarray]] = []
        beyond: list[np.ndarray] = []
        last: tuple[np.ndarray, np.ndarray] | None = None
        z = float(start[2])
        for k in range(1, steps + 1):
            p = start + axis * (k * SLIDE_STEP)
            p[2] = z + 0.002
            outcome = world.guarded_probe(
                finger, p, np.array([0.0, 0.0, -1.0]), 0.002 + 4 * SLIDE_STEP, angle
            )
            if outcome.event != "touched":
                beyond = [] if outcome.free is None else list(outcome.free)
                break
            assert outcome.centre is not None and outcome.normal is not None
            last = (outcome.centre, outcome.normal)
            if k % SLIDE_KEEP == 0:
                out.append(last)  # every SLIDE_KEEP-th step (and the last, below)
                last = None
            if z - float(outcome.centre[2]) > SLIDE_STEP:
                break  # dropped over an edge
            z = float(outcome.centre[2])
        if last is not None:
            out.append(last)
        return out, beyond

    @staticmethod
    def slide_axes(board: Board) -> list[np.ndarray]:
        """Horizontal directions to slide along: +x and ±y, or the oriented postulate's own
        horizontal axes both ways (a slide then crosses the edge it runs toward)."""
        shape = board.get(keys.SHAPE) or {}
        axes = []
        if shape.get("object") is not None and shape.get("pose_known"):
            R = pin.rpy.rpyToMatrix(*(float(a) for a in shape["object"]["rpy"]))
            for k in range(3):
                h = np.array([R[0, k], R[1, k], 0.0])
                n = float(np.linalg.norm(h))
                if n > 0.5:
                    axes.extend([h / n, -h / n])
        return axes or [np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])]

    def active_plan(self, board: Board, estimate: tuple[np.ndarray, np.ndarray]) -> Sequence[Iterable[Probe]]:
        """This round's active-touch lines, each its alternative probes
        (:mod:`eos_svc.agents.probe_choice`): the seed probes first (off a table), then the most
        informative lines while candidates and active rounds remain; none otherwise."""
        world = self.world
        if self.active_rounds == 0 and keys.EP2_TOUCHES not in board and world.table_height is None:
            return [seed_probes(world, *estimate, STANDOFF)]
        candidates = (board.get(keys.SHAPE) or {}).get("candidates") or []
        if not candidates or self.active_rounds >= MAX_ACTIVE_ROUNDS:
            return []
        return next_probes(world, candidates, estimate, RANKED_LINES, STANDOFF)

    def run_lines(
        self,
        lines: Sequence[Iterable[Probe]],
        touches: list[dict],
        free: list[list[float]],
        counts: dict[str, int],
    ) -> tuple[int, int]:
        """Run the ``lines`` in order until ROUND_PROBES of them are answered (a touch, or a
        whole travel free): a line the hand cannot probe (every alternative blocked) gives way
        to the next. (missed, blocked)."""
        missed = blocked = answered = 0
        for line in lines:
            felt = sum(counts.values())
            m, b = self.run_probes(line, touches, free, counts, miss_answers=True)
            missed, blocked = missed + m, blocked + b
            answered += sum(counts.values()) > felt or m > 0
            if answered >= ROUND_PROBES:
                break
        return missed, blocked

    def run_probes(
        self,
        probes: Iterable[Probe],
        touches: list[dict],
        free: list[list[float]],
        counts: dict[str, int],
        miss_answers: bool = False,
    ) -> tuple[int, int]:
        """Run ``probes`` (skipping a group's alternatives once one touched, or with
        ``miss_answers`` missed), adding to ``touches``, ``free`` and ``counts``; (missed, blocked)."""
        world = self.world
        missed = blocked = 0
        answered: set[int] = set()  # groups of alternatives already answered by a touch
        for probe in probes:
            if probe.group in answered:
                continue
            outcome = world.guarded_probe(
                probe.finger, probe.start, probe.direction, probe.travel, probe.angle, probe.yaw
            )
            if outcome.event == "touched":
                assert outcome.centre is not None and outcome.normal is not None
                touches.append(
                    touch_entry(world.hand, probe.face, probe.finger, outcome.centre, outcome.normal)
                )
                counts[probe.face] = counts.get(probe.face, 0) + 1
                if probe.group >= 0:
                    answered.add(probe.group)
            else:
                if outcome.free is not None:
                    r = world.hand.tip_radius(probe.finger)
                    free.extend([*row, r] for row in np.asarray(outcome.free).round(7).tolist())
                missed += outcome.event == "missed"
                blocked += outcome.event == "blocked"
                if miss_answers and outcome.event == "missed" and probe.group >= 0:
                    answered.add(probe.group)
        return missed, blocked

    def _done(
        self,
        board: Board,
        touches: list[dict],
        free: list,
        counts: dict[str, int],
        missed: int,
        blocked: int,
        what: str,
    ) -> ActionResult:
        board.set(keys.EP2_TOUCHES, touches)
        board.set(keys.EP2_FREE, free)
        board.set(keys.EP2_RUNS, self.rounds)
        felt = ", ".join(f"{face} {n}" for face, n in counts.items()) or "nothing"
        return ActionResult(
            Outcome.PROGRESS,
            f"EP2 {what}: guarded probes touched {sum(counts.values())} ({felt}), "
            f"missed {missed}, blocked {blocked}; {len(touches)} contacts in all",
        )

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        estimate = estimate_box(board)
        if estimate is None:
            return ActionResult(
                Outcome.CANNOT_ACT, "no estimate of the object to plan probes around yet (EP1 feels it first)"
            )
        world = self.world
        touches = list(board.get(keys.EP2_TOUCHES, []))
        free = list(board.get(keys.EP2_FREE, []))
        counts: dict[str, int] = {}
        # active touch where the candidates disagree most; else (or if nothing answered) a whole round
        active = self.active_plan(board, estimate)
        if active:
            missed, blocked = self.run_lines(active, touches, free, counts)
            if counts or missed:
                self.active_rounds += 1
                return self._done(
                    board, touches, free, counts, missed, blocked, f"active round {self.active_rounds}"
                )
        faces = (board.get(keys.SHAPE) or {}).get("open_faces") or []
        # the faces a fit leaves open first, the whole surface only when none of them is felt
        planned = targeted_probes(world, faces, STANDOFF) if faces else self.plan_round(*estimate)
        missed, blocked = self.run_probes(planned, touches, free, counts)
        if faces and not counts:
            more_missed, more_blocked = self.run_probes(self.plan_round(*estimate), touches, free, counts)
            missed, blocked = missed + more_missed, blocked + more_blocked
        # slides over the top from its highest touch, until the tip drops over an edge
        tops = [np.asarray(t["centre"], dtype=float) for t in touches if t["face"] in ("top", "slide")]
        top = board.get(keys.EP1_CONTACT, {}).get("top")
        if top is not None:  # EP1's top contact, as its tip's centre
            tops.append(
                np.asarray(top["point"]) + world.hand.tip_radius(top["finger"]) * np.asarray(top["normal"])
            )
        if tops:
            highest = max(tops, key=lambda c: c[2])
            for axis, steps in self.slide_plan(board, faces):
                # toward an open face: on from the top touch farthest that way
                start = highest if steps == SLIDE_STEPS else max(tops, key=lambda c: float(np.dot(c, axis)))
                slid, beyond = self.slide(start, axis, steps)
                for centre, normal in slid:
                    touches.append(
                        touch_entry(world.hand, "slide", world.probe_finger("top"), centre, normal)
                    )
                    counts["slide"] = counts.get("slide", 0) + 1
                r = world.hand.tip_radius(world.probe_finger("top"))
                free.extend([*np.asarray(p).round(7).tolist(), r] for p in beyond)
        self.rounds += 1
        return self._done(board, touches, free, counts, missed, blocked, f"round {self.rounds}")
