"""The service against real Zenoh sessions on loopback (in-process instances in threads)."""

from __future__ import annotations

import json
import os
import threading
import time
from typing import Any

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import slowed
from eos_svc.service.instances import ServiceUnavailableError
from eos_svc.service.plan_attempt import PlanOutcome
from tests.service.threads import run_in_threads
from tests.service.waiting import wait_until

OK_STATUS = "completed" if os.environ.get("EOS_TEST_PLANNER") == "root" else "success"
STATUSES = {"success", "failed", "stalled", "cycle_limit", "deadline", "cancelled", "error", "completed"}


def assert_stream_complete(outcome: PlanOutcome) -> None:
    seqs = [m["seq"] for m in outcome.cycles]
    assert seqs == list(range(1, len(seqs) + 1)), "cycles out of order or missing"
    assert outcome.gaps == []
    assert outcome.final_status is not None and outcome.final_status["state"] == "done"
    assert outcome.final_status["status"] == outcome.result["status"]
    assert len(seqs) == outcome.result["cycles_published"]
    assert outcome.complete


def test_plan_end_to_end_with_the_grasp_planner(port, services, clients, grasp_planner):
    svc = services(port, planner=grasp_planner)
    client = clients(port)
    assert client.wait_for_instances(1) == [svc.instance]
    seen: list[dict[str, Any]] = []
    outcome = client.plan(PlanRequest(seed=3), goal_id="e2e-1", on_cycle=seen.append)
    assert outcome.goal_id == "e2e-1" and outcome.instance == svc.instance
    assert outcome.result["status"] in STATUSES
    assert outcome.result["seed"] == 3
    assert outcome.result["cycles"] >= 1
    assert_stream_complete(outcome)
    assert len(outcome.cycles) == outcome.result["cycles"]
    assert seen == outcome.cycles  # live callback: every cycle, in order
    rec = seen[0]["record"]
    assert rec["seq"] == 1 and {"stage", "ratings", "weights", "chosen", "outcome", "changes"} <= set(rec)
    assert svc.stats.replied_ok == 1


def test_same_request_same_cycles(port, services, clients, grasp_planner):
    services(port, planner=grasp_planner)
    client = clients(port)
    client.wait_for_instances(1)
    a = client.plan(PlanRequest(seed=5))
    b = client.plan(PlanRequest(seed=5))

    def strip(msgs: list[dict[str, Any]]) -> list[Any]:
        return [
            (m["seq"], m["record"]["chosen"], m["record"]["outcome"], m["record"]["detail"]) for m in msgs
        ]

    assert strip(a.cycles) == strip(b.cycles)
    assert a.result["status"] == b.result["status"]


MALFORMED: list[tuple[str, bytes | None, str, str]] = [
    ("not JSON", b"plan please", proto.E_NOT_JSON, "request"),
    ("not UTF-8", b"\xff\xfe{", proto.E_NOT_JSON, "request"),
    ("empty payload", None, proto.E_NOT_JSON, "request"),
    ("JSON array", b"[1, 2]", proto.E_INVALID, "request"),
    ("missing schema", b'{"goal_id": "g1"}', proto.E_SCHEMA, "schema"),
    ("wrong schema version", b'{"schema": 2, "goal_id": "g1"}', proto.E_SCHEMA, "schema"),
    ("schema as string", b'{"schema": "1", "goal_id": "g1"}', proto.E_SCHEMA, "schema"),
    ("missing goal id", b'{"schema": 1}', proto.E_INVALID, "goal_id"),
    ("goal id with wildcard", b'{"schema": 1, "goal_id": "a/**"}', proto.E_INVALID, "goal_id"),
    ("goal id a number", b'{"schema": 1, "goal_id": 7}', proto.E_INVALID, "goal_id"),
    ("seed a string", b'{"schema": 1, "goal_id": "g1", "seed": "seven"}', proto.E_INVALID, "seed"),
    ("NaN", b'{"schema": 1, "goal_id": "g1", "tactile_noise": NaN}', proto.E_NOT_JSON, "request"),
    ("Infinity", b'{"schema": 1, "goal_id": "g1", "deadline_s": Infinity}', proto.E_NOT_JSON, "request"),
    (
        "unknown shape",
        b'{"schema": 1, "goal_id": "g1", "object": {"shape": "torus", "radius": 0.03}}',
        proto.E_INVALID,
        "object.shape",
    ),
    (
        "missing size",
        b'{"schema": 1, "goal_id": "g1", "object": {"shape": "cylinder", "radius": 0.03}}',
        proto.E_INVALID,
        "object.length",
    ),
    ("unknown field", b'{"schema": 1, "goal_id": "g1", "colour": "red"}', proto.E_INVALID, "colour"),
    (
        "weights not summing to 1",
        b'{"schema": 1, "goal_id": "g1", "weights": {"default": 0.9, "opportunistic": 0.9}}',
        proto.E_INVALID,
        "weights",
    ),
    (
        "huge integer",
        b'{"schema": 1, "goal_id": "g1", "tactile_noise": 1' + b"0" * 400 + b"}",
        proto.E_INVALID,
        "tactile_noise",
    ),
    ("deep nesting", b"[" * 30_000 + b"]" * 30_000, proto.E_NOT_JSON, "request"),
    ("UTF-16", '{"schema": 1, "goal_id": "g1"}'.encode("utf-16"), proto.E_NOT_JSON, "request"),
    ("surrogate bytes", b'{"schema": 1, "goal_id": "g1", "x\xed\xa0\x80": 1}', proto.E_NOT_JSON, "request"),
    ("duplicate key", b'{"schema": 1, "goal_id": "g1", "seed": 1, "seed": 2}', proto.E_NOT_JSON, "seed"),
    (
        "5000-digit seed",
        b'{"schema": 1, "goal_id": "g1", "seed": ' + b"9" * 5000 + b"}",
        proto.E_INVALID,
        "seed",
    ),
    (
        "60,000-char field",
        b'{"schema": 1, "goal_id": "g1", "' + b"f" * 60_000 + b'": 1}',
        proto.E_INVALID,
        "fff",
    ),
    (
        "oversized",
        b'{"schema": 1, "goal_id": "g1", "pad": "' + b"x" * 70_000 + b'"}',
        proto.E_TOO_LARGE,
        "request",
    ),
]


@pytest.mark.parametrize(("name", "payload", "code", "field"), MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_request_gets_an_error_reply(name, payload, code, field, port, services, clients):
    svc = services(port)
    client = clients(port)
    client.wait_for_instances(1)
    kwargs = {} if payload is None else {"payload": payload}
    replies = list(client.session.get(proto.plan_key(client.prefix, svc.instance), timeout=5, **kwargs))
    assert len(replies) == 1, "exactly one reply"
    err = replies[0].err
    assert err is not None, f"{name}: expected an error reply"
    assert len(err.payload) <= 4096  # bounded, whatever the request echoes
    body = json.loads(err.payload.to_bytes())
    assert body["code"] == code
    assert body["field"].startswith(field)
    assert body["reason"]
    # the service keeps serving
    assert client.plan(PlanRequest(), instance=svc.instance).result["status"] == OK_STATUS


def test_a_burst_of_garbage_then_a_plan(port, services, clients):
    svc = services(port)
    client = clients(port)
    client.wait_for_instances(1)
    key = proto.plan_key(client.prefix, svc.instance)
    handlers = [client.session.get(key, payload=bytes([i % 256]) * (i + 1), timeout=5) for i in range(50)]
    assert all(len(list(h)) == 1 for h in handlers)
    assert client.plan(PlanRequest()).result["status"] == OK_STATUS
    assert svc.stats.replied_err == 50


def test_client_raises_the_error_reply(port, services, clients):
    services(port)
    client = clients(port)
    client.wait_for_instances(1)
    with pytest.raises(proto.RequestError) as info:
        client.plan({"object": {"shape": "sphere", "radius": -1.0}}, goal_id="neg")
    assert (info.value.code, info.value.field, info.value.goal_id) == (
        proto.E_INVALID,
        "object.radius",
        "neg",
    )


def test_cancel_a_running_plan_ends_within_a_cycle(port, services, clients, grasp_planner):
    svc = services(port, planner=slowed(grasp_planner, 0.02))
    client = clients(port)
    client.wait_for_instances(1)
    seen: list[int] = []
    box: dict[str, Any] = {}
    started = threading.Event()

    def on_cycle(msg: dict[str, Any]) -> None:
        seen.append(msg["seq"])
        if msg["seq"] >= 3:
            started.set()

    t = threading.Thread(
        target=lambda: box.setdefault(
            "out",
            client.plan(
                PlanRequest(max_cycles=100_000, deadline_s=60.0), goal_id="long-1", on_cycle=on_cycle
            ),
        )
    )
    t.start()
    assert started.wait(30), "the plan did not start"
    assert client.cancel("long-1")
    at_cancel = len(seen)
    t.join(10)
    assert not t.is_alive()
    out: PlanOutcome = box["out"]
    assert out.result["status"] == "cancelled"
    assert_stream_complete(out)
    # the cycle in progress may finish (and one may be in flight): never more
    assert out.result["cycles_published"] - at_cancel <= 2
    assert svc.stats.cancelled == 1


def test_cancel_a_queued_plan_and_an_unknown_goal(port, services, clients, grasp_planner):
    services(port, planner=slowed(grasp_planner, 0.05), workers=1, queue_size=4)
    client = clients(port)
    client.wait_for_instances(1)
    outs: dict[str, PlanOutcome] = {}
    threads = [
        threading.Thread(target=lambda g=g: outs.setdefault(g, client.plan(PlanRequest(), goal_id=g)))
        for g in ("first", "second")
    ]
    threads[0].start()
    time.sleep(0.2)
    threads[1].start()
    time.sleep(0.2)
    assert client.cancel("second")
    assert not client.cancel("never-sent")
    for t in threads:
        t.join(10)
    assert outs["second"].result["status"] == "cancelled" and outs["second"].result["cycles"] == 0
    assert outs["first"].result["status"] == OK_STATUS


def test_busy_past_the_queue_bound(port, services, clients, grasp_planner):
    svc = services(port, planner=slowed(grasp_planner, 0.02), workers=1, queue_size=1)
    client = clients(port)
    client.wait_for_instances(1)
    outs: list[Any] = []

    def ask(goal: str) -> None:
        try:
            outs.append(client.plan(PlanRequest(), goal_id=goal, instance=svc.instance, max_attempts=1))
        except proto.RequestError as err:
            outs.append(err)

    run_in_threads(ask, (f"b{i}" for i in range(4)), 15, stagger=0.03)
    busy = [o for o in outs if isinstance(o, proto.RequestError)]
    done = [o for o in outs if isinstance(o, PlanOutcome)]
    assert len(outs) == 4 and len(done) == 2 and len(busy) == 2
    assert all(e.code == proto.E_BUSY and "busy" in e.reason for e in busy)
    assert client.plan(PlanRequest()).status == OK_STATUS  # still serving


def test_duplicate_goal_id_is_refused(port, services, clients, grasp_planner):
    services(port, planner=slowed(grasp_planner, 0.05))
    client = clients(port)
    client.wait_for_instances(1)
    t = threading.Thread(target=lambda: client.plan(PlanRequest(), goal_id="dup"))
    t.start()
    time.sleep(0.2)
    with pytest.raises(proto.RequestError) as info:
        client.plan(PlanRequest(), goal_id="dup")
    assert info.value.code == proto.E_DUPLICATE
    t.join(10)


def test_concurrent_plans_all_answered_with_complete_streams(port, services, clients, grasp_planner):
    svc = services(port, planner=slowed(grasp_planner, 0.002), workers=3)
    client = clients(port)
    client.wait_for_instances(1)
    outs: list[PlanOutcome] = []
    lock = threading.Lock()

    def run(i: int) -> None:
        out = client.plan(PlanRequest(seed=i), goal_id=f"c{i}")
        with lock:
            outs.append(out)

    run_in_threads(run, range(8), 20)
    assert sorted(o.goal_id for o in outs) == sorted(f"c{i}" for i in range(8))
    for o in outs:
        assert_stream_complete(o)
    assert svc.stats.replied_ok == 8


def test_discovery_and_spreading_over_two_instances(port, services, clients, grasp_planner):
    a = services(port, planner=slowed(grasp_planner, 0.002))
    b = services(connect=(port,), planner=slowed(grasp_planner, 0.002))
    client = clients(port)
    assert client.wait_for_instances(2) == sorted([a.instance, b.instance])
    assert client.discover() == sorted([a.instance, b.instance])
    outs: list[PlanOutcome] = []
    run_in_threads(lambda i: outs.append(client.plan(PlanRequest(), goal_id=f"s{i}")), range(8), 20)
    used = {o.instance for o in outs}
    assert used == {a.instance, b.instance}
    assert a.stats.replied_ok >= 2 and b.stats.replied_ok >= 2
    for o in outs:
        assert_stream_complete(o)
    b.stop()
    wait_until(lambda: b.instance not in client.instances(), 5, interval=0.02)
    assert client.instances() == [a.instance]


def test_retry_on_another_instance_when_one_goes_away(port, services, clients, grasp_planner):
    a = services(port, planner=slowed(grasp_planner, 0.05))
    b = services(connect=(port,), planner=slowed(grasp_planner, 0.05))
    client = clients(port)
    client.wait_for_instances(2)
    box: dict[str, Any] = {}
    first = threading.Event()

    def on_cycle(msg: dict[str, Any]) -> None:
        box.setdefault("first_instance", msg["instance"])
        first.set()

    t = threading.Thread(
        target=lambda: box.setdefault("out", client.plan(PlanRequest(), goal_id="move", on_cycle=on_cycle))
    )
    t.start()
    assert first.wait(10)
    victim = a if box["first_instance"] == a.instance else b
    victim.stop()
    t.join(15)
    out: PlanOutcome = box["out"]
    assert out.instance != victim.instance
    assert out.attempts == 2
    assert out.result["status"] == OK_STATUS
    assert_stream_complete(out)  # the survivor's stream, from seq 1


def test_no_instance_raises_service_unavailable(port, clients):
    client = clients(port)
    with pytest.raises(ServiceUnavailableError):
        client.plan(PlanRequest(), timeout=1.0)


def test_namespaces_are_separate(port, services, clients):
    services(port, namespace="lab-a")
    client_b = clients(port, namespace="lab-b")
    client_a = clients(port, namespace="lab-a")
    client_a.wait_for_instances(1)
    assert client_b.discover(timeout=0.3) == []
    assert client_a.plan(PlanRequest()).status == OK_STATUS


def test_zenoh_sessions_have_multicast_scouting_off():
    from eos_svc.service.session import make_config

    conf = make_config(listen=["tcp/127.0.0.1:7447"])
    assert json.loads(conf.get_json("scouting/multicast/enabled")) is False
    assert json.loads(conf.get_json("mode")) == "peer"
    assert json.loads(conf.get_json("listen/endpoints")) == ["tcp/127.0.0.1:7447"]
