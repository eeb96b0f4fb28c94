"""A watcher sees a goal from its first message: ``watch()`` returns only after every live
instance has the subscriber (real Zenoh sessions on loopback; two instances, the second
connected through the first)."""

from __future__ import annotations

import threading
from typing import Any

from eos_svc.agents.request import PlanRequest
from tests.service.waiting import wait_until


def test_sync_with_instances_names_every_live_instance(port, services, clients):
    a = services(port)
    b = services(connect=(port,))
    client = clients(port)
    client.wait_for_instances(2)
    assert client.sync_with_instances(5.0) == sorted([a.instance, b.instance])
    assert a.stats.cancelled == b.stats.cancelled == 0


def test_a_watcher_sees_every_goal_from_its_running_status(port, services, clients):
    """Fresh watchers, each followed at once by a plan from another client: every goal's
    first message seen is its ``running`` status, on whichever instance it ran."""
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
        out = owner.plan(PlanRequest(max_cycles=3, seed=k), goal_id=f"w-{k}")
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
