"""What a plan derives from its hand alone: :class:`HandContext`, built once per hand, immutable,
passed explicitly and shared between plans and threads (docs/planner.md). The process's default
hand keeps one (:func:`default_context`): building it costs about a third of a default plan.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np

from eos_svc.grasp.sweeps import FingerSweep, build_sweeps, finger_link_geometries, forward_reach
from eos_svc.hands import DEFAULT_HAND, load_hand_named
from eos_svc.kinematics import HandModel
from eos_svc.kinematics.gap_bounds import hand_bound_table
from eos_svc.kinematics.hand_state import read_only
from eos_svc.world.coverage import Lattice, column_counts, lattice_of
from eos_svc.world.fingertip_fit import FingertipOpening
from eos_svc.world.parameters import WorldParameters
from eos_svc.world.probe_pose import ProbePose
from eos_svc.world.probing import ProbeChoice

#: joint samples per finger joint when measuring the hand's span (a grid over the joint range)
SPAN_SAMPLES = 7


@dataclass(frozen=True)
class PlacedGeometry:
    """One hand collision geometry at the start configuration, with its bounding ball (world, m)."""

    name: str
    shape: coal.ShapeBase
    transform: coal.Transform3s
    centre: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class HandContext:
    """A hand and what is derived from it once (read-only; shared by every plan of the hand).

    Attributes:
        hand: the hand model.
        sweeps: each finger's closing sweep (palm frame).
        params: the world's constants for this hand (:meth:`WorldParameters.for_hand`).
        bounds: per collision geometry, how to bound its gap to a ball (:mod:`eos_svc.kinematics.gap_bounds`).
        links: per finger, its link geometries (what stops a closing finger as "link").
        probe: which finger explores the object's top and bottom, at which angle.
        probe_poses: the probe pose of every (finger, angle) EP2 probes with.
        angle_q: per finger, the q index of its first joint (its angle).
        finger_q: per finger, its joints' q indices (read-only).
        side_fingers: the upper finger leading a probe along +y (key ``+1``) and along −y (``-1``).
        span: the largest distance between two fingertips' surfaces over the joint ranges (m).
        neutral_geometries: the collision geometries at the start configuration.
        forward_reach: how far ahead of the wrist the fingers reach (m).
        lattice: the search's column lattice and its distances (from ``params``).
        opening: the fingertips' widest openings that still reach a contact (admission's size rule).
    """

    hand: HandModel
    sweeps: dict[str, FingerSweep]
    params: WorldParameters
    bounds: list[tuple[int, Any, Any, float]]
    links: dict[str, list[int]]
    probe: ProbeChoice
    probe_poses: dict[tuple[str, float], ProbePose]
    angle_q: dict[str, int]
    finger_q: dict[str, np.ndarray]
    side_fingers: dict[int, str]
    span: float
    neutral_geometries: tuple[PlacedGeometry, ...]
    forward_reach: float
    lattice: Lattice
    opening: FingertipOpening

    @classmethod
    def build(cls, hand: HandModel, params: WorldParameters | None = None) -> HandContext:
        """The context of ``hand`` (``params`` default: :meth:`WorldParameters.for_hand`)."""
        sweeps = build_sweeps(hand)
        if params is None:
            params = WorldParameters.for_hand(hand, sweeps)
        probe = ProbeChoice.for_hand(hand, sweeps)
        links = finger_link_geometries(hand)
        sides = side_fingers(hand)
        angles = {(f, probe.angles.get(f, 0.0)) for f in (probe.top, probe.bottom, *sides.values())}
        return cls(
            hand=hand,
            sweeps=sweeps,
            params=params,
            bounds=hand_bound_table(hand),
            links=links,
            probe=probe,
            probe_poses={(f, a): ProbePose.build(hand, f, a) for f, a in angles},
            angle_q={f: hand.finger_joint_limits(f)[0][0] for f in hand.finger_names},
            finger_q={f: read_only(hand.finger_q_index(f)) for f in hand.finger_names},
            side_fingers=sides,
            span=hand_span(hand),
            neutral_geometries=neutral_geometries(hand),
            forward_reach=forward_reach(hand, sweeps),
            lattice=lattice_of(*column_counts(params)),
            opening=FingertipOpening.build(hand, sweeps, links),
        )

    def with_params(self, params: WorldParameters) -> HandContext:
        """The same hand with other world constants (nothing here derives from them)."""
        if params == self.params:
            return self
        return dataclasses.replace(self, params=params, lattice=lattice_of(*column_counts(params)))

    def probe_pose(self, finger: str, angle: float, yaw: float = 0.0) -> ProbePose:
        """The :class:`ProbePose` of ``finger`` at ``angle`` rad, the wrist turned by ``yaw`` rad
        (kept for EP2's unturned probes, else built)."""
        pose = self.probe_poses.get((finger, float(angle))) if yaw == 0.0 else None
        return pose if pose is not None else ProbePose.build(self.hand, finger, angle, yaw)


@functools.cache
def default_context() -> HandContext:
    """The context of the default hand (hand3x3), built once per process."""
    return HandContext.build(load_hand_named(DEFAULT_HAND))


def context_for(hand: HandModel | None = None, params: WorldParameters | None = None) -> HandContext:
    """The default context for ``None`` or the default hand, else a new one; with ``params``."""
    default = default_context()
    context = default if hand is None or hand is default.hand else HandContext.build(hand, params)
    return context if params is None else context.with_params(params)


def side_fingers(hand: HandModel) -> dict[int, str]:
    """The upper finger whose tip lies farthest along +y at neutral (key ``+1``) and along −y (``-1``)."""
    upper = [f for f in hand.finger_names if f != hand.description.opposing_finger]
    state = hand.state(hand.neutral())
    y = {f: float(state.tip_position(f)[1]) for f in upper}
    return {+1: max(upper, key=lambda f: y[f]), -1: min(upper, key=lambda f: y[f])}


def hand_span(hand: HandModel) -> float:
    """Largest distance between the surfaces of two fingertips over the joint ranges (m), each
    joint sampled at :data:`SPAN_SAMPLES` values."""
    state = hand.state(hand.neutral())
    tips: dict[str, np.ndarray] = {}
    for finger in hand.finger_names:
        limits = hand.finger_joint_limits(finger)
        grids = [np.linspace(lo, hi, SPAN_SAMPLES) for _idx, lo, hi in limits]
        points = []
        for values in itertools.product(*grids):
            q = hand.neutral()
            for (idx, _lo, _hi), v in zip(limits, values, strict=True):
                q[idx] = v
            state.update(q)
            points.append(state.tip_position(finger).copy())
        tips[finger] = np.asarray(points)
    span = 0.0
    for a, b in itertools.combinations(hand.finger_names, 2):
        pa, pb = tips[a], tips[b]
        d = np.sqrt(((pa[:, None, :] - pb[None, :, :]) ** 2).sum(axis=2)).max()
        span = max(span, float(d) - hand.tip_radius(a) - hand.tip_radius(b))
    return span


def neutral_geometries(hand: HandModel) -> tuple[PlacedGeometry, ...]:
    """Every collision geometry of ``hand`` placed at its start configuration (``hand.neutral()``)."""
    state = hand.state(hand.neutral())
    out = []
    for gid, go in enumerate(hand.collision_model.geometryObjects):
        m = state.geometry_data.oMg[gid]
        transform = coal.Transform3s(np.array(m.rotation), np.array(m.translation))
        shape = go.geometry
        shape.computeLocalAABB()
        x, y, z = transform.transform(np.asarray(shape.aabb_center, dtype=float)).tolist()
        out.append(PlacedGeometry(go.name, shape, transform, (x, y, z), float(shape.aabb_radius)))
    return tuple(out)
