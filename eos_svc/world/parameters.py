"""The grasp world's tunable constants and what they derive from the hand (SI units).

:meth:`WorldParameters.for_hand` derives the hand-dependent fields (grasp centre, search box,
hand bound) from a hand's model and closing sweeps (:mod:`eos_svc.grasp.sweeps`); a hand's
description may set any of them (``[world]``, see ``docs/hands.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eos_svc.grasp.sweeps import FingerSweep, build_sweeps
from eos_svc.hands import DescribedHand
from eos_svc.kinematics import HandModel


@dataclass(frozen=True)
class WorldParameters:
    """Tunable constants of the grasp world (SI units).

    Attributes:
        search_box_lo, search_box_hi: bounds of the wrist's search workspace (m).
        envelope_radius: the object is *located* within this distance of the grasp centre (m).
        grasp_centre: the grasp centre in the palm frame (m): between the fingers.
        clearance: smallest hand–object distance a search or approach move may leave (m).
        wrist_step: length of one wrist approach step in the grasp stage (m).
        approach_distance: how far before its grasp position grasp_points places the hand (m).
        finger_step: joint increment of one finger closing step (rad, every joint).
        contact_tolerance: a fingertip within this distance touches (m).
        ep1_steps: rolling steps per direction in one EP1 run.
        ep1_omega: rolling rate (rad/s); a direction sweeps ``ep1_omega · ep1_dt · ep1_steps``
            rad (0.32 by default: the contact's travel dominates the tactile noise).
        ep1_dt: time step of the rolling motion (s).
        ep1_directions: roll directions of one EP1 run (degrees in the tangent plane).
        confidence_threshold: post_shape confidence needed to leave the information stage.
        landing_tolerance: a finger closes only when its tip lands within this distance of its
            chosen contact (m).
        hand_bound: radius of a ball about the grasp centre containing the whole hand (m).
        contact_patch_radius: the fingertips' contact patch radius (m): 0 for point contacts,
            > 0 for soft pads that resist a torque about the normal (:mod:`eos_svc.grasp.quality`).
    """

    search_box_lo: tuple[float, float, float] = (-0.10, -0.15, -0.15)
    search_box_hi: tuple[float, float, float] = (0.30, 0.15, 0.15)
    envelope_radius: float = 0.05
    grasp_centre: tuple[float, float, float] = (0.11, 0.0, 0.0)
    clearance: float = 0.002
    wrist_step: float = 0.005
    approach_distance: float = 0.04
    finger_step: float = 0.03
    contact_tolerance: float = 1e-4
    ep1_steps: int = 16
    ep1_omega: float = 2.0
    ep1_dt: float = 0.01
    ep1_directions: tuple[float, ...] = (0.0, 90.0)
    confidence_threshold: float = 0.6
    landing_tolerance: float = 0.002
    hand_bound: float = 0.2
    contact_patch_radius: float = 0.0

    @classmethod
    def for_hand(
        cls, hand: HandModel, sweeps: dict[str, FingerSweep] | None = None, **overrides: object
    ) -> WorldParameters:
        """Parameters for ``hand``: the hand-dependent fields derived from its model (see
        :func:`derive_hand_fields`), then those its description sets (``[world]`` of a
        :class:`~eos_svc.hands.DescribedHand`: hand3x3's are the values the planner was tuned
        with), then ``overrides``."""
        described = hand.world_overrides if isinstance(hand, DescribedHand) else {}
        fields = {**derive_hand_fields(hand, sweeps), **described, **overrides}
        return cls(**fields)


def derive_hand_fields(hand: HandModel, sweeps: dict[str, FingerSweep] | None = None) -> dict[str, object]:
    """The hand-dependent :class:`WorldParameters` fields: ``grasp_centre`` on the palm's x axis
    where the fingers' closing paths come nearest it (mean x), hand3x3's search box shifted so
    the grasp centre sweeps the same region, and ``hand_bound`` (the hand's reach from the grasp
    centre over the closing paths, plus 1 cm)."""
    sweeps = sweeps if sweeps is not None else build_sweeps(hand)
    xs = []
    for sweep in sweeps.values():
        off_axis = np.hypot(sweep.points[:, 1], sweep.points[:, 2])
        xs.append(float(sweep.points[int(np.argmin(off_axis)), 0]))
    centre = np.array([round(float(np.mean(xs)), 4), 0.0, 0.0])
    base = WorldParameters()
    shift = centre - np.asarray(base.grasp_centre)
    lo = np.round(np.asarray(base.search_box_lo) - shift, 4)
    hi = np.round(np.asarray(base.search_box_hi) - shift, 4)
    return {
        "grasp_centre": tuple(centre.tolist()),
        "search_box_lo": tuple(lo.tolist()),
        "search_box_hi": tuple(hi.tolist()),
        "hand_bound": round(_hand_reach(hand, sweeps, centre) + 0.01, 3),
    }


def _hand_reach(hand: HandModel, sweeps: dict[str, FingerSweep], centre_palm: np.ndarray) -> float:
    """Largest distance from ``centre_palm`` to any collision geometry's bounding sphere over
    the fingers' closing paths (every finger at the same fraction of its range), wrist at 0."""
    state = hand.state(hand.neutral())
    palm = state.palm_placement()
    geometries = hand.collision_model.geometryObjects
    radii = []
    for g in geometries:
        g.geometry.computeLocalAABB()
        radii.append(float(g.geometry.aabb_radius) + float(np.linalg.norm(g.geometry.aabb_center)))
    reach = 0.0
    for fraction in np.linspace(0.0, 1.0, 21):
        q = hand.neutral()
        for finger, sweep in sweeps.items():
            q[hand.finger_q_index(finger)] = sweep.angles[0] + fraction * (sweep.angles[-1] - sweep.angles[0])
        state.update(q)
        for gid, radius in enumerate(radii):
            p = palm.actInv(state.geometry_data.oMg[gid].translation)
            reach = max(reach, float(np.linalg.norm(p - centre_palm)) + radius)
    return reach
