"""A reliability run: other clients' plan times with and without a watcher that never drains.

One ``eos serve`` process (two workers); ``clients`` client threads, each its own session, plan
without pause (watching their own goals) for ``window_s`` seconds; then the same load again while
a second session subscribed to every goal's messages blocks 5 s in every sample's callback (run
in the thread that reads its link: nothing drains it, as a stuck client in any language). The
check: other clients' p99 plan time with the slow watcher within 1.5× of the one without, every
plan answered, every client's own cycle stream whole.
"""

from __future__ import annotations

import statistics
import threading
import time
from collections import Counter

import zenoh
from abuse import Probe
from serve_processes import counters_consistent, start_servers, stop_servers

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import EosClient
from eos_svc.service.session import loopback, make_config

#: what the slow watcher's callback blocks per sample (s)
BLOCK_S = 5.0
#: the p99 plan time with the slow watcher may be at most this many times the one without
P99_BOUND = 1.5


def _load(clients: list[EosClient], window_s: float, codes: Counter[str]) -> tuple[list[float], int]:
    """Every client plans without pause for ``window_s`` seconds; the plan times (s) and how many
    own streams were not whole."""
    times: list[float] = []
    broken = [0]
    lock = threading.Lock()
    end = time.monotonic() + window_s

    def work(ci: int, client: EosClient) -> None:
        k = 0
        while time.monotonic() < end:
            k += 1
            t0 = time.monotonic()
            try:
                out = client.plan(PlanRequest(seed=1 + (ci + k) % 7), timeout=30)
            except Exception as exc:
                with lock:
                    codes["error: " + getattr(exc, "code", type(exc).__name__)] += 1
                continue
            with lock:
                times.append(time.monotonic() - t0)
                codes[out.status] += 1
                broken[0] += not out.complete

    threads = [threading.Thread(target=work, args=(i, c), daemon=True) for i, c in enumerate(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(window_s + 60)
    return times, broken[0]


def _p99(times: list[float]) -> float:
    ordered = sorted(times)
    return ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))] if ordered else float("nan")


def run_slow_watcher(*, window_s: float = 20.0, clients: int = 4, planner: str = "grasp") -> Probe:
    """The run above as one row of the reliability table."""
    servers = start_servers(1, planner=planner)
    endpoints = [loopback(servers[0].port)]
    sessions = [EosClient.open(make_config(connect=endpoints)) for _ in range(clients)]
    slow = zenoh.open(make_config(connect=endpoints))
    got: list[int] = []
    probe = Probe(f"slow watcher ({BLOCK_S:g} s per sample), {window_s:g} s")
    try:
        for c in sessions:
            c.wait_for_instances(1, timeout=15)
            c.plan(PlanRequest(seed=1))  # warm
        alone, broken_alone = _load(sessions, window_s, probe.codes)

        def blocking(_sample: zenoh.Sample) -> None:
            got.append(1)
            time.sleep(BLOCK_S)

        slow.declare_subscriber(
            proto.goal_keys(proto.prefix()), zenoh.handlers.Callback(blocking, indirect=False)
        )
        list(slow.get(proto.cancel_key(proto.prefix(), "sync-slow-watcher"), timeout=5))  # it knows it now
        watched, broken_watched = _load(sessions, window_s, probe.codes)
    finally:
        for c in sessions:
            c.close()
        slow.close()
        stop_servers(servers)
    probe.sent = probe.answered_once = len(alone) + len(watched)
    failed = [code for code in probe.codes if code.startswith("error: ")]
    ratio = _p99(watched) / _p99(alone)
    stats = servers[0].stats
    consistent = stats is not None and counters_consistent(stats)
    probe.ok = ratio <= P99_BOUND and not broken_alone + broken_watched and consistent and not failed
    probe.detail = (
        f"other clients' plans: without it median {statistics.median(alone) * 1e3:.0f} ms, p99 "
        f"{_p99(alone) * 1e3:.0f} ms ({len(alone)} plans); with it median "
        f"{statistics.median(watched) * 1e3:.0f} ms, p99 {_p99(watched) * 1e3:.0f} ms "
        f"({len(watched)} plans): "
        f"p99 {ratio:.2f}x (bound {P99_BOUND}x); own streams not whole {broken_alone + broken_watched}; "
        f"the slow watcher took {len(got)} samples; counters consistent: {consistent}"
    )
    return probe
