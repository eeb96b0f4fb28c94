"""The hands a service plans with: every registered hand and those
``eos serve --hand FILE`` adds (the Zenoh path: tests/service/test_served_hands.py)."""

from __future__ import annotations

import pytest

from eos_svc.errors import ValidationError
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.service.hands import ServedHands
from tests.hands.claw import write_hand


def test_request_hand_field_round_trips_and_is_checked():
    request = PlanRequest.from_dict({"seed": 2, "hand": "trifinger"})
    assert request.hand == "trifinger" and request.to_dict()["hand"] == "trifinger"
    assert "hand" not in PlanRequest().to_dict()  # the default request's JSON is unchanged
    with pytest.raises(ValidationError) as info:
        PlanRequest.from_dict({"hand": "no spaces please"})
    assert info.value.field == "hand"


def test_served_hands_plan_with_the_named_hand_and_refuse_an_unknown_one(tmp_path):
    hands = ServedHands([write_hand(tmp_path)])
    assert {"hand3x3", "trifinger", "claw"} <= set(hands.names)
    sphere = ObjectSpec("sphere", {"radius": 0.025}, ObjectSpec().position)
    for name in ("claw", "trifinger"):
        request = PlanRequest(obj=sphere, seed=1, hand=name)
        hands.admit(request)
        result = hands.plan(request, keep_trace=False)
        assert result.status == "success", (name, result.reason)
        assert set(result.contacts) == set(hands.context(request).hand.finger_names)
    with pytest.raises(ValidationError) as info:
        hands.admit(PlanRequest(hand="nosuch"))
    assert info.value.field == "hand" and "claw" in info.value.reason
