"""EP2's active touch: which probes next — where the candidate postulates disagree most.

post_shape leaves, with a postulate it does not trust yet, its ``candidates``: the likeliest
classes with their fits and sigma steps (:class:`~eos_svc.shape.probe_information.Candidate`).
The probes the hand can make are lines onto the postulate's world-axis bounds: onto each of
its six faces (none from below on a table), at the face's centre and at ±:data:`OFFSET` of
its half sizes along both tangents, each line a group of executable alternatives (finger,
hook, start: :func:`~eos_svc.agents.probe_plan.targeted_probes`). :func:`next_probes` — the
one place that chooses where EP2 touches next — predicts, for the first probe of each group,
how far its tip travels under every candidate, and takes the groups of largest expected
information, each given the ones before (:func:`~eos_svc.shape.probe_information.choose`):
where the competing classes' surfaces differ most (a box's corner against a cylinder's side,
a capsule's dome against a cylinder's flat end) or where the fit's size and pose uncertainty,
projected on the probe's line, is largest.

Before any fit (no candidates yet) the first round is :func:`seed_probes`: the front and the
two sides at the estimate's middle, which with EP1's top and bottom give a fit its first
five contacts. SI units: metres.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from itertools import chain, product

import numpy as np

from eos_svc.agents.probe_plan import Probe, face_probes, front_probe, side_probe
from eos_svc.drivers.protocol import HandDriver
from eos_svc.shape.probe_information import Candidate, choose, disagreement

#: offsets of the probe lines from a face's centre, as fractions of its half sizes
OFFSET = 0.5
#: a probe is worth making only when the candidates' predicted distances spread more than this (m)
MIN_SPREAD = 5e-4
#: the least half size a line's reach is planned for (m): a probe starts up to twice that
#: beyond the face (nearer where the wrist cannot start there), as the object may reach farther
REACH_HALF = 0.1
#: the outward normals of the faces probed
NORMALS = tuple(s * e for e in np.eye(3) for s in (1.0, -1.0))


def probe_faces(centre: np.ndarray, half: np.ndarray, table: bool) -> list[dict]:
    """The lines the hand may probe along, as the faces
    :func:`~eos_svc.agents.probe_plan.targeted_probes` aims at: per
    outward normal (none turned down on a table), the bounds' face centre and the points
    ±OFFSET of its half sizes off it along both tangents (``half``: the bounds' half size along
    the normal, at least REACH_HALF)."""
    faces = []
    for normal in NORMALS:
        if table and normal[2] < -0.5:
            continue
        axis = int(np.argmax(np.abs(normal)))
        u, v = (a for a in range(3) if a != axis)
        for a, b in product((0.0, OFFSET, -OFFSET), repeat=2):
            point = centre + normal * half[axis]
            point[u] += a * half[u]
            point[v] += b * half[v]
            faces.append({"centre": point, "normal": normal, "half": max(float(half[axis]), REACH_HALF)})
    return faces


def next_probes(
    world: HandDriver,
    candidates: list[dict],
    estimate: tuple[np.ndarray, np.ndarray],
    most: int,
    standoff: float,
) -> list[Iterator[Probe]]:
    """The ``most`` most informative lines onto the ``estimate`` (centre, half extents along
    the world axes, m) under post_shape's ``candidates`` (their JSON form), each line's probes
    the alternatives (one group) in order, made as asked for: the greedy choice, then
    the other lines by their own spread (tried when the hand cannot probe the chosen ones);
    none when no line's predicted distance spreads over MIN_SPREAD."""
    faces = probe_faces(*estimate, table=world.support_height is not None)
    # each line scored by its face's first probe; the alternatives made as a line is probed
    lines = [face_probes(world, face, k, standoff, "active", False) for k, face in enumerate(faces)]
    firsts = [next(line) for line in lines]
    R = disagreement(
        [Candidate.from_dict(c) for c in candidates],
        np.array([p.start for p in firsts]),
        np.array([p.direction for p in firsts]),
        np.array([p.travel for p in firsts]),
        np.array([world.hand.tip_radius(p.finger) for p in firsts]),
    )
    noise = math.hypot(world.tactile_noise, world.kinematic_sigma)
    picks = choose(R, noise, most, MIN_SPREAD**2)
    # then, for when those lines cannot be probed, the others by their own spread
    variance = np.sum(R * R, axis=0)
    rest = [int(j) for j in np.argsort(-variance) if variance[j] > MIN_SPREAD**2 and j not in picks]
    return [chain([firsts[j]], lines[j]) for j in (picks + rest)[:most]]


def seed_probes(world: HandDriver, centre: np.ndarray, half: np.ndarray, standoff: float) -> list[Probe]:
    """The first round's probes: straight onto the front (along +x) and both sides (along ±y)
    at the estimate's middle, the sides in front of the widest section (the links trail the
    tip toward −x; a second start farther forward where the first cannot be reached), each
    its own group."""
    hx = float(half[0])
    out = [front_probe(world, centre, half, 0.0, 0.0, standoff, group=0)]
    for k, sign in enumerate((1, -1)):
        for dx in (-0.25 * hx, -0.6 * hx):  # the second where the first cannot start
            out.append(side_probe(world, centre, half, sign, dx, standoff, group=k + 1))
    return out
