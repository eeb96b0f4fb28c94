"""EP2's probes: one planned guarded probe, and the probes aimed at the faces a fit leaves open.

Once post_shape has fitted the object, a face no touch bounds (:mod:`eos_svc.shape.open_faces`)
is where the postulate's size is uncertain: the object may reach farther that way. Each open
face gets probes that separate the candidate extents (active touch):

a guarded probe straight onto the face along its inward normal, from beyond where it could be
(the fitted size doubled), with a finger whose tip leads that way: the straight top finger
(the opposing one for a face turned down) for faces the hand sees (normal toward −x or
sideways); for a face turned away from the hand (normal toward +x) the same finger *hooked*
(every joint at :data:`HOOK_ANGLE`: its tip curled back toward the hand, ahead of its links and
the palm), reaching around the object. A probe another part of the hand would end is
abandoned, as every guarded probe is; its alternatives follow (the other finger, a deeper
hook, points off the face's centre), and the first that touches ends the face's group. A hand
whose fingers cannot curl back (a parallel jaw's prismatic fingers) or reach round a long
object has one more way to such a face: the wrist turned a quarter turn about the vertical
(:data:`SIDE_TURN`), the hand beside the object and its fingers across the face, the tip moved
onto it from behind (tried after the hooks, within the wrist's yaw limits).

SI units: metres, radians.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from eos_svc.drivers.protocol import HandDriver

#: every joint of a hooked finger (rad): its tip points back toward the hand, ahead of its
#: links and the palm (hand3x3: from 0.9 rad the tip, not a link, meets a face turned away)
HOOK_ANGLE = 1.0
#: the hook angles tried, in order, when the one before cannot reach the face (rad)
HOOK_ANGLES = (HOOK_ANGLE, 1.3)
#: offset of the alternative probes from the face's centre, along its tangents (m)
OFFSET = 0.012
#: how far beyond the fitted face a targeted probe may find it, as a multiple of the fitted
#: half size (the object may be that much larger that way)
REACH = 2.0
#: the fractions of that reach tried, in order (a start the wrist cannot reach is skipped)
REACH_FRACTIONS = (1.0, 0.5, 0.25)
#: the least that reach (m)
MIN_REACH = 0.05
#: a face is turned away from the hand when its normal's x component exceeds this
AWAY = 0.3
#: the wrist's turn about the vertical, either way, of a probe from the side onto a face turned
#: away (rad): the fingers across the probe's direction
SIDE_TURN = 0.5 * np.pi
#: shifts of a side probe's start from the face's centre toward the hand (m)
SIDE_SHIFTS = (0.0, 0.012, 0.024)


@dataclass(frozen=True)
class Probe:
    """One planned guarded probe: which face, finger (at joint ``angle``, rad), start of the
    tip centre and direction (world), travel (m)."""

    face: str
    finger: str
    start: np.ndarray
    direction: np.ndarray
    travel: float
    angle: float
    group: int = -1  #: probes of one group (≥ 0) are alternatives: the first that touches ends it
    yaw: float = 0.0  #: the wrist's turn about the vertical during the probe (rad)


def front_probe(
    world: HandDriver,
    centre: np.ndarray,
    half: np.ndarray,
    dy: float,
    dz: float,
    standoff: float,
    group: int = -1,
) -> Probe:
    """A probe of the front along +x, ``(dy, dz)`` off the middle of the estimate (``centre``,
    ``half`` extents along the world axes, m), from ``standoff`` before it."""
    front = world.probe_finger("front")
    cx, cy, cz = centre.tolist()
    hx = float(half[0])
    start = np.array([cx - hx - standoff, cy + dy, cz + dz])
    direction, travel = np.array([1.0, 0.0, 0.0]), 2.0 * hx + 2.0 * standoff
    return Probe("front", front, start, direction, travel, world.probe.angles[front], group)


def side_probe(
    world: HandDriver,
    centre: np.ndarray,
    half: np.ndarray,
    sign: int,
    dx: float,
    standoff: float,
    group: int = -1,
) -> Probe:
    """A probe of a side along ``sign`` · y (from the other side), ``dx`` along x from the
    estimate's middle — in front of the widest section, the links trailing the tip toward −x —
    with the finger leading that way, straight (the front finger on a table)."""
    finger = world.context.side_fingers[sign] if world.table_height is None else world.probe_finger("front")
    cx, cy, cz = centre.tolist()
    hy = float(half[1])
    start = np.array([cx + dx, cy - sign * (hy + standoff), cz])
    direction = np.array([0.0, float(sign), 0.0])
    travel = 2.0 * hy + 2.0 * standoff
    return Probe("side", finger, start, direction, travel, world.probe.angles.get(finger, 0.0), group)


def top_probe(
    world: HandDriver, centre: np.ndarray, half: np.ndarray, dx: float, dy: float, standoff: float
) -> Probe:
    """A probe of the top along −z, ``(dx, dy)`` off the middle of the estimate (``centre``,
    ``half`` extents along the world axes, m), from ``standoff`` above it, the finger straight."""
    top = world.probe_finger("top")
    cx, cy, cz = centre.tolist()
    hz = float(half[2])
    start = np.array([cx + dx, cy + dy, cz + hz + standoff])
    return Probe("top", top, start, np.array([0.0, 0.0, -1.0]), 2.0 * hz + standoff, world.probe.angles[top])


def targeted_probes(
    world: HandDriver, faces: list[dict], standoff: float, label: str = "open", off_centre: bool = True
) -> list[Probe]:
    """The probes of the open ``faces`` (post_shape's ``open_faces``: centre, outward normal,
    half size), in order; ``standoff``: how far outside a surface a probe starts (m);
    ``label``: the face name their touches carry; ``off_centre``: with the alternatives off the
    face's centre (else on its centre line only)."""
    return [
        p for k, face in enumerate(faces) for p in face_probes(world, face, k, standoff, label, off_centre)
    ]


def face_probes(
    world: HandDriver, face: dict, group: int, standoff: float, label: str = "open", off_centre: bool = True
) -> Iterator[Probe]:
    """The probes of one open ``face`` (group ``group``), in order, made as they are asked for
    (active touch scores a face by its first probe alone); the rest as :func:`targeted_probes`."""
    probe = world.probe
    top, bottom = probe.finger("top"), probe.finger("bottom")
    centre = np.asarray(face["centre"], dtype=float)
    normal = np.asarray(face["normal"], dtype=float)
    away = normal[0] > AWAY
    first = bottom if normal[2] < -0.5 else top
    fingers = (first, bottom if first == top else top)
    angles = HOOK_ANGLES if away else (None,)
    tangents = _tangents(normal) if off_centre else ()
    # from as far out as the object may reach, nearer when the wrist cannot start there
    for fraction in REACH_FRACTIONS:
        reach = max(MIN_REACH, fraction * REACH * float(face["half"]))
        travel = 2.0 * reach + standoff
        offsets = (sign * OFFSET * t for t in tangents for sign in (1.0, -1.0))
        for offset in (np.zeros(3), *offsets):
            start = centre + offset + normal * (reach + standoff)
            for finger in fingers:
                for angle in angles:
                    a = probe.angles.get(finger, 0.0) if angle is None else angle
                    yield Probe(label, finger, start, -normal, travel, a, group=group)
    if away:
        yield from _side_probes(world, centre, normal, float(face["half"]), standoff, fingers, group, label)


def _side_probes(
    world: HandDriver,
    centre: np.ndarray,
    normal: np.ndarray,
    half: float,
    standoff: float,
    fingers: tuple[str, str],
    group: int,
    label: str = "open",
) -> list[Probe]:
    """Probes of a face turned away (outward ``normal``, fitted ``half`` size, m) with the wrist
    turned :data:`SIDE_TURN` either way about the vertical (within its yaw limits): the fingers
    point across the probe's direction, so the hand stays beside the object while the tip moves
    onto the face from behind it; each finger straight, from the reaches of
    :data:`REACH_FRACTIONS`, at the face's centre and :data:`SIDE_SHIFTS` toward the hand (the
    finger's base, wider than its tip, then passes beside the face); ``label``: the face name
    their touches carry."""
    hand = world.hand
    yaw_q = hand.wrist_q_index[5]
    heading = float(np.arctan2(normal[1], normal[0]))
    lo, hi = float(hand.lower[yaw_q]), float(hand.upper[yaw_q])
    # within the limits (a limit that rounds a quarter turn, as hand3x3's 1.570796, is taken)
    yaws = [
        min(max(y, lo), hi) for y in (heading + SIDE_TURN, heading - SIDE_TURN) if lo - 1e-3 <= y <= hi + 1e-3
    ]
    out = []
    for fraction in REACH_FRACTIONS:
        reach = max(MIN_REACH, fraction * REACH * half)
        for yaw in yaws:
            toward_hand = -np.array([np.cos(yaw), np.sin(yaw), 0.0])  # the fingers point away from it
            for shift in SIDE_SHIFTS:
                start = centre + normal * (reach + standoff) + shift * toward_hand
                travel = 2.0 * reach + standoff
                for finger in fingers:
                    angle = world.probe.angles.get(finger, 0.0)
                    out.append(Probe(label, finger, start, -normal, travel, angle, group, yaw))
    return out


def _tangents(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents of a face of unit ``normal``: the horizontal one (or x when the face
    is level) and the one across it."""
    n0, n1, n2 = (float(c) for c in normal)
    t1 = np.array([0.0 - n1, n0, 0.0])  # (0, 0, 1) × normal
    if float(np.linalg.norm(t1)) < 1e-6:
        t1 = np.array([1.0, 0.0, 0.0])
    t1 = t1 / np.linalg.norm(t1)
    a0, a1, a2 = (float(c) for c in t1)
    # normal × t1, written out (np.cross's set-up costs ten times the arithmetic on 3-vectors)
    return t1, np.array([n1 * a2 - n2 * a1, n2 * a0 - n0 * a2, n0 * a1 - n1 * a0])
