"""Reliability runs of the service on loopback, bounded in count and time (``docs/service.md``).

    .venv/bin/python benchmarks/reliability.py load|fault|freeze|abuse|slow-watcher|all [--help]

``eos serve`` subprocesses on 127.0.0.1; N client threads (each its own session) send M plans
each while an observer session counts every cycle and status. Checks: every request answered
exactly once, every cycle stream complete and contiguous, every instance's counters consistent
(``abuse``: the probes of ``abuse.py`` and the server's memory). One table, one row per check;
exit code 0 when every check holds.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from typing import Any

import abuse
import zenoh
from serve_processes import counters_consistent, start_servers, stop_servers
from slow_watcher import run_slow_watcher

from eos_svc.errors import ValidationError
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import EosClient
from eos_svc.service.plan_attempt import PlanOutcome
from eos_svc.service.session import direct_callback, loopback, make_config


@dataclass
class Report:
    """Counts of one run."""

    mode: str
    requested: int = 0
    answered: int = 0
    failed: list[str] = field(default_factory=list)
    incomplete: list[str] = field(default_factory=list)
    retried: int = 0
    statuses: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    cycles_received: int = 0
    observer_cycles: int = 0
    observer_gaps: list[str] = field(default_factory=list)
    server_stats: dict[str, Any] = field(default_factory=dict)
    wall_s: float = 0.0
    event: str = ""

    @property
    def ok(self) -> bool:
        """Every request answered exactly once, every stream complete and contiguous, every
        instance's counters consistent."""
        return (
            self.answered == self.requested
            and not self.failed
            and not self.incomplete
            and not self.observer_gaps
            and all(counters_consistent(s) for s in self.server_stats.values())
        )

    def row(self) -> abuse.Probe:
        """This run as one row of the table."""
        probe = abuse.Probe(
            f"{self.mode}: {self.requested} plans",
            sent=self.requested,
            answered_once=self.answered if not self.failed else self.answered - len(self.failed),
            codes=Counter(self.statuses),
            ok=self.ok,
        )
        notes = [self.event] if self.event else []
        notes.append(
            f"retried {self.retried}, streams complete {self.requested - len(self.incomplete)}, "
            f"observer gaps {len(self.observer_gaps)}, {self.wall_s:.1f} s"
        )
        probe.detail = "; ".join(notes)
        return probe


class Observer:
    """Counts every cycle message per (goal, instance) and checks contiguity."""

    def __init__(self, session: zenoh.Session, prefix: str) -> None:
        self._lock = threading.Lock()
        self.seqs: dict[tuple[str, str], list[int]] = defaultdict(list)
        self.done: dict[tuple[str, str], int] = {}
        self._sub = session.declare_subscriber(proto.goal_keys(prefix), direct_callback(self._on))

    def _on(self, sample: zenoh.Sample) -> None:
        msg = json.loads(sample.payload.to_bytes())
        key = (msg["goal_id"], msg["instance"])
        with self._lock:
            if "seq" in msg:
                self.seqs[key].append(msg["seq"])
            elif msg.get("state") == proto.STATE_DONE:
                self.done[key] = msg.get("result", {}).get("cycles_published", -1)

    def check(self, report: Report) -> None:
        """Every finished (goal, instance) stream is 1..n; streams cut by a dead instance are a prefix."""
        with self._lock:
            report.observer_cycles = sum(len(v) for v in self.seqs.values())
            for key, seqs in self.seqs.items():
                if seqs != list(range(1, len(seqs) + 1)):
                    report.observer_gaps.append(f"{key}: not contiguous")
                elif key in self.done and self.done[key] != len(seqs):
                    report.observer_gaps.append(f"{key}: {len(seqs)} seen, {self.done[key]} published")

    def close(self) -> None:
        self._sub.undeclare()


def run(
    mode: str,
    *,
    instances: int = 2,
    clients: int = 4,
    plans: int = 25,
    planner: str = "grasp",
    time_limit_s: float = 120.0,
    lease_ms: int = 1000,
    event_after: float = 0.3,
    cycle_delay: float | None = None,
) -> Report:
    """One bounded run; ``mode`` is ``load``, ``fault`` (SIGKILL) or ``freeze`` (SIGSTOP)."""
    if mode not in ("load", "fault", "freeze"):
        raise ValidationError("mode", f"must be load, fault or freeze, got {mode!r}")
    if mode != "load":
        instances = max(instances, 2)
    report = Report(mode, requested=clients * plans)
    t0 = time.monotonic()
    lease = lease_ms if mode == "freeze" else None
    servers = start_servers(instances, planner=planner, lease_ms=lease, cycle_delay=cycle_delay)
    endpoints = [loopback(s.port) for s in servers]
    sessions: list[EosClient] = []
    observer_session = zenoh.open(make_config(connect=endpoints))
    observer = Observer(observer_session, proto.prefix())
    lock = threading.Lock()
    try:
        for _ in range(clients):
            c = EosClient.open(make_config(connect=endpoints, lease_ms=lease), timeout_margin_s=10.0)
            c.wait_for_instances(instances, timeout=15)
            sessions.append(c)
        deadline = t0 + time_limit_s

        def work(ci: int, client: EosClient) -> None:
            for j in range(plans):
                goal = f"r{ci}-{j}"
                if time.monotonic() > deadline:
                    with lock:
                        report.failed.append(f"{goal}: not sent (time limit)")
                    continue
                try:
                    out: PlanOutcome = client.plan(
                        PlanRequest(seed=1 + (ci * plans + j) % 7), goal_id=goal, max_attempts=4
                    )
                except Exception as exc:
                    with lock:
                        report.failed.append(f"{goal}: {type(exc).__name__}: {exc}")
                    continue
                with lock:
                    report.answered += 1
                    report.statuses[out.status] += 1
                    report.cycles_received += len(out.cycles)
                    report.retried += out.attempts > 1
                    if not out.complete:
                        report.incomplete.append(goal)

        threads = [threading.Thread(target=work, args=(i, c), daemon=True) for i, c in enumerate(sessions)]
        for t in threads:
            t.start()
        if mode in ("fault", "freeze"):
            # strike once a share of the plans is done, so the victim has plans in flight
            while report.answered < event_after * report.requested and time.monotonic() < deadline:
                time.sleep(0.01)
            victim = servers[-1]
            if mode == "fault":
                victim.proc.send_signal(signal.SIGKILL)
                report.event = f"SIGKILL {victim.instance} after {report.answered} plans answered"
            else:
                victim.proc.send_signal(signal.SIGSTOP)
                t_stop = time.monotonic()
                watcher = sessions[0]
                while victim.instance in watcher.instances() and time.monotonic() < t_stop + 30:
                    time.sleep(0.01)
                report.event = (
                    f"SIGSTOP {victim.instance} after {report.answered} plans answered; token gone "
                    f"after {time.monotonic() - t_stop:.2f} s (lease {lease_ms} ms)"
                )
        for t in threads:
            t.join(max(0.0, deadline - time.monotonic()) + 30)
    finally:
        time.sleep(0.3)
        observer.check(report)
        observer.close()
        for c in sessions:
            c.close()
        observer_session.close()
        stop_servers(servers)
        report.server_stats = {s.instance: s.stats for s in servers}
        report.wall_s = time.monotonic() - t0
    return report


#: growth of the server's RSS under abuse that still counts as bounded (MB)
RSS_BOUND_MB = 50.0


def run_abuse(
    *, big: int = 100, big_mb: float = 10.0, mutated: int = 10_000, planner: str = "grasp"
) -> list[abuse.Probe]:
    """The abuse probes against two ``eos serve`` processes; the last row is inst-0's memory.

    inst-0 serves normally and takes the big payloads, the mutated and the unplannable requests;
    inst-1 (every cycle slowed to 20 ms) runs the goal a stranger tries to cancel.
    """
    servers = start_servers(1, planner=planner)
    servers += start_servers(1, planner=planner, cycle_delay=0.02, join=servers[0], first_index=1)
    endpoints = [loopback(s.port) for s in servers]
    rows: list[abuse.Probe] = []
    owner = EosClient.open(make_config(connect=endpoints))
    stranger = EosClient.open(make_config(connect=endpoints))
    try:
        owner.wait_for_instances(2, timeout=15)
        stranger.wait_for_instances(2, timeout=15)
        time.sleep(0.3)  # the instances see each other's tokens
        session = owner.session
        key = proto.plan_key(owner.prefix, servers[0].instance)
        for seed in (1, 2, 3):  # warm: the planner's caches, the first replies
            owner.plan(PlanRequest(seed=seed), instance=servers[0].instance)
        pid = servers[0].proc.pid
        start = abuse.rss_mb(pid)
        rows.append(abuse.big_payloads(session, key, big, int(big_mb * 1e6)))
        after_big = abuse.rss_mb(pid)
        rows.append(abuse.mutated_requests(session, key, mutated))
        after_mutated = abuse.rss_mb(pid)
        if planner == "grasp":  # admission is the grasp planner's (the root demo has none)
            rows.append(abuse.unplannable(session, key))
        rows.append(abuse.wildcard_plan(session, owner.prefix, len(servers)))
        rows.append(abuse.stranger_cancel(owner, stranger, instance=servers[1].instance))
        rows.append(abuse.squatter(owner, stranger, instance=servers[1].instance))
        memory = abuse.Probe(f"memory of {servers[0].instance} (RSS)")
        growth = after_mutated - start
        memory.ok = growth <= RSS_BOUND_MB
        memory.detail = (
            f"{start:.0f} MB at start, {after_big:.0f} after the big payloads, {after_mutated:.0f} after "
            f"the mutated requests: +{growth:.1f} MB (bound +{RSS_BOUND_MB:.0f})"
        )
        rows.append(memory)
    finally:
        owner.close()
        stranger.close()
        stop_servers(servers)
    if servers[0].stats is not None:
        rows[-1].detail += f"; {servers[0].instance}: {servers[0].stats}"
    counters = abuse.Probe("counters of every instance")
    counters.ok = all(s.stats is not None and counters_consistent(s.stats) for s in servers)
    counters.detail = "received == replied_ok + replied_err + left_to_peers: " + ", ".join(
        f"{s.instance} {counters_consistent(s.stats) if s.stats else 'no stats'}" for s in servers
    )
    rows.append(counters)
    return rows


def print_table(rows: list[abuse.Probe]) -> None:
    """One table: what was sent, how many got exactly one reply, the replies, the verdict."""
    print(f"{'check':<44} {'sent':>6} {'1 reply':>7}  {'ok':<4} replies / notes")
    for r in rows:
        codes = ", ".join(f"{k} {v}" for k, v in sorted(r.codes.items()))
        print(f"{r.name[:44]:<44} {r.sent:>6} {r.answered_once:>7}  {'OK' if r.ok else 'FAIL':<4} {codes}")
        if r.detail:
            print(f"{'':<44} {'':>6} {'':>7}  {'':<4} {r.detail}")


def main(argv: list[str] | None = None) -> int:
    """Command line: run one mode (or all) and print one table."""
    parser = argparse.ArgumentParser(prog="benchmarks/reliability.py", description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=("load", "fault", "freeze", "abuse", "slow-watcher", "all"))
    parser.add_argument("--instances", type=int, default=2, help="service processes (fault/freeze: ≥ 2)")
    parser.add_argument("--clients", type=int, default=4, help="concurrent clients, each its own session")
    parser.add_argument("--plans", type=int, default=25, help="plans per client")
    parser.add_argument("--planner", choices=("grasp", "root"), default="grasp")
    parser.add_argument("--time-limit", type=float, default=120.0, help="s")
    parser.add_argument("--lease-ms", type=int, default=1000, help="freeze: transport lease (ms)")
    parser.add_argument("--cycle-delay", type=float, default=None, help="sleep per cycle in the servers (s)")
    parser.add_argument("--big", type=int, default=100, help="abuse: oversized payloads sent")
    parser.add_argument("--big-mb", type=float, default=10.0, help="abuse: size of each (MB)")
    parser.add_argument("--mutated", type=int, default=10_000, help="abuse: mutated requests sent")
    parser.add_argument("--window", type=float, default=20.0, help="slow-watcher: each load window (s)")
    args = parser.parse_args(argv)
    for name in ("instances", "clients", "plans"):
        if getattr(args, name) < 1 or getattr(args, name) > 1000:
            parser.error(f"--{name}: must be in [1, 1000]")
    if not 0 <= args.big <= 10_000 or not 0 <= args.mutated <= 1_000_000 or not 0 < args.big_mb <= 100:
        parser.error("--big: [0, 10000]; --mutated: [0, 1000000]; --big-mb: (0, 100]")
    rows: list[abuse.Probe] = []
    modes = ("load", "fault", "freeze", "abuse", "slow-watcher") if args.mode == "all" else (args.mode,)
    for mode in modes:
        if mode == "slow-watcher":
            rows.append(run_slow_watcher(window_s=args.window, clients=args.clients, planner=args.planner))
            continue
        if mode == "abuse":
            rows += run_abuse(big=args.big, big_mb=args.big_mb, mutated=args.mutated, planner=args.planner)
            continue
        report = run(
            mode,
            instances=args.instances,
            clients=args.clients,
            plans=args.plans,
            planner=args.planner,
            time_limit_s=args.time_limit,
            lease_ms=args.lease_ms,
            cycle_delay=args.cycle_delay,
        )
        rows.append(report.row())
    print_table(rows)
    return 0 if all(r.ok for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
