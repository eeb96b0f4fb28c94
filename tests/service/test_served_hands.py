"""``eos serve --hand FILE``'s path on a real Zenoh session on loopback: the service plans with
the hand a request names (a registered one, or one added from a description file) and refuses
an unknown hand naming the field."""

from __future__ import annotations

import pytest

from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.hands import ServedHands
from tests.hands.claw import write_hand


def test_requests_name_their_hand(port, services, clients, tmp_path):
    hands = ServedHands([write_hand(tmp_path)])
    services(port, planner=hands.plan, admission=hands.admit)
    client = clients(port)
    client.wait_for_instances(1)
    sphere = ObjectSpec("sphere", {"radius": 0.025}, ObjectSpec().position)
    for name, fingers in (("claw", {"claw1", "claw2", "claw3"}), ("panda", {"left", "right"})):
        outcome = client.plan(PlanRequest(obj=sphere, seed=1, hand=name), goal_id=f"hand-{name}")
        assert outcome.result["status"] == "success", outcome.result["reason"]
        assert set(outcome.result["contacts"]) == fingers
    with pytest.raises(proto.RequestError) as info:
        client.plan({"hand": "nosuch"}, goal_id="hand-unknown")
    assert (info.value.code, info.value.field) == (proto.E_INVALID, "hand")
