"""The referee's verdict of a grip: contacts per finger, the paper's good-grasp test and the
grasp's quality, measured on the true object (world side: only a driver calls it).

The grasp is *good* (paper Fig. 2) when every fingertip touches, the contacts lie about the
object's diameter — the opposing finger's contact and the middle of the other contacts on
opposite sides of the object's centre, the angle between them, seen from the centre, at least
150° — and they are in force closure under Coulomb friction (:mod:`eos_svc.grasp.quality`:
linearised cones, the Ferrari–Canny ε).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from eos_svc.grasp.quality import DEFAULT_EDGES, contacts_quality

if TYPE_CHECKING:
    from eos_svc.world.world import GraspWorld

#: smallest angle (deg) between the opposing contact and the others' midpoint for a good grasp
GOOD_GRASP_ANGLE_DEG = 150.0


def grasp_geometry(world: GraspWorld, friction: float) -> dict[str, Any]:
    """Contacts per finger and the good-grasp test, from the world as it is (ground truth).

    Returns a dict: ``contacts`` (per finger: touching, distance, point, outward normal),
    ``all_touching``, ``diameter_angle_deg``, ``about_diameter`` (the paper's Fig. 2 test),
    ``quality`` (:class:`~eos_svc.grasp.quality.GraspQuality` as a dict: force closure, ε,
    μ, …, over the touching contacts, torques about the object's centre scaled by its half
    diameter), ``good`` (all touching, about the diameter and in force closure) and
    ``q_final`` (the hand configuration judged).
    """
    hand = world.hand
    contacts = {}
    for finger in hand.finger_names:
        c = world.scene.contact(world.state, finger)
        contacts[finger] = {
            "touching": bool(c.distance <= world.params.contact_tolerance),
            "distance": float(c.distance),
            "point": c.point_object.round(6).tolist(),  # np.round's own method, without its wrapper
            "normal": c.normal.round(6).tolist(),
        }
    all_touch = all(c["touching"] for c in contacts.values())
    angle = None
    about = False
    if all_touch:
        centre = world.obj.placement.translation
        opposing = hand.description.opposing_finger
        u = np.asarray(contacts[opposing]["point"]) - centre
        others = [np.asarray(c["point"]) for f, c in contacts.items() if f != opposing]
        v = np.mean(others, axis=0) - centre
        cos = float(u @ v / max(np.linalg.norm(u) * np.linalg.norm(v), 1e-12))
        angle = math.degrees(math.acos(max(-1.0, min(1.0, cos))))
        about = angle >= GOOD_GRASP_ANGLE_DEG
    quality = contacts_quality(
        contacts,
        world.obj.placement.translation,
        0.5 * world.obj.diameter,
        friction,
        DEFAULT_EDGES,
        world.params.contact_patch_radius,
    )
    return {
        "contacts": contacts,
        "all_touching": all_touch,
        "good": bool(about and quality.force_closure),
        "about_diameter": about,
        "diameter_angle_deg": angle,
        "quality": quality.to_dict(),
        "q_final": world.state.q.tolist(),
    }
