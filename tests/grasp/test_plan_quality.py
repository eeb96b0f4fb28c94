"""Grasp quality in the planner: the request's friction, the end agent's verdict, the result."""

from __future__ import annotations

import json

import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.errors import ValidationError
from eos_svc.grasp.quality import contacts_quality


@pytest.fixture(scope="module")
def default_result():
    return plan(PlanRequest(seed=1))


def test_default_plan_reports_force_closure_and_epsilon(default_result):
    r = default_result
    assert r.status == "success"
    assert r.friction == 0.5 and r.force_closure and r.epsilon > 0.0
    assert r.good_grasp  # about the diameter and in force closure
    q = r.quality
    assert q["force_closure"] and q["dimension"] == 6 and q["contacts"] == 3 and q["edges"] == 8
    assert q["torque_scale"] == pytest.approx(0.5 * r.ground_truth["diameter"])
    data = json.loads(r.to_json())
    assert data["force_closure"] is True and data["epsilon"] == r.epsilon and len(data["q_final"]) > 0
    # the end agent judged with the same numbers
    end = r.trace[-1]
    assert end.chosen == "end" and "force closure at μ=0.5" in end.detail
    verdict = next(c.new for c in end.changes if c.key == "grasp_outcome")
    assert verdict["quality"] == q and verdict["good"] is True


def test_result_quality_recomputes_from_contacts(default_result):
    r = default_result
    q = contacts_quality(r.contacts, r.ground_truth["position"], 0.5 * r.ground_truth["diameter"], 0.5)
    assert q.epsilon == r.epsilon


def test_frictionless_grasp_is_not_good():
    r = plan(PlanRequest(seed=1, friction=0.0))
    assert r.precision_grip and r.stages_completed[-1] == "grasping"  # all fingertips touch...
    assert not r.force_closure and r.epsilon == 0.0 and not r.good_grasp  # ...but nothing holds it
    assert r.status == "completed" and not r.success  # a poor grip is never a success
    assert "no force closure" in r.reason and r.friction == 0.0


def test_epsilon_grows_with_friction(default_result):
    r = plan(PlanRequest(seed=1, friction=1.0))
    assert r.cycles == default_result.cycles  # friction changes the judgement, not the run
    assert r.epsilon > default_result.epsilon


@pytest.mark.parametrize("value", [-0.1, 11.0, float("nan"), "0.5", True, None])
def test_friction_is_validated(value):
    with pytest.raises(ValidationError) as err:
        PlanRequest(friction=value)
    assert err.value.field == "friction"


def test_friction_round_trips_through_json():
    req = PlanRequest.from_dict({"friction": 0.8})
    assert req.friction == 0.8 and PlanRequest.from_dict(req.to_dict()) == req
    with pytest.raises(ValidationError, match="friction"):
        PlanRequest.from_dict({"friction": -1})
