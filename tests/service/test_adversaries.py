"""The service under a slow watcher and a guessing stranger (real Zenoh sessions on loopback):
a watcher that never drains stalls no one else, default goal ids cannot be squatted, the
counters agree for every kind of query, and every goal ends and says so in the same order."""

from __future__ import annotations

import json
import threading
import time
from typing import Any

import pytest
import zenoh

from eos_svc.errors import ValidationError
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import root_plan, slowed
from eos_svc.service.session import loopback, make_config
from tests.service.waiting import wait_until


def flood(request: PlanRequest, *, on_cycle: Any, cancel: Any) -> dict[str, Any]:
    """A planner that publishes ``max_cycles`` cycles of 2 kB each, one every 0.2 ms."""
    pad = "x" * 2000
    for seq in range(1, request.max_cycles + 1):
        on_cycle({"seq": seq, "pad": pad})
        time.sleep(0.0002)
    return {"status": "success", "reason": "flooded", "cycles": request.max_cycles, "seed": request.seed}


@pytest.fixture
def slow_watcher(port: int) -> Any:
    """A second Zenoh session subscribed to every goal's messages, its callback blocking 5 s per sample."""
    session = zenoh.open(make_config(connect=[loopback(port)]))
    received: list[str] = []

    def blocking(sample: zenoh.Sample) -> None:
        received.append(str(sample.key_expr))
        time.sleep(5.0)

    # run in the thread that reads its link (as a client in C or Rust would): nothing drains it
    session.declare_subscriber(
        proto.goal_keys(proto.prefix()), zenoh.handlers.Callback(blocking, indirect=False)
    )
    # a round trip to the instance after the declaration: it now knows the subscriber
    list(session.get(proto.cancel_key(proto.prefix(), "sync-slow-watcher"), timeout=5))
    yield received
    session.close()


def test_a_watcher_that_never_drains_stalls_no_one_else(port, services, clients, slow_watcher):
    services(port, planner=flood, admission=None)
    owner = clients(port)
    other = clients(port)
    owner.wait_for_instances(1)
    other.wait_for_instances(1)
    took = []
    for k in range(6):  # 6 x 1000 cycles of 2 kB: far more than the slow watcher's link buffers
        t0 = time.monotonic()
        out = owner.plan(PlanRequest(max_cycles=1000, seed=k), watch=False, timeout=30)
        took.append(time.monotonic() - t0)
        assert out.status == "success"
        t0 = time.monotonic()
        small = other.plan(PlanRequest(max_cycles=3, seed=k), timeout=30)
        took.append(time.monotonic() - t0)
        assert small.status == "success" and small.complete  # its own stream whole
    assert slow_watcher  # the slow watcher did get messages (its callback runs)
    assert max(took) < 2.5, took  # a blocked put would wait 5 s (Zenoh's wait_before_close)


def test_default_goal_ids_cannot_be_squatted(port, services, clients):
    services(port, planner=slowed(root_plan, 0.15), workers=2, queue_size=8)
    owner = clients(port)
    squatter = clients(port)
    owner.wait_for_instances(1)
    squatter.wait_for_instances(1)
    seen: list[str] = []
    sub = squatter.watch(lambda kind, msg: seen.append(msg["goal_id"]) if kind == "status" else None)
    first = owner.plan(PlanRequest(max_cycles=2)).goal_id
    wait_until(lambda: first in seen, 5)
    assert first in seen  # goal ids are public
    stem, _, number = first.rpartition("-")
    guesses = [f"{stem}-{int(number) + i}" if number.isdigit() else f"{first}{i}" for i in (1, 2, 3)]
    squats = [
        threading.Thread(target=lambda g=g: squatter.plan(PlanRequest(max_cycles=10), goal_id=g, timeout=30))
        for g in guesses
    ]
    for t in squats:
        t.start()
    time.sleep(0.3)  # the squatters' goals are held (running or queued)
    failed = []
    for _ in range(3):
        try:
            assert owner.plan(PlanRequest(max_cycles=2), timeout=30).status
        except proto.RequestError as err:
            failed.append(err.code)
    sub.undeclare()
    for t in squats:
        t.join(30)
    assert failed == []


def test_a_default_goal_id_refused_as_a_duplicate_is_retried_with_another(
    port, services, clients, monkeypatch
):
    from eos_svc.service import client as client_module

    services(port, planner=slowed(root_plan, 0.15))
    owner = clients(port)
    squatter = clients(port)
    owner.wait_for_instances(1)
    held = threading.Thread(
        target=lambda: squatter.plan(PlanRequest(max_cycles=10), goal_id="g-taken", timeout=30)
    )
    held.start()
    time.sleep(0.3)
    draws = iter(["g-taken", "g-free"])
    monkeypatch.setattr(client_module, "new_goal_id", lambda: next(draws))
    out = owner.plan(PlanRequest(max_cycles=2), timeout=30)
    assert out.goal_id == "g-free" and out.status
    held.join(30)


def test_counters_agree_for_every_kind_of_query(port, services, clients):
    svc = services(port, planner=slowed(root_plan, 0.1))
    owner = clients(port)
    owner.wait_for_instances(1)
    done: dict[str, Any] = {}
    run = threading.Thread(
        target=lambda: done.setdefault("out", owner.plan(PlanRequest(max_cycles=20), goal_id="count-1"))
    )
    run.start()
    wait_until(lambda: svc.stats.received >= 1, 5)
    time.sleep(0.2)
    with pytest.raises(proto.RequestError) as info:  # a refused cancel
        owner.cancel("count-1", cancel_token="not-the-owners-token-000")
    assert info.value.code == proto.E_FORBIDDEN
    assert owner.cancel("nobody-has-this") is False  # a cancel of an unknown goal
    with pytest.raises(proto.RequestError):  # a refused plan
        owner.plan({"object": {"shape": "cube"}}, goal_id="count-2")
    run.join(30)
    assert done["out"].status
    stats = svc.stats
    assert (stats.received, stats.cancels) == (4, 2)  # 2 plans, 2 cancels
    assert stats.received == stats.replied_ok + stats.replied_err + getattr(stats, "left_to_peers", 0)


def test_every_goal_has_a_deadline_from_the_service(port, services, clients):
    services(port, planner=slowed(root_plan, 0.2), max_deadline_s=0.5)
    client = clients(port)
    client.wait_for_instances(1)
    statuses: list[dict[str, Any]] = []
    for deadline in (None, 100.0):
        statuses.clear()
        t0 = time.monotonic()
        out = client.plan(
            {"max_cycles": 1000, "deadline_s": deadline},
            on_cycle=lambda m: None,
            timeout=30,
        )
        assert out.status == "deadline" and time.monotonic() - t0 < 3.0
        assert out.final_status is not None and out.final_status["state"] == "done"


@pytest.mark.parametrize(("field", "value"), [("seed", 1e5), ("max_cycles", 5.0), ("seed", 7.0)])
def test_integer_fields_take_integers_only(field, value):
    payload = json.dumps({"schema": 1, "goal_id": "ints", field: value}).encode()
    with pytest.raises(proto.RequestError) as info:
        proto.decode_request(payload)
    assert info.value.code == proto.E_INVALID and info.value.field == field
    assert "integer" in info.value.reason


def _refusing_planner(request: PlanRequest, *, on_cycle: Any, cancel: Any) -> Any:
    raise ValidationError("object.radius", "this planner plans nothing")


@pytest.mark.parametrize("path", ["planned", "cancelled while queued", "refused by the planner"])
def test_every_path_a_worker_takes_publishes_running_then_done(path, port, services, clients):
    planner = _refusing_planner if path == "refused by the planner" else slowed(root_plan, 0.1)
    services(port, planner=planner, workers=1, queue_size=4, admission=None)
    client = clients(port)
    client.wait_for_instances(1)
    seen: list[tuple[str, dict[str, Any]]] = []
    sub = client.watch(lambda kind, msg: seen.append((kind, msg)))
    if path == "cancelled while queued":
        busy = threading.Thread(target=lambda: client.plan(PlanRequest(max_cycles=20), goal_id="ahead"))
        busy.start()
        time.sleep(0.3)
        queued = threading.Thread(
            target=lambda: client.plan(PlanRequest(max_cycles=20), goal_id="the-goal", watch=False)
        )
        queued.start()
        time.sleep(0.2)
        assert client.cancel("the-goal")
        queued.join(30)
        busy.join(30)
    elif path == "refused by the planner":
        with pytest.raises(proto.RequestError):
            client.plan(PlanRequest(max_cycles=3), goal_id="the-goal")
    else:
        client.plan(PlanRequest(max_cycles=3), goal_id="the-goal")
    wait_until(lambda: any(m.get("state") == "done" and m["goal_id"] == "the-goal" for _k, m in seen), 5)
    sub.undeclare()
    states = [m["state"] for kind, m in seen if kind == "status" and m["goal_id"] == "the-goal"]
    assert states == ["running", "done"]
    done = [m for kind, m in seen if kind == "status" and m["goal_id"] == "the-goal"][-1]
    expected = {"planned": None, "cancelled while queued": "cancelled", "refused by the planner": "refused"}
    if expected[path] is not None:
        assert done["status"] == expected[path]
    if path == "cancelled while queued":
        assert done["cycles"] == 0
