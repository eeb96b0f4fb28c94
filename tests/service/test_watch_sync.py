"""A watcher sees a goal from its first message: ``watch()`` returns only after every live
instance has the subscriber (real Zenoh sessions on loopback; two instances, the second
connected through the first)."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from tests.service.waiting import wait_until


def test_sync_with_instances_names_every_live_instance(port, services, clients):
    a = services(port)
    b = services(connect=(port,))
    client = clients(port)
    client.wait_for_instances(2)
    assert client.sync_with_instances(5.0) == sorted([a.instance, b.instance])
    assert a.stats.cancelled == b.stats.cancelled == 0


@pytest.mark.parametrize("owner_watches", [True, False], ids=["owner-watches", "owner-does-not"])
def test_a_watcher_sees_every_goal_from_its_running_status(port, services, clients, owner_watches):
    """Fresh watchers, each followed at once by a plan from another client: every goal's
    first message seen is its ``running`` status, on whichever instance it ran — also when
    the owner says it does not watch (its ``watch`` hint false: the instance does not ask
    Zenoh, it counts the watcher from the sync's refresh)."""
    services(port)
    services(connect=(port,))
    owner = clients(port)
    owner.wait_for_instances(2)
    for k in range(20):
        watcher = clients(port)
        watcher.wait_for_instances(2)
        seen: list[tuple[str, dict[str, Any]]] = []
        lock = threading.Lock()

        def on_message(kind: str, msg: dict[str, Any], box: list = seen, guard: Any = lock) -> None:
            with guard:
                box.append((kind, msg))

        sub = watcher.watch(on_message)
        out = owner.plan(PlanRequest(max_cycles=3, seed=k), goal_id=f"w-{k}", watch=owner_watches)
        assert out.status == "cycle_limit"

        def ended(box: list = seen, guard: Any = lock) -> bool:
            with guard:
                return any(kd == "status" and m.get("state") == "done" for kd, m in box)

        wait_until(ended, 5)  # the done status travels to the watcher on its own route
        sub.undeclare()
        with lock:
            mine = [(kd, m) for kd, m in seen if m.get("goal_id") == f"w-{k}"]
        assert mine and mine[0][0] == "status" and mine[0][1]["state"] == "running", mine[:2]
        assert mine[-1][1]["state"] == "done"
        assert [m["seq"] for kd, m in mine if kd == "cycle"] == list(range(1, len(mine) - 1))


def test_a_sync_sets_the_watchers_flag_from_the_routing_tables(port, services, clients):
    """The sync's cancel query makes the instance read its watchers exactly before it answers,
    whatever Zenoh's matching notices said so far (they come late, from tasks Zenoh spawns):
    here the flag is set wrong by hand, and each sync sets it right."""
    svc = services(port)
    client = clients(port)
    client.wait_for_instances(1)
    sub = client.session.declare_subscriber(proto.goal_keys(client.prefix), lambda _sample: None)
    for _ in range(3):
        svc._watched.any = False  # as if the notice of this subscriber had not come yet
        assert client.sync_with_instances(5.0) == [svc.instance]
        assert svc._watched.any is True
    sub.undeclare()
    assert wait_until(lambda: not svc._watched.any, 10)
    svc._watched.any = True  # as if a late notice had said "matching"
    assert client.sync_with_instances(5.0) == [svc.instance]
    assert svc._watched.any is False
