"""Grasp synthesis simulates orientations lazily, least wrist rotation first: the candidates it
returns are those of the plain version that simulates every orientation first."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world, default_hand, parameters_for
from eos_svc.grasp.postulate import make_object
from eos_svc.grasp.synthesis import GraspSynthesis, candidate_frames, palm_turn

HERE = (0.21, 0.02, -0.015)
SPECS = [
    ObjectSpec("sphere", {"radius": 0.03}, HERE),
    ObjectSpec("sphere", {"radius": 0.055}, HERE),
    ObjectSpec("ellipsoid", {"radii": (0.04, 0.028, 0.022)}, HERE, (0.2, -0.1, 0.7)),
    ObjectSpec("cylinder", {"radius": 0.02, "length": 0.08}, HERE),
    ObjectSpec("cylinder", {"radius": 0.018, "length": 0.07}, HERE, (math.pi / 2, 0.0, 0.4)),
    ObjectSpec("capsule", {"radius": 0.02, "length": 0.05}, HERE, (1.0, 0.2, -0.5)),
    ObjectSpec("capsule", {"radius": 0.025, "length": 0.02}, HERE, (0.0, math.pi / 2, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.05, 0.05)}, HERE, (0.0, 0.0, 0.5)),
    ObjectSpec("box", {"size": (0.07, 0.035, 0.045)}, HERE, (0.3, 0.6, -1.1)),
    ObjectSpec("box", {"size": (0.03, 0.03, 0.08)}, HERE, (0.0, 0.0, 1.0)),
    ObjectSpec("box", {"size": (0.2, 0.2, 0.2)}, HERE),  # too large: no candidate at all
]


def _synthesis(spec: ObjectSpec) -> GraspSynthesis:
    hand = default_hand()
    world = build_world(PlanRequest(), hand)
    return GraspSynthesis(hand, world.sweeps, parameters_for(hand), make_object(spec), 0.5)


def _same(a, b) -> bool:
    return (
        a.label == b.label
        and np.array_equal(a.rotation, b.rotation)
        and a.wrist_rpy == b.wrist_rpy
        and np.array_equal(a.wrist, b.wrist)
        and a.depth == b.depth
        and a.angle_deg == b.angle_deg
        and a.epsilon == b.epsilon
        and a.turn == b.turn
        and all(
            np.array_equal(a.landings[f].point, b.landings[f].point)
            and a.landings[f].angle == b.landings[f].angle
            for f in a.landings
        )
    )


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: f"{s.shape}-{s.rpy}")
def test_lazy_candidates_are_the_eager_ones(spec):
    lazy, eager = _synthesis(spec), _synthesis(spec)
    got, want = lazy.candidates(), eager.candidates_eager()
    assert len(got) == len(want)
    assert all(_same(a, b) for a, b in zip(got, want, strict=True))
    if not want:  # nothing kept: every orientation was simulated, the reasons agree
        assert lazy.rejections == eager.rejections


def test_lazy_candidates_simulate_fewer_orientations():
    spec = SPECS[8]  # a box: 26 orientations
    lazy, eager = _synthesis(spec), _synthesis(spec)
    calls = {"lazy": 0, "eager": 0}

    def counting(s, name):
        plain = s._simulated

        def wrapped(label, R):
            calls[name] += 1
            return plain(label, R)

        s._simulated = wrapped

    counting(lazy, "lazy")
    counting(eager, "eager")
    lazy.candidates()
    eager.candidates_eager()
    frames = list(candidate_frames(lazy.obj))
    assert calls["eager"] == len(frames)
    assert 0 < calls["lazy"] < calls["eager"]


def test_turn_groups_ascend_and_keep_the_frame_order():
    s = _synthesis(SPECS[4])
    groups = s._turn_groups()
    turns = [round(palm_turn(R), 6) for group in groups for _, _, R in group]
    assert turns == sorted(turns)
    for group in groups:
        indices = [i for i, _, _ in group]
        assert indices == sorted(indices)
    assert sum(len(g) for g in groups) == len(list(candidate_frames(s.obj)))
