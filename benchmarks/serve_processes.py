"""``eos serve`` processes on loopback, started and stopped for the reliability runs and benchmarks."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from dataclasses import dataclass

from eos_svc.errors import ComputationError
from eos_svc.service.session import free_port, loopback


@dataclass
class Server:
    """One ``eos serve`` subprocess."""

    port: int
    proc: subprocess.Popen[str]
    instance: str
    stats: dict[str, int] | None = None


def start_servers(
    n: int,
    *,
    planner: str = "grasp",
    workers: int = 2,
    queue: int = 16,
    lease_ms: int | None = None,
    cycle_delay: float | None = None,
    join: Server | None = None,
    first_index: int = 0,
) -> list[Server]:
    """Start ``n`` service processes on loopback, ``inst-<first_index>``, ...; each listens, and
    connects to ``join`` (default: the first one started here)."""
    servers: list[Server] = []
    for i in range(first_index, first_index + n):
        port = free_port()
        cmd = [
            sys.executable,
            "-m",
            "eos_svc.cli",
            "serve",
            "--listen",
            loopback(port),
            "--instance",
            f"inst-{i}",
            "--planner",
            planner,
            "--workers",
            str(workers),
            "--queue",
            str(queue),
            "--log-level",
            "warning",
        ]
        hub = join or (servers[0] if servers else None)
        if hub is not None:
            cmd += ["--connect", loopback(hub.port)]
        if lease_ms is not None:
            cmd += ["--lease-ms", str(lease_ms)]
        if cycle_delay is not None:
            cmd += ["--cycle-delay", str(cycle_delay)]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert proc.stdout is not None
        line = proc.stdout.readline()
        if "serving" not in line:
            proc.kill()
            err = proc.stderr.read() if proc.stderr else ""
            raise ComputationError(f"eos serve did not start: {line}{err}")
        servers.append(Server(port, proc, f"inst-{i}"))
    return servers


def stop_servers(servers: list[Server]) -> None:
    """SIGTERM the live servers (SIGCONT first, in case one is frozen) and read their final stats."""
    for s in servers:
        if s.proc.poll() is None:
            s.proc.send_signal(signal.SIGCONT)
            s.proc.send_signal(signal.SIGTERM)
    for s in servers:
        try:
            out, _ = s.proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            s.proc.kill()
            out, _ = s.proc.communicate()
        for line in (out or "").splitlines():
            if "stopped;" in line:
                s.stats = json.loads(line.split("stopped;", 1)[1].strip().replace("'", '"'))


def counters_consistent(stats: dict[str, int] | None) -> bool:
    """Whether an instance's final counters say every query it received ended in exactly one way
    (``received == replied_ok + replied_err + left_to_peers``); ``None`` (killed): nothing to check."""
    return (
        stats is None
        or stats["received"] == stats["replied_ok"] + stats["replied_err"] + stats["left_to_peers"]
    )
