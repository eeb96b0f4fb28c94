"""Admission in the service: requests the planner cannot plan are refused with ``invalid_request``
naming the field, one log line each, no traceback (real Zenoh sessions on loopback)."""

from __future__ import annotations

import json
import logging
import os

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import slowed

pytestmark = pytest.mark.skipif(
    os.environ.get("EOS_TEST_PLANNER") == "root", reason="admission is the grasp planner's"
)

UNPLANNABLE = [
    ("far away", {"shape": "sphere", "radius": 0.03, "position": [9, 9, 9]}, "object.position"),
    (
        "above the reach",
        {"shape": "sphere", "radius": 0.03, "position": [0.21, 0.0, 0.3]},
        "object.position[2]",
    ),
    ("inside the hand", {"shape": "sphere", "radius": 0.03, "position": [0, 0, 0]}, "object.position"),
    ("too large", {"shape": "sphere", "radius": 0.2, "position": [0.4, 0, 0]}, "object.radius"),
    ("box too large", {"shape": "box", "size": [0.3, 0.4, 0.5], "position": [0.5, 0, 0]}, "object.size"),
]


def _refused(client, svc, body: dict) -> dict:
    payload = proto.encode_request("adm-1", body)
    replies = list(
        client.session.get(proto.plan_key(client.prefix, svc.instance), payload=payload, timeout=10)
    )
    assert len(replies) == 1
    assert replies[0].err is not None
    return json.loads(replies[0].err.payload.to_bytes())


@pytest.mark.parametrize(("name", "obj", "field"), UNPLANNABLE, ids=[u[0] for u in UNPLANNABLE])
def test_unplannable_object_is_refused_at_admission(name, obj, field, port, services, clients, caplog):
    svc = services(port, planner=None)  # the grasp planner and its admission
    client = clients(port)
    client.wait_for_instances(1)
    statuses: list[tuple[str, dict]] = []
    sub = client.watch(lambda kind, msg: statuses.append((kind, msg)))
    with caplog.at_level(logging.INFO, logger="eos_svc.service.server"):
        body = _refused(client, svc, {"object": obj})
    sub.undeclare()
    assert body["code"] == proto.E_INVALID
    assert body["field"].startswith(field)
    assert body["goal_id"] == "adm-1"
    refusals = [r for r in caplog.records if "refused goal adm-1" in r.getMessage()]
    assert len(refusals) == 1 and refusals[0].exc_info is None
    assert not any(r.levelno >= logging.ERROR for r in caplog.records)
    assert statuses == []  # never queued: no running/done for the goal
    assert svc.stats.replied_ok == svc.stats.cancels  # the watcher's sync only: no plan ran
    assert svc.stats.consistent()
    # the client library raises it, and the service still plans
    with pytest.raises(proto.RequestError) as info:
        client.plan({"object": obj}, goal_id="adm-2")
    assert info.value.code == proto.E_INVALID and info.value.field.startswith(field)
    assert client.plan(PlanRequest(max_cycles=3)).status == "cycle_limit"


def test_planner_refusal_without_admission_is_invalid_request_not_internal_error(
    port, services, clients, grasp_planner, caplog
):
    # a wrapped planner gets no admission by default: the planner's own refusal is still named
    svc = services(port, planner=slowed(grasp_planner, 0.0))
    client = clients(port)
    client.wait_for_instances(1)
    with caplog.at_level(logging.INFO, logger="eos_svc.service.server"):
        body = _refused(client, svc, {"object": UNPLANNABLE[0][1]})
    assert body["code"] == proto.E_INVALID and body["field"].startswith("object.position")
    assert not any(r.exc_info for r in caplog.records)
