"""The referee's verdict of a grip: contacts per finger, the paper's good-grasp test and the
grasp's quality, measured on the true object (world side: only a driver calls it).

The grasp is *good* (paper Fig. 2) when every fingertip touches, the contacts lie about the
object's diameter — the opposing finger's contact and the middle of the other contacts on
opposite sides of the object's centre, the angle between them, seen from the centre, at least
150° — and they are in force closure under Coulomb friction (:mod:`eos_svc.grasp.quality`:
linearised cones, the Ferrari–Canny ε).

A kind whose ``grasp_about_diameter`` is False (a mesh) is judged by force closure alone: the
contacts made on the true surface, with its true normals, torques about its true centre of mass.
The 150° test is the paper's for a sphere's diameter; on pybullet's random meshes it rejected
grips that Drake's lift test holds (on objects 600–629, 5 seeds, 43 of the 45 grips it
rejected were held, all 36 of them in force closure: docs/objects.md).
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
    diameter), ``centre_rule`` (``"diameter"``: the Fig. 2 test applies; ``"force closure"``:
    a mesh, judged by force closure alone), ``good`` (all touching, in force closure, and
    about the diameter where the rule is ``"diameter"``) and ``q_final`` (the hand
    configuration judged).
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
    diameter_rule = bool(getattr(world.obj, "grasp_about_diameter", True))
    return {
        "contacts": contacts,
        "all_touching": all_touch,
        "good": bool(all_touch and (about or not diameter_rule) and quality.force_closure),
        "centre_rule": "diameter" if diameter_rule else "force closure",
        "about_diameter": about,
        "diameter_angle_deg": angle,
        "quality": quality.to_dict(),
        "q_final": world.state.q.tolist(),
    }
