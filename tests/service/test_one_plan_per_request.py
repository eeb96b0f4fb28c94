"""A plan query whose key names no single instance gets one clear error, never one plan per
instance (three real instances on loopback)."""

from __future__ import annotations

import json

import pytest
import zenoh

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from tests.service.waiting import wait_until


@pytest.fixture
def three(port, services, clients, grasp_planner):
    svcs = [services(port, planner=grasp_planner, instance="inst-b")]
    svcs += [services(connect=(port,), planner=grasp_planner, instance=i) for i in ("inst-a", "inst-c")]
    client = clients(port)
    client.wait_for_instances(3)
    wait_until(lambda: all(len(s._peers._peers) >= 3 for s in svcs), 5)  # they see each other
    return svcs, client


@pytest.mark.parametrize("target", ["BEST_MATCHING", "ALL"])
@pytest.mark.parametrize(
    ("suffix", "named"),
    [("*", ["inst-a", "inst-b", "inst-c"]), ("**", ["inst-a", "inst-b", "inst-c"]), ("inst-$*c", ["inst-c"])],
)
def test_a_wildcard_gets_one_error_naming_the_keys(three, suffix, named, target):
    svcs, client = three
    payload = proto.encode_request("wild-1", PlanRequest(max_cycles=3), proto.new_cancel_token())
    statuses: list[dict] = []
    sub = client.watch(lambda _kind, msg: statuses.append(msg))
    replies = list(
        client.session.get(
            f"{client.prefix}/plan/{suffix}",
            payload=payload,
            target=getattr(zenoh.QueryTarget, target),
            consolidation=zenoh.ConsolidationMode.NONE,
            timeout=5,
        )
    )
    sub.undeclare()
    assert len(replies) == 1, [r.ok or r.err for r in replies]
    err = replies[0].err
    assert err is not None
    body = json.loads(err.payload.to_bytes())
    assert body["code"] == proto.E_INVALID and body["field"] == "key_expr"
    for iid in named:
        assert proto.plan_key(client.prefix, iid) in body["reason"]
    assert "liveliness" in body["reason"]
    assert sum(s.stats.replied_ok - s.stats.cancels for s in svcs) == 0  # no plan ran (a sync: a cancel)
    assert all(s.stats.consistent() for s in svcs)
    assert statuses == []
    # an exact key still plans, once
    assert client.plan(PlanRequest(max_cycles=3), instance="inst-c").instance == "inst-c"


def test_the_client_never_sends_a_wildcard(three):
    _svcs, client = three
    with pytest.raises(proto.RequestError) as info:
        client.plan(PlanRequest(), instance="*")
    assert info.value.field == "instance"
