"""EP2's probes: one planned guarded probe, and the probes aimed at the faces a fit leaves open.

Once post_shape has fitted the object, a face no touch bounds (:mod:`eos_svc.shape.open_faces`)
is where the postulate's size is uncertain: the object may reach farther that way. Each open
face gets probes that separate the candidate extents (active touch):

one guarded probe straight onto the face along its inward normal, from beyond where it could
be (the fitted size doubled), with a finger whose tip leads that way: the straight top finger
(the opposing one for a face turned down) for faces the hand sees (normal toward −x or
sideways); for a face turned away from the hand (normal toward +x) the same finger *hooked*
(every joint at :data:`HOOK_ANGLE`: its tip curled back toward the hand, ahead of its links and
the palm), reaching around the object. A probe another part of the hand would end is
abandoned, as every guarded probe is.

SI units: metres, radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eos_svc.world.world import GraspWorld

#: every joint of a hooked finger (rad): its tip points back toward the hand, ahead of its
#: links and the palm (hand3x3: from 0.9 rad the tip, not a link, meets a face turned away)
HOOK_ANGLE = 1.0
#: how far beyond the fitted face a targeted probe may find it, as a multiple of the fitted
#: half size (the object may be that much larger that way)
REACH = 2.0
#: the least that reach (m)
MIN_REACH = 0.05
#: a face is turned away from the hand when its normal's x component exceeds this
AWAY = 0.3


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


def targeted_probes(world: GraspWorld, faces: list[dict], standoff: float) -> list[Probe]:
    """The probes of the open ``faces`` (post_shape's ``open_faces``: centre, outward normal,
    half size), in order; ``standoff``: how far outside a surface a probe starts (m)."""
    probe = world.probe
    top, bottom = probe.finger("top"), probe.finger("bottom")
    probes: list[Probe] = []
    for face in faces:
        centre = np.asarray(face["centre"], dtype=float)
        normal = np.asarray(face["normal"], dtype=float)
        reach = max(MIN_REACH, REACH * float(face["half"]))
        start = centre + normal * (reach + standoff)
        travel = 2.0 * reach + standoff
        finger = bottom if normal[2] < -0.5 else top
        angle = HOOK_ANGLE if normal[0] > AWAY else probe.angles.get(finger, 0.0)
        probes.append(Probe("open", finger, start, -normal, travel, angle))
    return probes
