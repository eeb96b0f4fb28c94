"""Goal messages go out only while someone watches: a watcher that comes mid-plan gets the rest."""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any

from eos_svc.agents.request import PlanRequest
from eos_svc.records import CycleRecord
from eos_svc.service.demo_planner import slowed


def signalling(planner: Callable[..., Any], after: int, event: threading.Event) -> Callable[..., Any]:
    """``planner`` setting ``event`` once the service has been handed cycle ``after``."""

    def plan(request: PlanRequest, *, on_cycle: Callable[[CycleRecord], None], **kwargs: Any) -> Any:
        count = 0

        def cycle(record: CycleRecord) -> None:
            nonlocal count
            on_cycle(record)
            count += 1
            if count == after:
                event.set()

        return planner(request, on_cycle=cycle, **kwargs)

    return plan


def test_a_watcher_that_comes_mid_plan_gets_the_rest_numbered(port, services, clients, grasp_planner):
    fifth = threading.Event()
    svc = services(port, planner=signalling(slowed(grasp_planner, 0.02), 5, fifth))
    client = clients(port)
    client.wait_for_instances(1)
    box: dict[str, Any] = {}
    asker = threading.Thread(
        target=lambda: box.setdefault(
            "out",
            client.plan(PlanRequest(max_cycles=100_000, deadline_s=60.0), goal_id="late-1", watch=False),
        )
    )
    asker.start()
    assert fifth.wait(30), "the plan did not start"
    seen: queue.SimpleQueue[tuple[str, dict[str, Any]]] = queue.SimpleQueue()
    watcher = client.watch(lambda kind, msg: seen.put((kind, msg)), goal_id="late-1")
    try:
        messages = [seen.get(timeout=30) for _ in range(8)]  # eight cycles of the running plan
        assert client.cancel("late-1")
        asker.join(30)
        out = box["out"]
        while messages[-1][0] != "status":  # the rest, up to the done status
            messages.append(seen.get(timeout=10))
    finally:
        watcher.undeclare()
    cycles = [m["seq"] for kind, m in messages if kind == "cycle"]
    statuses = [m for kind, m in messages if kind == "status"]
    assert out.result["status"] == "cancelled"
    # cycles 1-5 ran while nobody watched: numbered, never sent; from the watcher's arrival, every one
    assert cycles[0] > 5 and cycles == list(range(cycles[0], cycles[0] + len(cycles)))
    assert cycles[-1] == out.result["cycles_published"] == svc.stats.cycles_published
    assert svc.stats.cycles_sent == len(cycles)  # only the cycles put while watched
    assert [s["state"] for s in statuses] == ["done"]  # nobody watched at the start: no "running"
    assert statuses[0]["result"] == out.result
