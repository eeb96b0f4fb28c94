"""``eos serve`` as a subprocess, ``eos client`` and the programs in clients/ against it."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from eos_svc.schema.request import PlanRequest
from eos_svc.service.session import loopback, make_config

ROOT = Path(__file__).resolve().parents[2]
EOS = [sys.executable, "-m", "eos_svc.cli"]


def start_server(port: int, *extra: str) -> subprocess.Popen[str]:
    """``eos serve`` on loopback; returns once it prints that it is serving."""
    proc = subprocess.Popen(
        [*EOS, "serve", "--listen", loopback(port), "--log-level", "warning", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert "serving under eos/@v1" in line, line + (proc.stderr.read() if proc.poll() is not None else "")
    return proc


@pytest.fixture
def server(port: int) -> Iterator[subprocess.Popen[str]]:
    # the shipped loopback-peer config file, its endpoint overridden by --listen
    proc = start_server(port, "--instance", "sub-1", "--config", str(ROOT / "config" / "peer-loopback.json5"))
    yield proc
    if proc.poll() is None:
        proc.kill()
    proc.wait(5)


def test_eos_serve_subprocess_end_to_end(port, server, clients):
    client = clients(port)
    assert client.wait_for_instances(1, timeout=10) == ["sub-1"]
    out = client.plan(PlanRequest(seed=2), goal_id="cli-e2e")
    assert out.instance == "sub-1"
    assert out.result["status"] in ("success", "completed", "failed", "stalled", "cycle_limit", "deadline")
    assert [m["seq"] for m in out.cycles] == list(range(1, out.result["cycles"] + 1))
    assert out.complete
    # eos client, as a user would run it
    res = subprocess.run(
        [*EOS, "client", "plan", "--connect", loopback(port), "--json", "--quiet", "--seed", "2"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["result"]["cycles"] == out.result["cycles"]  # same seed, same plan
    res = subprocess.run(
        [*EOS, "client", "list", "--connect", loopback(port)], capture_output=True, text=True, timeout=30
    )
    assert res.stdout.split() == ["sub-1"]
    res = subprocess.run(
        [*EOS, "client", "plan", "--connect", loopback(port), "--radius", "2"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert res.returncode == 2 and "--radius" in res.stderr and "Traceback" not in res.stderr
    # clients/ programs
    res = subprocess.run(
        [
            sys.executable,
            str(ROOT / "clients" / "plan_and_watch.py"),
            "-e",
            loopback(port),
            "--seed",
            "2",
            "--goal-id",
            "pw-1",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith("[sub-1] pw-1 #   1")
    summary = json.loads(res.stdout[res.stdout.index("{") :])
    assert summary["complete"] and summary["cycles_received"] == summary["result"]["cycles"]
    # graceful stop on SIGTERM
    server.send_signal(signal.SIGTERM)
    assert server.wait(10) == 0
    assert "stopped" in server.stdout.read()


def test_watch_all_sees_every_cycle(port, server, clients):
    sys.path.insert(0, str(ROOT / "clients"))
    try:
        import watch_all
    finally:
        sys.path.pop(0)
    client = clients(port)
    client.wait_for_instances(1, timeout=10)
    counted: dict[str, int] = {}
    t = threading.Thread(
        target=lambda: counted.setdefault(
            "n", watch_all.main(make_config(connect=[loopback(port)]), duration_s=3.0)
        )
    )
    t.start()
    time.sleep(0.7)
    outs = [client.plan(PlanRequest(seed=s)) for s in (1, 3)]
    t.join(10)
    expected = sum(o.result["cycles"] + 2 for o in outs)  # cycles + running + done
    assert counted["n"] == expected


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["serve", "--workers", "0"], "--workers"),
        (["serve", "--queue", "-1"], "--queue"),
        (["serve", "--config", "/nonexistent.json5"], "--config"),
        (["serve", "--listen", "nonsense"], "--listen"),
        (["serve", "--namespace", "a/b"], "--namespace"),
        (["serve", "--cycle-delay", "nan"], "--cycle-delay"),
        (["client", "plan", "--goal-id", "a b"], "--goal-id"),
        (["client", "cancel", "*", "--token", "t" * 16], "GOAL_ID"),
        (["client", "cancel", "g1", "--token", "short"], "--token"),
        (["client", "cancel", "g1"], "--token"),
        (["client", "plan", "--cancel-token", "not a token!!!!!!"], "--cancel-token"),
        (["client"], "ACTION"),
    ],
)
def test_bad_options_exit_2_naming_the_option(argv, option, capsys):
    from eos_svc.cli import main

    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert option in capsys.readouterr().err
