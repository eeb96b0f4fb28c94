"""Speed of the EOS Zenoh service on loopback (one command).

    .venv/bin/python benchmarks/bench_service.py [--quick]

1. Round-trip overhead of a plan request over the same plan called in-process:
   medians of interleaved runs (service: ``eos serve`` in another process,
   grasp planner, client in this process), for a 1-cycle plan (where the
   overhead is not lost in the plan's own noise), without and with the live
   cycle stream, and for a whole default plan with its stream. A bare Zenoh
   queryable round trip is printed for reference. Goal: ≤ 1 ms median.
2. Throughput (plans/s) with one and with two service processes on this
   machine, the same plans sent by concurrent client threads. Goal: ≥ 1.7×.

Loopback only (tcp/127.0.0.1), multicast scouting off.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import queue
import resource
import statistics
import sys
import threading
import time

import zenoh

from eos_svc.agents.planner import plan
from eos_svc.agents.request import PlanRequest
from eos_svc.service import EosClient, free_port, loopback, make_config
from eos_svc.service.reliability import start_servers, stop_servers


def median_ms(xs: list[float]) -> float:
    return statistics.median(xs) * 1e3


def bare_zenoh_round_trip(n: int) -> float:
    """Median round trip (ms) of a get to a queryable answering at once (own thread), loopback, 2 sessions."""
    port = free_port()
    server = zenoh.open(make_config(listen=[loopback(port)]))
    client = zenoh.open(make_config(connect=[loopback(port)]))
    inbox: queue.SimpleQueue[zenoh.Query | None] = queue.SimpleQueue()

    def answer() -> None:
        while (q := inbox.get()) is not None:
            q.reply(q.key_expr, b"ok")
            q.drop()

    worker = threading.Thread(target=answer, daemon=True)
    worker.start()
    qable = server.declare_queryable("bench/rt", zenoh.handlers.Callback(inbox.put, indirect=False))
    time.sleep(0.3)
    ts = []
    for _ in range(n):
        t0 = time.perf_counter()
        replies = list(client.get("bench/rt", payload=b"x", timeout=5))
        ts.append(time.perf_counter() - t0)
        assert len(replies) == 1
    qable.undeclare()
    inbox.put(None)
    client.close()
    server.close()
    return median_ms(ts[n // 10 :])


def overhead(client: EosClient, request: PlanRequest, n: int, watch: bool) -> tuple[float, float, int]:
    """Interleaved medians (ms): in-process plan, service round trip; and the plan's cycles."""
    local, remote = [], []
    cycles = 0
    for i in range(n + 5):
        t0 = time.perf_counter()
        plan(request, keep_trace=False)
        t1 = time.perf_counter()
        out = client.plan(request, watch=watch)
        t2 = time.perf_counter()
        if watch:
            assert out.complete
        cycles = out.result["cycles"]
        if i >= 5:  # warm-up
            local.append(t1 - t0)
            remote.append(t2 - t1)
    return median_ms(local), median_ms(remote), cycles


def throughput(
    n_servers: int, requests: list[PlanRequest], threads: int, workers: int
) -> tuple[float, dict[str, float]]:
    """Plans per second through ``n_servers`` service processes, ``threads`` concurrent client threads."""
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    servers = start_servers(n_servers, planner="grasp", workers=workers)
    try:
        client = EosClient.open(make_config(connect=[loopback(s.port) for s in servers]))
        client.wait_for_instances(n_servers, timeout=15)
        for r in requests[: 2 * n_servers]:  # warm-up: imports and first plans in every process
            client.plan(r, watch=False)
        todo: queue.SimpleQueue[PlanRequest] = queue.SimpleQueue()
        for r in requests:
            todo.put(r)
        used: dict[str, float] = {}
        lock = threading.Lock()

        def work() -> None:
            while True:
                try:
                    r = todo.get_nowait()
                except queue.Empty:
                    return
                out = client.plan(r, watch=False)
                with lock:
                    used[out.instance] = used.get(out.instance, 0) + 1

        pool = [threading.Thread(target=work) for _ in range(threads)]
        t0 = time.perf_counter()
        for t in pool:
            t.start()
        for t in pool:
            t.join()
        wall = time.perf_counter() - t0
        client.close()
    finally:
        stop_servers(servers)
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # the servers' CPU time, once they are reaped
    used["cpu_s"] = round(cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime, 1)
    return len(requests) / wall, used


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    args = parser.parse_args()
    n_rt = 60 if args.quick else 150
    n_tp = 24 if args.quick else 60
    version = importlib.metadata.version("eclipse-zenoh")
    print(
        f"bench_service: {os.cpu_count()} CPU(s), Python {sys.version.split()[0]}, eclipse-zenoh {version}, "
        f"load average {os.getloadavg()[0]:.2f} (other processes share these CPUs)"
    )
    bare = bare_zenoh_round_trip(500)
    print(f"bare Zenoh get->reply round trip (two sessions, one process): {bare:.3f} ms median")

    servers = start_servers(1, planner="grasp", workers=1)
    try:
        client = EosClient.open(make_config(connect=[loopback(servers[0].port)]))
        client.wait_for_instances(1, timeout=15)
        rows: list[tuple[str, float, float, int]] = []
        one = PlanRequest(seed=3, max_cycles=1)
        for label, req, n, watch in (
            ("1-cycle plan, no stream", one, n_rt, False),
            ("1-cycle plan, live stream", one, n_rt, True),
            ("default plan (seed 3), live stream", PlanRequest(seed=3), max(10, n_rt // 10), True),
        ):
            loc, rem, cyc = overhead(client, req, n, watch)
            rows.append((label, loc, rem, cyc))
        client.close()
    finally:
        stop_servers(servers)
    print("\n1. round-trip overhead over the in-process plan (medians of interleaved runs)")
    print(f"   {'case':<38} {'in-process':>11} {'service':>9} {'overhead':>9} {'cycles':>7}")
    for label, loc, rem, cyc in rows:
        print(f"   {label:<38} {loc:9.2f}ms {rem:7.2f}ms {rem - loc:7.2f}ms {cyc:7d}")
    goal = rows[0][2] - rows[0][1]
    print(f"   goal ≤ 1 ms median overhead (1-cycle plan, no stream): {'met' if goal <= 1.0 else 'NOT met'}")

    seeds = [1, 2, 3, 4, 6, 7]  # plans of 50-120 cycles
    requests = [PlanRequest(seed=seeds[i % len(seeds)]) for i in range(n_tp)]
    print(f"\n2. throughput: {n_tp} plans (seeds {seeds}), 4 client threads, no stream")
    ratios = {}
    for workers in (1, 2):
        rates: dict[int, float] = {}
        for k in (1, 2):
            rate, used = throughput(k, requests, threads=4, workers=workers)
            rates[k] = rate
            print(
                f"   workers={workers}, {k} process(es): {rate:6.2f} plans/s   plans per instance, "
                f"server CPU s: {used}"
            )
        ratios[workers] = rates[2] / rates[1]
        print(f"   workers={workers}: two processes / one = {ratios[workers]:.2f}x")
    print(
        f"   goal ≥ 1.7x from one to two processes (one worker each): "
        f"{'met' if ratios[1] >= 1.7 else 'NOT met'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
