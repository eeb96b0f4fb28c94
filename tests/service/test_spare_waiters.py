"""A client reuses an attempt's waiter (queue, Zenoh handler, cancellation token) once its query
has ended, and never one whose query is still running (eos_svc.service.client._Waiter)."""

from __future__ import annotations

import time

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import _END, _Waiter
from eos_svc.service.demo_planner import root_plan
from tests.service.threads import run_in_threads

ONE = PlanRequest(seed=3, max_cycles=1)


def _wait_ended(waiter: _Waiter, timeout: float = 5.0) -> None:
    """Until the waiter's query has ended (its ``_END`` queued), without taking anything."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if waiter.events.qsize():
            return
        time.sleep(0.005)
    raise AssertionError("the query did not end")


def test_sequential_plans_reuse_one_waiter_and_get_their_own_replies(port, services, clients):
    services(port, planner=root_plan)
    client = clients(port)
    client.wait_for_instances(1)
    seen: set[int] = set()
    for seed in range(6):
        outcome = client.plan(PlanRequest(seed=seed, max_cycles=2), watch=False)
        assert outcome.result["seed"] == seed and outcome.result["cycles"] == 2
        assert len(client._spare_waiters) == 1
        waiter = client._spare_waiters[0]
        seen.add(id(waiter))
        _wait_ended(waiter)
    assert len(seen) == 1  # one waiter served all six
    # a stream's attempt builds its own (its subscriber puts into the queue) and keeps none
    outcome = client.plan(ONE, watch=True)
    assert outcome.complete and len(client._spare_waiters) == 1


def test_a_waiter_whose_query_is_running_is_not_reused(port, services, clients):
    services(port, planner=root_plan)
    client = clients(port)
    client.wait_for_instances(1)
    client.plan(ONE, watch=False)
    spare = client._spare_waiters[0]
    _wait_ended(spare)
    # a query still running: its _END not yet put (a stale "lost" notice already in the queue)
    running = _Waiter()
    running.events.put(("lost", "inst-x"))
    client._spare_waiters[:] = [running]
    fresh = client._waiter()
    assert fresh is not running and client._spare_waiters == [running]
    assert running.events.qsize() == 0  # the stale notice was dropped
    running.events.put(_END)  # its query ends
    assert client._waiter() is running and not client._spare_waiters
    assert running.events.qsize() == 0


def test_concurrent_plans_through_one_client_never_share_a_waiter(port, services, clients):
    services(port, planner=root_plan, workers=4)
    client = clients(port)
    client.wait_for_instances(1)
    errors: list[BaseException] = []
    results: dict[int, int] = {}

    def work(k: int) -> None:
        try:
            for i in range(8):
                seed = 100 * k + i
                out = client.plan(PlanRequest(seed=seed, max_cycles=1), watch=False)
                results[seed] = out.result["seed"]
        except BaseException as exc:
            errors.append(exc)

    run_in_threads(work, range(4), 60)
    assert not errors
    assert results == {s: s for s in results} and len(results) == 32  # each its own reply
    assert len(client._spare_waiters) <= 8


def test_a_refused_request_leaves_a_reusable_waiter(port, services, clients):
    services(port, planner=root_plan)
    client = clients(port)
    client.wait_for_instances(1)
    try:
        client.plan({"seed": -1}, watch=False)
    except proto.RequestError as err:
        assert err.field == "seed"
    else:  # pragma: no cover - the service must refuse it
        raise AssertionError("a negative seed was accepted")
    assert len(client._spare_waiters) == 1
    out = client.plan(ONE, watch=False)  # served by the same waiter once the refusal's query ended
    assert out.result["cycles"] == 1


def test_a_waiter_whose_query_was_never_issued_is_not_kept(port, services, clients):
    """No query, no ``_END`` ever: such a waiter would stay unusable in the spare list."""
    services(port, planner=root_plan)
    client = clients(port)
    client.wait_for_instances(1)
    payload = proto.encode_request("g-never-1", ONE, proto.new_cancel_token())
    with pytest.raises(Exception):  # noqa: B017 - Zenoh's own error for an invalid key expression
        client._attempt("a*b", "g-never-1", payload, None, False, 1.0)  # no such key: get never runs
    assert client._spare_waiters == []
    assert client.plan(ONE, watch=False).result["cycles"] == 1  # and the client goes on
