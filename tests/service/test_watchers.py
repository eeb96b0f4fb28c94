"""Goal messages go out only while someone watches: a watcher that comes mid-plan gets the rest."""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterator
from types import SimpleNamespace
from typing import Any

import pytest
import zenoh

from eos_svc.records import CycleRecord
from eos_svc.schema.request import PlanRequest
from eos_svc.service import make_config
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import slowed
from eos_svc.service.goal_watchers import GoalWatchers
from eos_svc.service.wire_json import loads_strict
from tests.service.waiting import wait_until


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


def test_once_the_last_watcher_leaves_unwatched_plans_send_nothing(port, services, clients):
    """The flag the watch hint relies on turns false again (an exact reading after Zenoh's
    notice): plans whose owner does not watch then build and put no message."""
    svc = services(port)
    client = clients(port)
    watcher = clients(port)
    client.wait_for_instances(1)
    watcher.wait_for_instances(1)
    seen: queue.SimpleQueue[tuple[str, dict[str, Any]]] = queue.SimpleQueue()
    sub = watcher.watch(lambda kind, msg: seen.put((kind, msg)))
    out = client.plan(PlanRequest(max_cycles=3), goal_id="seen-1", watch=False)
    assert out.result["cycles_published"] == 3
    messages = [seen.get(timeout=10) for _ in range(5)]  # running, 3 cycles, done
    assert [m.get("state", m.get("seq")) for _kind, m in messages] == ["running", 1, 2, 3, "done"]
    sent = svc.stats.cycles_sent
    assert sent == 3
    sub.undeclare()
    assert wait_until(lambda: not svc._watched.any, 10)  # the listener's notice, then the exact reading
    out = client.plan(PlanRequest(max_cycles=3), goal_id="unseen-1", watch=False)
    assert out.result["cycles_published"] == 3
    assert svc.stats.cycles_sent == sent  # numbered, not sent


class _NoticesNeverCome:
    """An instance's watchers as if Zenoh's matching notices (and refreshes) had not come yet:
    the flag stays false; an exact reading still asks the routing tables."""

    any = False

    def __init__(self, real: GoalWatchers) -> None:
        self._real = real

    def watched(self, hint: bool | None) -> bool:
        return GoalWatchers.watched(self, hint)  # type: ignore[arg-type]

    def now(self) -> bool:
        self._real.refresh()
        return self._real.any

    def refresh(self) -> None:
        pass


def test_a_request_without_the_hint_is_watched_from_its_start(port, services, clients):
    """A client that does not send the ``watch`` hint (another language's, an older one) and
    subscribes just before its request gets every message: the instance asks Zenoh — even
    when no notice of that subscriber has come (the flag held false here)."""
    svc = services(port)
    svc._watched = _NoticesNeverCome(svc._watched)  # type: ignore[assignment]
    client = clients(port)
    client.wait_for_instances(1)
    session = client.session
    for k in range(3):
        seen: queue.SimpleQueue[Any] = queue.SimpleQueue()
        sub = session.declare_subscriber(
            proto.goal_keys(client.prefix, f"raw-{k}"), lambda sample, box=seen: box.put(sample)
        )
        payload = proto.encode_request(f"raw-{k}", PlanRequest(max_cycles=2, seed=k))
        assert b'"watch"' not in payload
        replies = list(
            session.get(proto.plan_key(client.prefix, client.instances()[0]), payload=payload, timeout=30)
        )
        assert len(replies) == 1 and replies[0].ok is not None
        first = loads_strict(seen.get(timeout=10).payload.to_bytes())
        sub.undeclare()
        assert first.get("state") == "running", first
    # the same with the hint false: the instance takes the sender's word and, knowing of no
    # other watcher, builds and sends nothing
    sent = svc.stats.cycles_sent
    out = client.plan(PlanRequest(max_cycles=2), goal_id="hint-false", watch=False)
    assert out.result["cycles_published"] == 2 and svc.stats.cycles_sent == sent


@pytest.fixture
def lone_watchers() -> Iterator[Callable[..., GoalWatchers]]:
    """Factory: a service's goal watchers on a Zenoh session of their own (no service); at the
    end, the real publisher put back where a test swapped it, undeclared, the session closed."""
    session = zenoh.open(make_config())
    made: list[tuple[GoalWatchers, Any]] = []

    def make(on_notice: Callable[[], None] = lambda: None) -> GoalWatchers:
        watchers = GoalWatchers(session, proto.prefix(None), on_notice)
        made.append((watchers, watchers._publisher))
        return watchers

    yield make
    for watchers, publisher in made:
        watchers._publisher = publisher
        watchers.undeclare()
    session.close()


def test_a_matching_notice_never_turns_the_flag_false_by_itself(lone_watchers):
    """Zenoh delivers matching notices from tasks it spawns, late and possibly out of order: a
    notice that says "matching" turns the flag true at once (a put too many costs little) and
    wakes nobody; one that says "nobody" asks for an exact reading (``refresh``), the only way
    the flag turns false."""
    notices: list[int] = []
    watchers = lone_watchers(lambda: notices.append(1))
    assert watchers.any is False  # read from the tables at once: nobody
    watchers.any = True
    notices.clear()
    watchers._on_status(SimpleNamespace(matching=False))  # a late notice of a watcher gone
    assert watchers.any is True and notices == [1]
    watchers.refresh()  # what the dispatcher runs for that notice: nobody matches
    assert watchers.any is False
    watchers._on_status(SimpleNamespace(matching=True))
    assert watchers.any is True and notices == [1]  # believed as it is


def test_a_stale_matching_notice_lasts_one_plan(port, services, clients):
    """A "matching" notice that came late (the watcher already gone) is believed only until the
    plan that found it ends: the instance then reads the tables."""
    svc = services(port)
    client = clients(port)
    client.wait_for_instances(1)
    svc._watched.any = True  # as a late "matching" notice would leave it, nobody subscribed
    client.plan(PlanRequest(max_cycles=2), goal_id="stale-1", watch=False)
    sent = svc.stats.cycles_sent
    assert sent == 2  # believed: built and put, to nobody
    assert wait_until(lambda: not svc._watched.any, 5)  # read after the reply
    client.plan(PlanRequest(max_cycles=2), goal_id="stale-2", watch=False)
    assert svc.stats.cycles_sent == sent


def test_a_matching_notice_during_a_reading_is_not_overwritten(lone_watchers):
    """The dispatcher reads "nobody" from the tables; a "matching" notice lands before it stores
    that answer: the reading is taken again (here the publisher's matching status is read
    through a property that delivers such a notice during the first reading)."""
    watchers = lone_watchers()
    real = watchers._publisher
    readings: list[bool] = []

    class NoticeDuringReading:
        @property
        def matching_status(self) -> Any:
            status = real.matching_status
            readings.append(bool(status.matching))
            if len(readings) == 1:  # the subscriber arrives, its notice with it
                watchers._on_status(SimpleNamespace(matching=True))
            return status

    watchers._publisher = NoticeDuringReading()
    watchers.refresh()
    assert readings == [False, False]  # read again after the notice
    assert watchers.any is False  # the tables' answer: the notice was made up here


def test_readings_are_taken_one_at_a_time(lone_watchers):
    """Zenoh releases the GIL while it reads the tables: a worker's reading of "nobody", taken
    before a watcher came but stored after the dispatcher's reading of "matching" (the watcher's
    sync), must not win. The tables here are a stand-in whose first reading, in the worker,
    pauses between reading and returning."""
    watchers = lone_watchers()
    read_nobody, resume = threading.Event(), threading.Event()

    class Tables:
        matching = False

        @property
        def matching_status(self) -> Any:
            value = self.matching
            if threading.current_thread().name == "worker" and not read_nobody.is_set():
                read_nobody.set()
                resume.wait(10)  # the worker's reading, late to be stored
            return SimpleNamespace(matching=value)

    tables = Tables()
    watchers._publisher = tables
    worker = threading.Thread(target=watchers.refresh, name="worker")
    worker.start()
    assert read_nobody.wait(10)
    tables.matching = True  # a watcher subscribes and syncs: the dispatcher reads the tables
    dispatcher = threading.Thread(target=watchers.refresh, name="dispatcher")
    dispatcher.start()
    dispatcher.join(0.3)  # with one reading at a time it waits for the worker's
    resume.set()
    worker.join(10)
    dispatcher.join(10)
    assert watchers.any is True


def test_a_watcher_zenoh_will_not_notify_again_is_counted_after_the_next_plan(port, services, clients):
    """Zenoh notifies only when its own matching state changes; a reading of ours taken between
    one watcher leaving and another coming can leave the flag false with Zenoh's state true (no
    notice will come). The worker reads the tables after a plan while Zenoh's last notice said
    "matching": here the flag is set false by hand under a bare subscriber (no sync)."""
    svc = services(port)
    client = clients(port)
    other = clients(port)
    client.wait_for_instances(1)
    sub = other.session.declare_subscriber(proto.goal_keys(other.prefix), lambda _sample: None)
    try:
        assert wait_until(lambda: svc._watched.zenoh_says_matching and svc._watched.any, 10)
        svc._watched.any = False  # as a reading left behind by Zenoh's state would leave it
        client.plan(PlanRequest(max_cycles=2), goal_id="unseen-2", watch=False)
        sent = svc.stats.cycles_sent
        assert wait_until(lambda: svc._watched.any, 5)  # read after that plan's reply
        client.plan(PlanRequest(max_cycles=2), goal_id="seen-2", watch=False)
        assert svc.stats.cycles_sent == sent + 2
    finally:
        sub.undeclare()
