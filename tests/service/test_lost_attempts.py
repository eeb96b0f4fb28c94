"""An attempt whose instance does not answer is lost and tried on another instance: its
liveliness token withdrawn while it holds the query, or the query timed out (Zenoh's own
``Timeout`` error reply, not the service's: never an ``internal_error``); with and without the
cycle stream."""

from __future__ import annotations

import threading
from typing import Any

import pytest
import zenoh

from eos_svc.schema.request import PlanRequest
from eos_svc.service import ServiceUnavailableError, loopback, make_config
from eos_svc.service import client as client_module
from eos_svc.service import protocol as proto
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


def _asked(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The instances the client's attempts query, in order: a spy on the real
    :class:`~eos_svc.service.plan_attempt.Attempt` (each query is still sent)."""
    asked: list[str] = []
    real = client_module.Attempt

    def spy(session: Any, prefix: str, iid: str, *rest: Any) -> Any:
        asked.append(iid)
        return real(session, prefix, iid, *rest)

    monkeypatch.setattr(client_module, "Attempt", spy)
    return asked


def _settled(client: Any) -> bool:
    """No attempt of the client registered (each one counts as a plan in flight)."""
    return not client._instances._waiters


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
        assert started.wait(60), "the plan did not reach the stuck instance"
        token = stuck._entities[-1]  # its liveliness token, declared last
        assert type(token).__name__ == "LivelinessToken"
        token.undeclare()
        t.join(60)  # returns as soon as the plan is done: long only on a loaded machine
        assert not t.is_alive(), "the client did not give up on the stuck instance"
    finally:
        release.set()
    out = box["out"]
    assert out.instance == "b-fine" and out.attempts == 2 and out.result["cycles"] == 1
    assert wait_until(lambda: _settled(client), 5)


@pytest.mark.parametrize("watch", [False, True])
def test_an_instance_that_times_out_is_not_asked_again(port, services, clients, watch, monkeypatch):
    """Zenoh's own ``Timeout`` reply loses the attempt (never an ``internal_error``), and the
    instance, which may still hold the goal, is not asked again by this call (it would refuse
    the goal id as a duplicate): with one instance, the default three attempts end in
    ServiceUnavailableError after one query."""
    release, started = threading.Event(), threading.Event()
    svc = services(port, planner=_held_planner(release, started))
    client = clients(port)
    (iid,) = client.wait_for_instances(1)
    asked = _asked(monkeypatch)
    try:
        with pytest.raises(ServiceUnavailableError, match="no reply within the query's timeout"):
            client.plan(ONE, watch=watch, timeout=0.5)
        assert asked == [iid]  # one query of the three attempts allowed, no more
        # the query reaches the instance (late, on a loaded machine): counted once, never refused
        assert started.wait(30) and wait_until(lambda: svc.stats.received == 1, 30)
    finally:
        release.set()
    assert svc.stats.received == 1 and svc.stats.replied_err == 0
    assert _settled(client)


def test_every_instance_timed_out_is_tried_once(port, services, clients, monkeypatch):
    release = threading.Event()
    a = services(port, planner=_held_planner(release, threading.Event()), instance="a")
    b = services(None, (port,), planner=_held_planner(release, threading.Event()), instance="b")
    client = clients(port)
    client.wait_for_instances(2)
    asked = _asked(monkeypatch)
    try:
        with pytest.raises(ServiceUnavailableError, match="no reply within the query's timeout"):
            client.plan(ONE, watch=False, timeout=0.5)
        assert sorted(asked) == ["a", "b"]  # each once, then no attempt left to anyone
        assert wait_until(lambda: (a.stats.received, b.stats.received) == (1, 1), 30)
    finally:
        release.set()
    assert (a.stats.received, b.stats.received) == (1, 1)
    assert a.stats.replied_err == b.stats.replied_err == 0


def test_an_instances_own_error_reply_saying_timeout_is_a_refusal(port, clients):
    """Only Zenoh's timeout (its own encoding) is a lost attempt: an instance's JSON error reply
    whose payload reads "Timeout" stays what the instance said."""
    session = zenoh.open(make_config(listen=[loopback(port)]))
    try:
        prefix = proto.prefix(None)

        def refuse(query: zenoh.Query) -> None:
            query.reply_err(b"Timeout", encoding=zenoh.Encoding.APPLICATION_JSON)
            query.drop()

        qable = session.declare_queryable(proto.plan_key(prefix, "fake-1"), refuse, complete=True)
        token = session.liveliness().declare_token(proto.instance_key(prefix, "fake-1"))
        client = clients(port)
        client.wait_for_instances(1)
        with pytest.raises(proto.RequestError) as err:
            client.plan(ONE, watch=False, timeout=2.0)
        assert err.value.code == proto.E_INTERNAL and "Timeout" in err.value.reason
        token.undeclare()
        qable.undeclare()
    finally:
        session.close()
