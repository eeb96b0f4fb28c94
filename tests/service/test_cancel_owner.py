"""Only a goal's owner cancels it: the cancel must carry the goal's secret cancel token
(real Zenoh sessions on loopback; a second session learns the goal id from the status topic)."""

from __future__ import annotations

import os
import threading
from typing import Any

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import slowed
from eos_svc.service.plan_attempt import PlanOutcome
from eos_svc.service.wire_json import loads_strict
from tests.service.waiting import wait_until


def _start_long_plan(client: Any, goal: str, **kwargs: Any) -> tuple[threading.Thread, dict[str, Any]]:
    box: dict[str, Any] = {}
    started = threading.Event()

    def on_cycle(msg: dict[str, Any]) -> None:
        if msg["seq"] >= 2:
            started.set()

    def run() -> None:
        box["out"] = client.plan(
            PlanRequest(max_cycles=100_000, deadline_s=60.0), goal_id=goal, on_cycle=on_cycle, **kwargs
        )

    t = threading.Thread(target=run)
    t.start()
    assert started.wait(30), "the plan did not start"
    return t, box


def test_a_stranger_knowing_the_goal_id_cannot_cancel_the_owner_can(port, services, clients, grasp_planner):
    a = services(port, planner=slowed(grasp_planner, 0.02))
    b = services(connect=(port,), planner=slowed(grasp_planner, 0.02))
    owner = clients(port)
    stranger = clients(port)
    owner.wait_for_instances(2)
    stranger.wait_for_instances(2)
    seen: list[tuple[str, dict[str, Any]]] = []
    # every goal's messages; watch() returns once both instances know the subscriber
    sub = stranger.watch(lambda kind, msg: seen.append((kind, msg)))
    t, box = _start_long_plan(owner, "mine-1", cancel_token="owner-secret-0123456789")

    def learned() -> set[str]:
        return {msg["goal_id"] for kind, msg in list(seen) if kind == "status"}

    wait_until(lambda: "mine-1" in learned(), 5)  # the stranger's copy travels its own route
    assert "mine-1" in learned()  # the goal id is public
    for token in (None, "wrong-secret-0123456789", "owner-secret-012345678X"):
        with pytest.raises(proto.RequestError) as info:
            stranger.cancel("mine-1", cancel_token=token)
        assert info.value.code == proto.E_FORBIDDEN and info.value.field == "cancel_token"
    assert t.is_alive()  # still running
    assert owner.cancel("mine-1")  # the owner's client remembers the token it sent
    t.join(15)
    out: PlanOutcome = box["out"]
    assert out.result["status"] == "cancelled"
    sub.undeclare()
    # the token was never published on any cycle or status message
    assert not any("owner-secret" in str(msg) for _kind, msg in seen)
    assert (a.stats.cancelled + b.stats.cancelled) == 1


def test_another_process_with_the_token_can_cancel(port, services, clients, grasp_planner):
    services(port, planner=slowed(grasp_planner, 0.02))
    owner = clients(port)
    helper = clients(port)  # e.g. ``eos client cancel g --token T`` from another shell
    owner.wait_for_instances(1)
    helper.wait_for_instances(1)
    t, box = _start_long_plan(owner, "shared-1", cancel_token="shared-secret-0123456789")
    assert helper.cancel("shared-1", cancel_token="shared-secret-0123456789")
    t.join(15)
    assert box["out"].result["status"] == "cancelled"


def test_a_goal_sent_without_a_token_cannot_be_cancelled(port, services, clients, grasp_planner):
    svc = services(port, planner=slowed(grasp_planner, 0.02))
    client = clients(port)
    client.wait_for_instances(1)
    payload = proto.encode_request("tokenless", PlanRequest(max_cycles=30))  # no cancel_token
    handler = client.session.get(proto.plan_key(client.prefix, svc.instance), payload=payload, timeout=20)
    wait_until(lambda: svc._goals.get("tokenless") is not None, 20)
    with pytest.raises(proto.RequestError) as info:
        client.cancel("tokenless", cancel_token="any-secret-0123456789")
    assert info.value.code == proto.E_FORBIDDEN and "without a cancel_token" in info.value.reason
    replies = list(handler)
    assert len(replies) == 1 and replies[0].ok is not None  # it ran to its end
    assert loads_strict(replies[0].ok.payload.to_bytes())["result"]["status"] == "cycle_limit"


def test_a_malformed_cancel_token_in_a_request_is_named():
    with pytest.raises(proto.RequestError) as info:
        proto.decode_request(proto.encode_request("g1", PlanRequest(), "short"))
    assert (info.value.code, info.value.field) == (proto.E_INVALID, "cancel_token")


def test_cancel_tokens_are_unique_and_not_shared_with_a_forked_child():
    tokens = {proto.new_cancel_token() for _ in range(500)}  # several batches
    assert len(tokens) == 500 and all(proto.TOKEN_PATTERN.fullmatch(t) for t in tokens)
    read_end, write_end = os.pipe()
    pid = os.fork()  # the parent holds a batch of unused tokens now
    if pid == 0:  # pragma: no cover - the child
        os.write(write_end, proto.new_cancel_token().encode())
        os._exit(0)
    os.waitpid(pid, 0)
    child_token = os.read(read_end, 64).decode()
    os.close(read_end)
    os.close(write_end)
    parent_tokens = {proto.new_cancel_token() for _ in range(64)}  # at least the rest of the batch
    assert proto.TOKEN_PATTERN.fullmatch(child_token) and child_token not in parent_tokens | tokens
