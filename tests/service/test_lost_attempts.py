"""An attempt whose instance does not answer is lost and tried on another instance: its
liveliness token withdrawn while it holds the query, or the query timed out (Zenoh's own
``Timeout`` error reply, not the service's: never an ``internal_error``); with and without the
cycle stream."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from eos_svc.agents.request import PlanRequest
from eos_svc.service import ServiceUnavailableError
from eos_svc.service.demo_planner import root_plan
from tests.service.waiting import wait_until

ONE = PlanRequest(seed=3, max_cycles=1)


def _held_planner(release: threading.Event, started: threading.Event) -> Any:
    """The root planner, held before it plans until ``release`` is set (``started`` set on entry)."""

    def plan(request: PlanRequest, **kwargs: Any) -> Any:
        started.set()
        release.wait(30)
        return root_plan(request, **kwargs)

    return plan


def _settled(client: Any) -> bool:
    """No attempt of the client registered or counted in flight."""
    return not client._waiters and not any(client._inflight.values())


@pytest.mark.parametrize("watch", [False, True])
def test_a_withdrawn_token_loses_the_attempt_and_another_instance_plans(port, services, clients, watch):
    """The asked instance's liveliness token goes while it holds the query (no reply, its session
    still up): the client gives the attempt up and plans on the other instance."""
    release, started = threading.Event(), threading.Event()
    stuck = services(port, planner=_held_planner(release, started), instance="a-stuck")
    services(None, (port,), planner=root_plan, instance="b-fine")
    client = clients(port)
    client.wait_for_instances(2)
    box: dict[str, Any] = {}
    # a new client's first choice is the first instance by id, a-stuck
    t = threading.Thread(
        target=lambda: box.update(out=client.plan(ONE, watch=watch, max_attempts=2)), daemon=True
    )
    t.start()
    try:
        assert started.wait(10), "the plan did not reach the stuck instance"
        token = stuck._entities[-1]  # its liveliness token, declared last
        token.undeclare()
        t.join(15)
        assert not t.is_alive(), "the client did not give up on the stuck instance"
    finally:
        release.set()
    out = box["out"]
    assert out.instance == "b-fine" and out.attempts == 2 and out.result["cycles"] == 1
    assert wait_until(lambda: _settled(client), 5)


@pytest.mark.parametrize("watch", [False, True])
def test_a_query_that_times_out_is_lost_not_an_internal_error(port, services, clients, watch):
    release, started = threading.Event(), threading.Event()
    services(port, planner=_held_planner(release, started))
    client = clients(port)
    client.wait_for_instances(1)
    try:
        with pytest.raises(ServiceUnavailableError, match="no reply before the timeout"):
            client.plan(ONE, watch=watch, timeout=0.5, max_attempts=1)
    finally:
        release.set()
    assert _settled(client)
