"""``SweepLandings.miss_lower_bound`` never exceeds the landing's exact distance to a point, and
a finger's ``lands_within`` (which skips the landing when the bound decides) answers as the
exact ``landing_miss`` does, through whole plans."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.finger import FingerAgent
from eos_svc.agents.planner import default_hand, finger_sweeps
from eos_svc.grasp.synthesis import SweepLandings, rotated_sweep_gaps
from eos_svc.kinematics import Box, Capsule, Cylinder, Ellipsoid, Sphere


def _objects():
    placement = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.7), np.array([0.12, 0.01, -0.02]))
    return [
        Sphere(0.03, placement),
        Box((0.05, 0.04, 0.06), placement),
        Cylinder(0.025, 0.08, placement),
        Capsule(0.02, 0.06, placement),
        Ellipsoid((0.035, 0.03, 0.025), placement),
    ]


@pytest.mark.parametrize("obj", _objects(), ids=lambda o: o.kind)
def test_the_bound_never_exceeds_the_exact_miss(obj):
    hand = default_hand()
    sweeps = finger_sweeps(hand)
    rng = np.random.default_rng(2)
    compared = informative = 0
    for _ in range(150):
        rotation = pin.rpy.rpyToMatrix(*rng.uniform(-0.4, 0.4, 3))
        centre = np.array([0.12, 0.01, -0.02]) + rng.uniform(-0.03, 0.03, 3)
        origin = centre - rotation[:, 0] * rng.uniform(0.0, 0.09)
        finger = str(rng.choice(hand.finger_names))
        sweep, r = sweeps[finger], hand.tip_radius(finger)
        pts, gaps = rotated_sweep_gaps(obj, sweep.points @ rotation.T, r, origin)
        landings = SweepLandings(obj, sweep, pts, gaps)
        for start in rng.integers(0, len(sweep.angles), 5).tolist():
            hit = landings.landing(start)
            point = obj.closest_surface_point(obj.placement.translation + rng.normal(size=3))
            bound = landings.miss_lower_bound(start, r, point)
            if hit is None:
                assert bound == -np.inf
                continue
            exact = float(np.linalg.norm(hit.point - point))
            assert bound <= exact
            compared += 1
            informative += bound > 0.002
    assert compared > 100
    if obj.kind != "ellipsoid":
        assert informative > compared // 4  # the bound decides often


REQUESTS = [
    PlanRequest(),
    PlanRequest(seed=2),
    PlanRequest(obj=ObjectSpec("box", {"size": (0.05, 0.05, 0.05)}, rpy=(0.0, 0.0, 0.5))),
    PlanRequest(obj=ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, rpy=(1.5708, 0.0, 0.0))),
]


@pytest.mark.parametrize("request_", REQUESTS, ids=["default", "seed2", "box", "cylinder"])
def test_lands_within_answers_as_the_exact_miss(request_, monkeypatch):
    checked = []
    plain = FingerAgent.lands_within

    def checked_lands_within(self, board, tolerance):
        answer = plain(self, board, tolerance)
        miss = self.landing_miss(board)
        assert answer == (miss is not None and miss <= tolerance)
        checked.append(answer)
        return answer

    monkeypatch.setattr(FingerAgent, "lands_within", checked_lands_within)
    plan(request_)
    # the grasping stage ran: fingers in and out of reach were both asked about
    assert len(checked) > 20 and True in checked and False in checked
