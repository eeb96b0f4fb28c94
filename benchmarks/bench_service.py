"""Speed of the EOS Zenoh service on loopback (one command).

    .venv/bin/python benchmarks/bench_service.py [--quick] [--only overhead|scale-out] [--breakdown]

1. Round-trip overhead of a plan request over the same plan called in-process,
   medians of interleaved runs (service: ``eos serve`` in another process, one
   worker, grasp planner; client in this process), for a 1-cycle plan (where the
   per-request overhead is not lost in the plan's own noise), without and with
   the live cycle stream, and for a whole default plan with its stream.

   The baseline is ``plan(request, keep_trace=False)`` in this process with no
   cycle callback: what a caller pays without the service. Everything the
   service adds counts as overhead: encoding, sending, decoding and validating
   the request, the hand-off to a worker, deciding whether anyone watches the
   goal (the request's watch hint, which the client sends; the ``running`` and
   ``done`` status messages and every cycle are built and published only when
   some subscriber matches; with "no stream" nobody subscribes, with "live
   stream" the client does), the result to JSON,
   the reply and its parsing. Measured in the same loop: a bare
   Zenoh get→reply to a queryable in another process answering from its own
   thread, with a request and a reply of the same sizes as the plan's (the
   transport floor in the same conditions). Goal: the 1-cycle plan's
   overhead (no stream) ≤ 2× that bare get→reply. Then, each in a loop of its
   own: a plain get to the service with the request encoded beforehand and the
   reply not parsed (the service without the client library), and a bare
   get→reply whose queryable runs the same plan first (no service code: the
   floor of this measure).
2. Scale-out: plans per second with one and with two service processes (one
   worker each), the same plans sent by concurrent client threads, in
   alternating batches on the same two processes ("one": every plan to the
   first, the second idle; "two": spread over both), so both figures share the
   machine's conditions; median of the per-round ratios, after a warm-up that
   lasts until both processes have loaded the fit's compiled kernels (a background
   thread of each at its start; this process loads them too). Peer to peer and
   through a router (a Python Zenoh router process; instances and the client
   are Zenoh clients of it). Goal: ≥ 1.8× from one to two processes. Where the
   time goes: each plan's own duration in its process (``wall_time_s``) with
   one and with two processes busy, the fraction of each process's time spent
   planning, and the CPU time per plan of the service processes, the client and
   the router (``/proc``): which of them saturates, if any. Each round also plans
   the same requests in two plain planner processes (no service, no Zenoh; one
   alone, then both) right after the service's batches: their two / one is what
   the machine's two cores gave the planner itself in those minutes.

``--breakdown`` times one request's path across both processes (timestamps on
the monotonic clock, which both share) and prints the median of every step; then
it times the bare get->reply and the planning one (no service code) the same way
and prints the steps they share with the service's request beside the service's:
the transport legs, the answering thread's wake-up, the plan, the reply call, the
client's wake-up. What the service adds is the rest.

Loopback only (tcp/127.0.0.1), multicast scouting off.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import queue
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import zenoh
from serve_processes import Server, start_servers, stop_servers

from eos_svc.agents.planner import plan
from eos_svc.schema.request import PlanRequest
from eos_svc.service import EosClient, free_port, loopback, make_config
from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback
from eos_svc.service.wire_json import encode_result
from eos_svc.shape import kernels


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


def _wait_for(stop: threading.Event, limit_s: float) -> None:
    """Until ``stop`` is set (by the SIGTERM handler) or ``limit_s`` passes: short waits, so a
    handler that ran in the middle of one long ``Event.wait`` cannot leave it waiting to the end."""
    end = time.monotonic() + limit_s
    while not stop.is_set() and time.monotonic() < end:
        time.sleep(0.05)


#: default size of the echo server's reply (bytes): about a 1-cycle plan's reply
ECHO_REPLY_BYTES = 1600


def echo_server(
    port: int, reply_bytes: int = ECHO_REPLY_BYTES, plan_first: bool = False, stamps_out: str | None = None
) -> None:
    """``--echo-server``: a queryable answering every get at once from its own thread (loopback).

    ``plan_first``: the answering thread runs the 1-cycle plan (``PlanRequest(seed=3,
    max_cycles=1)``, no admission check, as the service runs it) before each reply: a bare
    get->reply carrying the same work as the service's, without any service code.
    ``stamps_out``: stamp the steps the service's probe stamps too (the queryable's callback, a
    Python function in Zenoh's thread as the service's; the answering thread's wake-up; the
    reply call) and write them to this file at SIGTERM (``--breakdown``)."""
    work = PlanRequest(seed=3, max_cycles=1)
    if plan_first:
        plan(work, keep_trace=False, check=False)  # warm: the hand, the fit
    if stamps_out is not None:
        sys.setswitchinterval(0.001)  # as eos serve
    session = zenoh.open(make_config(listen=[loopback(port)]))
    inbox: queue.SimpleQueue[zenoh.Query] = queue.SimpleQueue()

    def stamped_put(query: zenoh.Query) -> None:
        _stamp("callback")
        inbox.put(query)

    qable = session.declare_queryable(
        "bench/echo",
        direct_callback(stamped_put if stamps_out else inbox.put),
        complete=True,
    )
    body = b"x" * reply_bytes
    stamp = _stamp if stamps_out else lambda _label: None
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())

    def answer() -> None:
        while True:
            q = inbox.get()
            stamp("worker")
            if plan_first:
                plan(work, keep_trace=False, check=False)
            stamp("reply0")
            q.reply("bench/echo", body)
            stamp("reply1")
            q.drop()

    threading.Thread(target=answer, daemon=True).start()
    print("echo ready", flush=True)
    _wait_for(stop, 600)  # bounded: the benchmark ends it long before
    qable.undeclare()
    session.close()
    if stamps_out is not None:
        with open(stamps_out, "w") as f:
            json.dump(_STAMPS, f)


def start_echo(
    reply_bytes: int, plan_first: bool = False, stamps_out: str | None = None
) -> tuple[subprocess.Popen[str], zenoh.Session]:
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, __file__, "--echo-server", str(port), str(reply_bytes)]
        + (["--plan-first"] if plan_first else [])
        + (["--stamps", stamps_out] if stamps_out else []),
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and "echo ready" in proc.stdout.readline()
    session = zenoh.open(make_config(connect=[loopback(port)]))
    time.sleep(0.3)
    return proc, session


def echo_round_trip(
    session: zenoh.Session, payload: bytes, key: Any = "bench/echo", stamped: bool = False
) -> float:
    """One get->reply to the echo server (s), through a callback and a queue as the client does
    (``key``: another queryable's, e.g. a service instance's plan key). ``stamped``
    (``--breakdown``): stamp ``get0``, ``reply_cb`` (in a Python callback in Zenoh's thread, as
    the client library's reply is stamped) and ``end``."""
    events: queue.SimpleQueue[Any] = queue.SimpleQueue()

    def stamped_put(reply: Any) -> None:
        _stamp("reply_cb")
        events.put(reply)

    t0 = time.perf_counter()
    if stamped:
        _stamp("get0")
    session.get(
        key,
        direct_callback(stamped_put, lambda: events.put(None))
        if stamped
        else zenoh.handlers.Callback(events.put, lambda: events.put(None), indirect=False),
        payload=payload,
        consolidation=zenoh.ConsolidationMode.NONE,
        timeout=5,
    )
    reply = events.get(timeout=5)
    dt = time.perf_counter() - t0
    if stamped:
        _stamp("end")
    assert reply is not None and reply.ok is not None, reply
    while events.get(timeout=5) is not None:
        pass
    return dt


def plan_reply_bytes(instance: str, result: dict[str, Any]) -> int:
    """Bytes of the service's reply to a plan whose result is ``result`` (what the echo sends)."""
    done = {"schema": 1, "goal_id": "g-" + "0" * 24, "instance": instance, "state": "done"}
    return len(
        encode_result(
            {**done, "status": result.get("status"), "cycles": result.get("cycles"), "result": result}
        )
    )


def request_bytes(request: PlanRequest) -> bytes:
    """``request`` as ``EosClient.plan(request, watch=False)`` sends it (goal id of the same
    length, a cancel token, the watch hint)."""
    return proto.encode_request("g-000000000000-1", request, proto.new_cancel_token(), False)


def echo_payload(request: PlanRequest) -> bytes:
    """The bare get->reply's request: as many bytes as ``request``'s plan request."""
    return b"x" * len(request_bytes(request))


def interleaved(
    request: PlanRequest, echo: zenoh.Session, n: int, round_trip: Callable[[int], float]
) -> tuple[float, float, float]:
    """Interleaved medians (ms): the in-process plan, ``round_trip(i)`` right after it (the i-th
    round trip under test, s), then another in-process plan (the echo, too, right after one) and
    the bare echo; the first five rounds are warm-up."""
    local, tested, bare = [], [], []
    payload = echo_payload(request)
    for i in range(n + 5):
        t0 = time.perf_counter()
        plan(request, keep_trace=False)
        t1 = time.perf_counter()
        rt_tested = round_trip(i)
        plan(request, keep_trace=False)
        rt = echo_round_trip(echo, payload)
        if i >= 5:
            local.append(t1 - t0)
            tested.append(rt_tested)
            bare.append(rt)
    return median_ms(local), median_ms(tested), median_ms(bare)


def overhead(
    client: EosClient, echo: zenoh.Session, request: PlanRequest, n: int, watch: bool
) -> tuple[float, float, float, int]:
    """:func:`interleaved` medians of the service round trip (``client.plan``); and the plan's cycles."""
    cycles = 0

    def service_round_trip(_: int) -> float:
        nonlocal cycles
        t0 = time.perf_counter()
        out = client.plan(request, watch=watch)
        dt = time.perf_counter() - t0
        if watch:
            assert out.complete
        cycles = out.result["cycles"]
        return dt

    local, remote, bare = interleaved(request, echo, n, service_round_trip)
    return local, remote, bare, cycles


def planning_echo(
    echo: zenoh.Session, echo_planning: zenoh.Session, request: PlanRequest, n: int
) -> tuple[float, float, float]:
    """:func:`interleaved` medians of the echo that runs the same plan before replying. A loop of
    its own, after the service's: a plan in another process between the service's requests
    would change them."""
    payload = echo_payload(request)
    return interleaved(request, echo, n, lambda _: echo_round_trip(echo_planning, payload))


def raw_service(
    client: EosClient, echo: zenoh.Session, request: PlanRequest, n: int
) -> tuple[float, float, float]:
    """:func:`interleaved` medians of a plain get to the service's instance with the request
    encoded first (a fresh goal id and cancel token each and the client's watch hint, outside the
    timing) and its reply's bytes not parsed — the service without the client library. A loop
    of its own, after the service's, on the same client session."""
    key = proto.plan_key(client.prefix, client.instances()[0])

    def raw_get(i: int) -> float:
        payload = proto.encode_request(f"g-raw{i:08d}-1", request, proto.new_cancel_token(), False)
        return echo_round_trip(client.session, payload, key)

    return interleaved(request, echo, n, raw_get)


def start_router() -> tuple[subprocess.Popen[str], int]:
    """A Python Zenoh router process on loopback (``python -m eos_svc.service.router``)."""
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "eos_svc.service.router", "--listen", loopback(port)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and "running" in proc.stdout.readline()
    return proc, port


def start_clients_of(router_port: int, n: int, workers: int) -> list[Server]:
    """``n`` ``eos serve`` processes as Zenoh clients of the router."""
    servers = []
    for i in range(n):
        cmd = [
            sys.executable, "-m", "eos_svc.cli", "serve", "--mode", "client",
            "--connect", loopback(router_port), "--instance", f"inst-{i}", "--workers", str(workers),
            "--log-level", "warning",
        ]  # fmt: skip
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert proc.stdout is not None and "serving" in proc.stdout.readline()
        servers.append(Server(router_port, proc, f"inst-{i}"))
    return servers


@dataclass
class Batch:
    """One batch of plans: its rate and where the time went."""

    rate: float  #: plans per second
    wall_s: float  #: the batch's duration (s)
    plan_s: list[float]  #: each plan's own duration in its service process (``wall_time_s``)
    processes: int  #: service processes the batch used
    cpu_s: dict[str, float]  #: CPU time used during the batch (s): "client", "services", "router"

    @property
    def busy(self) -> float:
        """Fraction of the processes' time spent planning (1: never idle)."""
        return sum(self.plan_s) / (self.wall_s * self.processes)


def _cpu_s(pid: int) -> float:
    """CPU time (user + system, s) a process has used so far (Linux ``/proc``)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _batch(
    client: EosClient,
    requests: list[PlanRequest],
    threads: int,
    instance: str | None,
    pids: dict[str, list[int]],
) -> Batch:
    """``requests`` sent by ``threads`` client threads (to ``instance`` only, or spread over every
    instance); ``pids``: the processes whose CPU time to count, by role."""
    todo: queue.SimpleQueue[PlanRequest] = queue.SimpleQueue()
    for r in requests:
        todo.put(r)
    plan_s: list[float] = []
    used: set[str] = set()

    def work() -> None:
        while True:
            try:
                r = todo.get_nowait()
            except queue.Empty:
                return
            out = client.plan(r, watch=False, instance=instance)
            plan_s.append(float(out.result["wall_time_s"]))
            used.add(out.instance)

    def cpu() -> dict[str, float]:
        out = {role: sum(_cpu_s(p) for p in ps) for role, ps in pids.items()}
        return out | {"client": time.process_time()}

    pool = [threading.Thread(target=work) for _ in range(threads)]
    cpu0 = cpu()
    t0 = time.perf_counter()
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    wall = time.perf_counter() - t0
    cpu1 = cpu()
    return Batch(len(requests) / wall, wall, plan_s, len(used), {k: cpu1[k] - cpu0[k] for k in cpu1})


def plain_planner() -> None:
    """``--plain-planner``: plans with no service around them: every line on stdin is a seed,
    planned (the default request otherwise), then ``done``."""
    plan(PlanRequest(seed=1), keep_trace=False)  # warm: the hand, the fit (kernels loaded by main)
    print("planner ready", flush=True)
    for line in sys.stdin:
        plan(PlanRequest(seed=int(line)), keep_trace=False)
        print("done", flush=True)


class PlainPlanners:
    """Two :func:`plain_planner` processes: the scale-out's plans in the first alone or spread over
    both, timed in the same rounds as the service's batches — what this machine's two cores give
    the planner by itself then (the ceiling of the service's two / one)."""

    def __init__(self) -> None:
        self.procs = [
            subprocess.Popen(
                [sys.executable, __file__, "--plain-planner"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )
            for _ in range(2)
        ]
        for proc in self.procs:
            assert proc.stdout is not None and "planner ready" in proc.stdout.readline()

    def rate(self, seeds: list[int], processes: int) -> float:
        """Plans per second of ``seeds`` in the first process alone (1) or over both (2), each
        process taking the next seed when it is done with one (as the service's workers do)."""
        todo: queue.SimpleQueue[int] = queue.SimpleQueue()
        for seed in seeds:
            todo.put(seed)

        def feed(proc: subprocess.Popen[str]) -> None:
            assert proc.stdin is not None and proc.stdout is not None
            while True:
                try:
                    seed = todo.get_nowait()
                except queue.Empty:
                    return
                proc.stdin.write(f"{seed}\n")
                proc.stdin.flush()
                assert proc.stdout.readline().strip() == "done"

        feeders = [threading.Thread(target=feed, args=(proc,)) for proc in self.procs[:processes]]
        t0 = time.perf_counter()
        for t in feeders:
            t.start()
        for t in feeders:
            t.join()
        return len(seeds) / (time.perf_counter() - t0)

    def close(self) -> None:
        for proc in self.procs:
            if proc.stdin is not None:
                proc.stdin.close()
            proc.wait(10)


#: seconds from a service process's start to the end of the scale-out's warm-up: each process
#: loads the fit's compiled kernels in a background thread when it starts (1-2 s here, from
#: numba's cache on disk, which this process's own ``kernels.load()`` writes if it is missing),
#: and no batch should share the cores with that
KERNELS_LOAD_S = 3.0


def scale_out(
    requests: list[PlanRequest],
    threads: int,
    rounds: int,
    via_router: bool = False,
    plain: PlainPlanners | None = None,
) -> tuple[list[Batch], list[Batch], list[float]]:
    """Plans/s with one and with two service processes, in alternating batches on the same two
    processes (one worker each): "one" sends every plan to inst-0 (inst-1 idles), "two" spreads
    them. Peer to peer, or every session a Zenoh client of a router process. Returns the batches
    of each round: (one, two), and ``plain``'s two / one in each round (after the service's
    batches; empty without ``plain``)."""
    router = None
    if via_router:
        router, router_port = start_router()
        servers = start_clients_of(router_port, 2, workers=1)
        config = make_config(mode="client", connect=[loopback(router_port)])
    else:
        servers = start_servers(2, planner="grasp", workers=1)
        config = make_config(connect=[loopback(s.port) for s in servers])
    started = time.monotonic()
    one: list[Batch] = []
    two: list[Batch] = []
    ceiling: list[float] = []
    try:
        client = EosClient.open(config)
        client.wait_for_instances(2, timeout=15)
        warm = 0  # first plans in both processes, until their fit's kernels have loaded
        while warm < 4 or time.monotonic() - started < KERNELS_LOAD_S:
            client.plan(requests[warm % len(requests)], watch=False)
            warm += 1
        pids = {"services": [s.proc.pid for s in servers]}
        if router is not None:
            pids["router"] = [router.pid]
        seeds = [r.seed for r in requests]
        for _ in range(rounds):
            one.append(_batch(client, requests, threads, servers[0].instance, pids))
            two.append(_batch(client, requests, threads, None, pids))
            if plain is not None:
                alone = plain.rate(seeds, 1)  # in the order of the service's batches: one, then two
                ceiling.append(plain.rate(seeds, 2) / alone)
        client.close()
    finally:
        stop_servers(servers)
        if router is not None:
            router.terminate()
            router.wait(10)
    return one, two, ceiling


# ---------------------------------------------------------------------------------------- --breakdown
_STAMPS: list[tuple[str, int]] = []


def _stamp(label: str) -> None:
    _STAMPS.append((label, time.perf_counter_ns()))  # CLOCK_MONOTONIC: comparable across processes


def _timed(owner: Any, name: str, before: str, after: str) -> None:
    """Wrap ``owner.name`` with two stamps."""
    f = getattr(owner, name)

    def wrapper(*a: Any, **k: Any) -> Any:
        _stamp(before)
        try:
            return f(*a, **k)
        finally:
            _stamp(after)

    setattr(owner, name, wrapper)


class _Proxy:
    """Forwards to a Zenoh object, stamping the calls named in ``stamps``."""

    def __init__(self, target: Any, stamps: dict[str, Any]) -> None:
        self._t, self._s = target, stamps

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._t, name)
        if name not in self._s:
            return attr
        label = self._s[name]

        def call(*a: Any, **k: Any) -> Any:
            tag = label(a) if callable(label) else label
            _stamp(tag + "0")
            out = attr(*a, **k)
            _stamp(tag + "1")
            return out

        return call


def probe_server(port: int, out: str) -> None:
    """``--probe-server``: a one-worker grasp service with timestamps on every step."""
    from eos_svc.service import goal_stream
    from eos_svc.service import protocol as proto
    from eos_svc.service import server as srv
    from eos_svc.service.goal_watchers import GoalWatchers

    sys.setswitchinterval(0.001)  # as eos serve
    _timed(proto, "decode_envelope", "decode0", "decode1")
    _timed(goal_stream, "encode_result", "json0", "json1")  # the done message (the reply)
    _timed(GoalWatchers, "watched", "watch0", "watch1")

    from eos_svc.schema.result import PlanResult

    _timed(PlanResult, "to_dict", "to_dict0", "to_dict1")  # the service calls to_dict(jsonable=False)

    def planner(request: Any, *, on_cycle: Any, cancel: Any, keep_trace: bool) -> Any:
        def cycle(rec: Any) -> None:
            _stamp("cycle0")
            on_cycle(rec)
            _stamp("cycle1")

        _stamp("plan0")
        r = plan(request, on_cycle=cycle, cancel=cancel, keep_trace=keep_trace, check=False)
        _stamp("plan1")
        return r

    class Probed(srv.PlanService):
        def _on_plan(self, query: Any) -> None:
            _stamp("callback")
            super()._on_plan(_Proxy(query, {"reply": "reply", "drop": "drop"}))
            _stamp("admitted")

        def _run(self, job: Any) -> None:
            _stamp("worker")
            super()._run(job)
            _stamp("worker_end")

    from eos_svc.service.planners import default_admission

    check = default_admission()

    def admission(request: Any) -> None:  # the service's admission, as eos serve runs it
        _stamp("admission0")
        check(request)
        _stamp("admission1")

    session = zenoh.open(make_config(listen=[loopback(port)]))
    service = Probed(session, instance="probe", planner=planner, workers=1, admission=admission)
    service.session = _Proxy(  # type: ignore[assignment]
        session,
        {
            "declare_publisher": "declare",
            "put": lambda a: (
                "running"
                if b'"state":"running"' in bytes(a[1])
                else "done"
                if b'"state":"done"' in bytes(a[1])
                else "cycleput"
            ),
        },
    )
    service.start()
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    print("probe ready", flush=True)
    _wait_for(stop, 600)  # bounded: the benchmark ends it long before
    service.stop()
    session.close()
    with open(out, "w") as f:
        json.dump(_STAMPS, f)


#: (from, to, what) — the steps of one request, in order
_STEPS = [
    ("start", "encode0", "client: before encoding (goal id, options)"),
    ("encode0", "encode1", "client: request to JSON"),
    ("encode1", "get0", "client: choose instance, waiter, callbacks"),
    ("get0", "callback", "transport: get -> server callback (GIL taken)"),
    ("callback", "decode0", "server: payload bytes, counters"),
    ("decode0", "decode1", "server: decode + validate request"),
    ("admission0", "admission1", "server: admission (check_plannable)"),
    ("admission1", "admitted", "server: job, queue"),
    ("admitted", "worker", "server: wake the worker thread"),
    ("worker", "watch0", "server: message heads"),
    ("watch0", "watch1", "server: anyone watching? (the hint; no hint: Zenoh)"),
    ("running0", "running1", "server: put status running"),
    ("plan0", "plan1", "plan in the server (incl. cycles)"),
    ("cycle0", "cycle1", "  of which: cycle 1 to JSON + put"),
    ("to_dict0", "to_dict1", "server: PlanResult.to_dict (members as held)"),
    ("json0", "json1", "server: result to JSON"),
    ("done0", "done1", "server: put status done"),
    ("reply0", "reply1", "server: query.reply call"),
    ("reply0", "reply_cb", "transport: reply -> client callback (GIL taken)"),
    ("reply_cb", "loads0", "client: wake the waiting thread"),
    ("loads0", "loads1", "client: parse the reply"),
    ("loads1", "end", "client: outcome, clean-up"),
    ("reply1", "drop1", "server: query.drop (after the reply)"),
    ("drop1", "worker_end", "server: undeclare publisher, counters (after the reply)"),
]


#: the steps a planning echo (no service code) shares with the service's request: (from, to,
#: what, the service's step in _STEPS)
_ECHO_STEPS = [
    ("get0", "callback", "transport: get -> server callback (GIL taken)", ("get0", "callback")),
    ("callback", "worker", "server: queue, wake the answering thread", ("admitted", "worker")),
    ("worker", "reply0", "plan in the server", ("plan0", "plan1")),
    ("reply0", "reply1", "server: query.reply call", ("reply0", "reply1")),
    ("reply0", "reply_cb", "transport: reply -> client callback (GIL taken)", ("reply0", "reply_cb")),
    ("reply_cb", "end", "client: wake the waiting thread", ("reply_cb", "loads0")),
]


def _step_medians(
    starts: list[int], server_stamps: list[tuple[str, int]], steps: list[tuple[str, str]], skip: int
) -> dict[tuple[str, str], float]:
    """Median µs of every step in ``steps`` over the requests after the first ``skip``: the
    client's stamps of a request run from its index in ``starts`` (into ``_STAMPS``), the
    server's from its ``callback`` stamp."""
    client_runs = [_STAMPS[a:b] for a, b in zip(starts, [*starts[1:], len(_STAMPS)], strict=True)]
    server_runs: list[list[tuple[str, int]]] = []
    for label, t in server_stamps:
        if label == "callback":
            server_runs.append([])
        if server_runs:
            server_runs[-1].append((label, t))
    found: dict[tuple[str, str], list[float]] = defaultdict(list)
    for c_run, s_run in list(zip(client_runs, server_runs, strict=False))[skip:]:
        first: dict[str, int] = {}
        for label, t in c_run + s_run:
            first.setdefault(label, t)
        for a, b in steps:
            if a in first and b in first:
                found[(a, b)].append((first[b] - first[a]) / 1e3)
    return {step: statistics.median(times) for step, times in found.items()}


def _stamps_file(prefix: str) -> str:
    """A new empty file for a server process's stamps (``--stamps`` / ``--probe-server``)."""
    fd, out = tempfile.mkstemp(prefix=prefix, suffix=".json")
    os.close(fd)
    return out


def _stop_for_stamps(proc: subprocess.Popen[str], out: str) -> list[tuple[str, int]]:
    """Stop a server process (SIGTERM: it writes its stamps to ``out`` as it ends); its stamps."""
    proc.send_signal(signal.SIGTERM)
    proc.wait(30)
    with open(out) as f:
        stamps = [(label, t) for label, t in json.load(f)]
    os.unlink(out)
    return stamps


def _echo_steps(
    n: int, reply_bytes: int, plan_first: bool
) -> tuple[float, float, dict[tuple[str, str], float]]:
    """The echo's round trip and its time over the in-process plan (ms), and its steps (µs):
    ``n`` gets, each right after an in-process plan, as :func:`breakdown` times the service's;
    the reply taken by a Python callback in Zenoh's thread, as the client library's is stamped.
    ``plan_first``: the planning echo (see :func:`echo_server`)."""
    out = _stamps_file("eos-echo-")
    proc, session = start_echo(reply_bytes, plan_first=plan_first, stamps_out=out)
    request = PlanRequest(seed=3, max_cycles=1)
    payload = echo_payload(request)
    starts: list[int] = []
    trips, over = [], []
    try:
        for i in range(n + 10):
            t0 = time.perf_counter()
            plan(request, keep_trace=False)
            t1 = time.perf_counter()
            starts.append(len(_STAMPS))
            trip = echo_round_trip(session, payload, stamped=True)
            if i >= 10:
                trips.append(trip)
                over.append(trip - (t1 - t0))
    finally:
        session.close()
        server_stamps = _stop_for_stamps(proc, out)
    steps = _step_medians(starts, server_stamps, [(a, b) for a, b, _, _ in _ECHO_STEPS], 10)
    return median_ms(trips), median_ms(over), steps


def breakdown(n: int) -> None:
    """Time the steps of ``n`` 1-cycle requests (no stream), interleaved with in-process plans;
    then the steps a bare and a planning get->reply share with them, timed the same way."""
    from eos_svc.service import plan_attempt as cli
    from eos_svc.service import protocol as proto

    out = _stamps_file("eos-probe-")
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, __file__, "--probe-server", str(port), out], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None and "probe ready" in proc.stdout.readline()
    _timed(proto, "encode_request", "encode0", "encode1")
    _timed(cli, "loads_strict", "loads0", "loads1")
    direct = cli.direct_callback

    def stamped_callback(cb: Any, drop: Any = None) -> Any:
        def f(x: Any) -> None:
            _stamp("reply_cb")
            cb(x)

        return direct(f, drop)

    cli.direct_callback = stamped_callback  # type: ignore[assignment]
    client = EosClient.open(make_config(connect=[loopback(port)]))
    client.session = _Proxy(client.session, {"get": "get"})  # type: ignore[assignment]
    client.wait_for_instances(1, timeout=15)
    request = PlanRequest(seed=3, max_cycles=1)
    local, remote = [], []
    starts = []
    for i in range(n + 10):
        t0 = time.perf_counter_ns()
        plan(request, keep_trace=False)
        t1 = time.perf_counter_ns()
        starts.append(len(_STAMPS))
        _stamp("start")
        outcome = client.plan(request, watch=False)
        _stamp("end")
        if i >= 10:
            local.append(t1 - t0)
            remote.append(_STAMPS[-1][1] - t1)
    reply_bytes = plan_reply_bytes("probe", outcome.result)  # the echoes answer with as many bytes
    client.close()
    cli.direct_callback = direct  # type: ignore[assignment]
    server_stamps = _stop_for_stamps(proc, out)
    steps = _step_medians(starts, server_stamps, [(a, b) for a, b, _ in _STEPS], 10)
    m = statistics.median
    print(
        f"breakdown of a 1-cycle plan request, no stream ({n} requests, medians; "
        f"load average {os.getloadavg()[0]:.2f}):"
    )
    print(
        f"   in-process plan {m(local) / 1e6:.2f} ms, service {m(remote) / 1e6:.2f} ms, "
        f"overhead {(m(remote) - m(local)) / 1e6:.2f} ms"
    )
    for a, b, what in _STEPS:
        if (a, b) in steps:
            print(f"   {what:<50} {steps[(a, b)]:8.0f} µs")
    bare_trip, _, bare_steps = _echo_steps(n, reply_bytes, plan_first=False)
    _, echo_over, echo_steps = _echo_steps(n, reply_bytes, plan_first=True)
    print(
        f"the same steps of a bare get->reply ({bare_trip:.2f} ms) and of one whose queryable runs the same "
        f"plan first ({echo_over:.2f} ms over the in-process plan), each right after an in-process plan: "
        f"no service code; {n} requests each, medians"
    )
    print(f"   {'step':<50} {'bare':>8}    {'planning':>8}    {'service':>8}")
    for a, b, what, service_step in _ECHO_STEPS:
        if (a, b) in echo_steps and service_step in steps:
            bare = f"{bare_steps[(a, b)]:8.0f} µs" if (a, b) in bare_steps else f"{'-':>8}   "
            print(f"   {what:<50} {bare} {echo_steps[(a, b)]:8.0f} µs {steps[service_step]:8.0f} µs")


def overhead_part(n_rt: int) -> None:
    """Part 1: the round-trip overhead of a plan request over the in-process plan."""
    bare = bare_zenoh_round_trip(500)
    print(f"bare Zenoh get->reply round trip, back to back (two sessions, one process): {bare:.3f} ms median")

    servers = start_servers(1, planner="grasp", workers=1)
    echo_proc = floor_proc = None
    echo = echo_planning = None
    try:
        client = EosClient.open(make_config(connect=[loopback(servers[0].port)]))
        client.wait_for_instances(1, timeout=15)
        # the echo answers with as many bytes as a 1-cycle plan's reply
        reply_bytes = plan_reply_bytes(
            servers[0].instance, client.plan(PlanRequest(seed=3, max_cycles=1), watch=False).result
        )
        echo_proc, echo = start_echo(reply_bytes)
        rows: list[tuple[str, float, float, float, int]] = []
        one = PlanRequest(seed=3, max_cycles=1)
        for label, req, n, watch in (
            ("1-cycle plan, no stream", one, n_rt, False),
            ("1-cycle plan, live stream", one, n_rt, True),
            ("default plan (seed 3), live stream", PlanRequest(seed=3), max(10, n_rt // 10), True),
        ):
            loc, rem, bare_rt, cyc = overhead(client, echo, req, n, watch)
            rows.append((label, loc, rem, bare_rt, cyc))
        server_alone = raw_service(client, echo, one, n_rt)
        client.close()
        floor_proc, echo_planning = start_echo(reply_bytes, plan_first=True)  # only now: see planning_echo
        floor = planning_echo(echo, echo_planning, one, n_rt)
    finally:
        stop_servers(servers)
        for proc, session in ((echo_proc, echo), (floor_proc, echo_planning)):
            if session is not None:
                session.close()
            if proc is not None:
                proc.terminate()
                proc.wait(10)
    print("\n1. round-trip overhead over the in-process plan (medians of interleaved runs)")
    print(
        "   in-process: plan(request, keep_trace=False), no cycle callback; overhead = service - in-process,"
    )
    print(
        "   i.e. everything the service adds; cycles and status are built and published only when "
        "someone subscribes (live stream)"
    )
    print(
        f"   {'case':<38} {'in-process':>11} {'service':>9} {'overhead':>9} {'cycles':>7} "
        f"{'bare get->reply':>16}"
    )
    for label, loc, rem, bare_rt, cyc in rows:
        print(f"   {label:<38} {loc:9.2f}ms {rem:7.2f}ms {rem - loc:7.2f}ms {cyc:7d} {bare_rt:14.2f}ms")
    ratio = (rows[0][2] - rows[0][1]) / rows[0][3]
    print(
        f"   1-cycle plan, no stream: overhead / bare get->reply = {ratio:.2f}x "
        f"(request {len(request_bytes(one))} B, "
        f"reply {reply_bytes} B); goal ≤ 2x: {'met' if ratio <= 2.0 else 'NOT met'}"
    )
    per_cycle = (rows[2][2] - rows[2][1] - (rows[1][2] - rows[1][1])) / max(1, rows[2][4] - 1)
    print(
        f"   streaming: ≈ {per_cycle * 1e3:.0f} µs of overhead per further cycle "
        "(default plan vs 1-cycle, both live)"
    )
    print(
        "   bare get->reply: a queryable in another process, same reply size, measured in the same loop "
        "(the transport floor here)"
    )
    r_local, r_raw, r_bare = server_alone
    print(
        "   then, in loops of their own: a plain get to the service, the request encoded beforehand and the "
        f"reply's bytes not parsed, takes {r_raw - r_local:.2f} ms over the in-process plan"
    )
    print(
        f"   ({(r_raw - r_local) / r_bare:.2f}x the bare get->reply of that loop, {r_bare:.2f} ms): "
        "the service without the client library (its share: the rest of the first row)"
    )
    f_local, f_planned, f_bare = floor
    print(
        "   and the same bare get->reply whose queryable runs the same 1-cycle plan "
        f"first takes {f_planned - f_local:.2f} ms over the in-process plan"
    )
    print(
        f"   ({(f_planned - f_local) / f_bare:.2f}x the bare get->reply of that loop, {f_bare:.2f} ms): what "
        "planning in another process costs with no service code (wake-ups after idling, cold caches)"
    )


def scale_out_part(n_tp: int, rounds: int) -> None:
    """Part 2: plans per second with one and with two service processes."""
    seeds = [1, 2, 3, 4, 6, 7]  # plans of 50-120 cycles
    requests = [PlanRequest(seed=seeds[i % len(seeds)]) for i in range(n_tp)]
    print(
        f"\n2. scale-out: {n_tp} plans (seeds {seeds}) per batch, 4 client threads, no stream; two eos serve "
        f"processes (one worker each), {rounds} rounds of alternating batches: 'one' = every plan to inst-0, "
        "'two' = spread over both"
    )
    ratios = {}
    plain = PlainPlanners()
    try:
        runs = {
            topology: scale_out(requests, threads=4, rounds=rounds, via_router=via_router, plain=plain)
            for topology, via_router in (("peer to peer", False), ("through a router", True))
        }
    finally:
        plain.close()
    for topology, (one, two, ceiling) in runs.items():
        per_round = [b.rate / a.rate for a, b in zip(one, two, strict=True)]
        ratios[topology] = statistics.median(per_round)
        med = statistics.median
        print(
            f"   {topology:<17} one {med(b.rate for b in one):6.2f} plans/s, two "
            f"{med(b.rate for b in two):6.2f} plans/s; two / one per round "
            f"{', '.join(f'{r:.2f}' for r in per_round)} -> median {ratios[topology]:.2f}x"
        )
        print(
            f"   {'':<17} the same plans in two plain planner processes (no service, no Zenoh), right "
            f"after in each round: two / one {', '.join(f'{r:.2f}' for r in ceiling)} -> median "
            f"{med(ceiling):.2f}x (what the two cores gave the planner itself; the service's "
            f"{ratios[topology]:.2f}x is {ratios[topology] / med(ceiling):.0%} of it)"
        )
        # two / one = 2 x (busy two / busy one) / (plan time two / plan time one)
        slower = med(med(b.plan_s) for b in two) / med(med(b.plan_s) for b in one)
        print(
            f"   {'':<17} where it goes: a plan takes {slower:.2f}x as long with two processes busy "
            f"(median plan {med(med(b.plan_s) for b in one) * 1e3:.0f} -> "
            f"{med(med(b.plan_s) for b in two) * 1e3:.0f} ms); time spent planning: one "
            f"{med(b.busy for b in one):.0%}, two {med(b.busy for b in two):.0%} of each process's "
            "time (the rest: idle between plans, request/reply, batch tail)"
        )
        for label, batches in (("one", one), ("two", two)):
            n = len(requests)
            cpu = {k: med(b.cpu_s[k] for b in batches) / n * 1e3 for k in batches[0].cpu_s}
            plan_ms = med(sum(b.plan_s) for b in batches) / n * 1e3
            print(
                f"   {'':<17} CPU per plan ({label}): service processes {cpu['services']:.0f} ms (planning "
                f"{plan_ms:.0f} ms of wall time), client process {cpu['client']:.1f} ms"
                + (f", router {cpu['router']:.1f} ms" if "router" in cpu else "")
            )
    print(
        "   goal ≥ 1.8x from one to two processes: "
        + ", ".join(f"{t} {'met' if r >= 1.8 else 'NOT met'}" for t, r in ratios.items())
        + f" (load average now {os.getloadavg()[0]:.2f}: other processes share the 2 CPUs)"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--breakdown", action="store_true", help="time each step of one request, then stop")
    parser.add_argument("--only", choices=("overhead", "scale-out"), help="run one of the two parts")
    parser.add_argument("--echo-server", type=int, nargs=2, metavar=("PORT", "BYTES"), help=argparse.SUPPRESS)
    parser.add_argument("--plan-first", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--stamps", metavar="OUT", help=argparse.SUPPRESS)
    parser.add_argument("--plain-planner", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--probe-server", nargs=2, metavar=("PORT", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.echo_server is not None:
        port, reply_bytes = args.echo_server
        echo_server(port, reply_bytes, plan_first=args.plan_first, stamps_out=args.stamps)
        return 0
    if args.probe_server is not None:
        probe_server(int(args.probe_server[0]), args.probe_server[1])
        return 0
    # the fit's compiled kernels, as the service processes run it (they load them at start): this
    # process's own plans (the in-process baseline, the plain planners') run the same code, and
    # numba's cache on disk is written here if missing, so that the services load the kernels
    # instead of compiling them
    kernels.load()
    if args.plain_planner:
        plain_planner()
        return 0
    if args.breakdown:
        breakdown(40 if args.quick else 120)
        return 0
    n_rt = 60 if args.quick else 150
    n_tp = 24 if args.quick else 40
    version = importlib.metadata.version("eclipse-zenoh")
    print(
        f"bench_service: {os.cpu_count()} CPU(s), Python {sys.version.split()[0]}, eclipse-zenoh {version}, "
        f"load average {os.getloadavg()[0]:.2f} (other processes share these CPUs)"
    )
    if args.only != "scale-out":
        overhead_part(n_rt)
    if args.only != "overhead":
        scale_out_part(n_tp, rounds=2 if args.quick else 4)
    return 0


if __name__ == "__main__":
    sys.exit(main())
