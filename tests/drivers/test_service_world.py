"""A request's ``world`` through the service: a real Zenoh request with ``world="drake"`` to a
real service instance on loopback plans in the Drake world (slow: a Drake simulation)."""

from __future__ import annotations

import pytest

from eos_svc.agents.planner import plan
from eos_svc.schema import keys
from eos_svc.schema.request import PlanRequest
from eos_svc.service.client import EosClient
from eos_svc.service.server import PlanService
from eos_svc.service.session import free_port, loopback, make_config


@pytest.mark.slow
def test_a_request_with_world_drake_plans_in_the_drake_world_through_the_service() -> None:
    port = free_port()
    service = PlanService.open(make_config(listen=[loopback(port)]), planner=plan)
    client = EosClient.open(make_config(connect=[loopback(port)]))
    try:
        assert client.wait_for_instances(1) == [service.instance]
        request = PlanRequest(seed=1, world="drake", max_cycles=9, deadline_s=600)
        outcome = client.plan(request, goal_id="drake-1")
        result = outcome.result
        assert outcome.complete and result["world"]["name"] == "drake"
        assert result["world"]["simulated_s"] > 0.0  # the plan ran in a Drake simulation
        poses = [c for m in outcome.cycles for c in m["record"]["changes"] if c["key"] == keys.OBJECT_POSE]
        assert poses  # the object's pose, as Drake had it, rides along every cycle's record
        kinematic = client.plan(PlanRequest(seed=1, max_cycles=9), goal_id="kinematic-1").result
        assert "world" not in kinematic or kinematic["world"] is None  # the default world: no Drake
    finally:
        client.close()
        service.stop()
