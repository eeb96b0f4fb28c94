"""The deployment past one machine: a Zenoh router (TLS + access control, the shipped config files),
service instances and users as Zenoh clients of it, on loopback."""

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
import zenoh

from eos_svc.schema.request import PlanRequest
from eos_svc.service.client import EosClient
from eos_svc.service.server import PlanService
from eos_svc.service.session import free_port
from tests.service.waiting import wait_until

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"
EOS = [sys.executable, "-m", "eos_svc.cli"]


@pytest.fixture(scope="module")
def certs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped certificate script, run into a temporary directory."""
    out = tmp_path_factory.mktemp("tls")
    subprocess.run(["sh", str(CONFIG / "make-tls-certs.sh"), str(out)], check=True, capture_output=True)
    return out


def config_file(name: str, tmp: Path, certs: Path, port: int, lease_ms: int = 1000) -> Path:
    """A shipped config file with its certificate paths, port and lease made local to the test."""
    text = (
        (CONFIG / name)
        .read_text()
        .replace("config/tls/", f"{certs}/")
        .replace("config/eos-users.txt", str(CONFIG / "eos-users.txt"))
        .replace("localhost:7447", f"localhost:{port}")
        .replace("lease: 3000", f"lease: {lease_ms}")
    )
    path = tmp / name
    path.write_text(text)
    return path


def test_the_tls_router_keeps_the_acl_of_the_tcp_example():
    def acl(name: str) -> object:
        return json.loads(zenoh.Config.from_file(str(CONFIG / name)).get_json("access_control"))

    assert acl("router-tls-acl.json5") == acl("router-acl.json5")


def test_plans_through_a_tls_router_with_access_control(tmp_path, certs):
    port = free_port()
    router = zenoh.open(
        zenoh.Config.from_file(str(config_file("router-tls-acl.json5", tmp_path, certs, port)))
    )
    svc = PlanService.open(
        zenoh.Config.from_file(str(config_file("planner-tls.json5", tmp_path, certs, port))), instance="tls-1"
    )
    try:
        with EosClient.open(
            zenoh.Config.from_file(str(config_file("user-tls.json5", tmp_path, certs, port)))
        ) as c:
            assert c.wait_for_instances(1) == ["tls-1"]
            out = c.plan(PlanRequest(seed=3))
            assert out.instance == "tls-1" and out.complete and out.result["cycles"] > 1
        # a client that does not trust the router's CA cannot join; nor can one speaking plain TCP
        wrong_ca = zenoh.Config.from_file(str(config_file("user-tls.json5", tmp_path, certs, port)))
        wrong_ca.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(certs / "router.pem")))
        plain = zenoh.Config.from_file(str(config_file("user-tls.json5", tmp_path, certs, port)))
        plain.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
        for conf in (wrong_ca, plain):
            conf.insert_json5("connect/timeout_ms", "1000")
            with pytest.raises(zenoh.ZError):
                zenoh.open(conf)
    finally:
        svc.stop()
        router.close()


def _start(cmd: list[str], ready: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    if ready not in line:
        proc.kill()
        raise AssertionError(f"{cmd[3:5]} did not start: {line}{proc.stderr.read() if proc.stderr else ''}")
    return proc


@pytest.fixture
def deployment(tmp_path: Path, certs: Path) -> Iterator[dict]:
    """A router process, three ``eos serve`` processes as its Zenoh clients (lease 1 s)."""
    port = free_port()
    files = {
        n: config_file(n, tmp_path, certs, port)
        for n in ("router-tls-acl.json5", "planner-tls.json5", "user-tls.json5")
    }
    procs: list[subprocess.Popen[str]] = []
    try:
        procs.append(
            _start(
                [
                    sys.executable,
                    "-m",
                    "eos_svc.service.router",
                    "--config",
                    str(files["router-tls-acl.json5"]),
                ],
                "running",
            )
        )
        for i in range(3):
            procs.append(
                _start(
                    [
                        *EOS,
                        "serve",
                        "--config",
                        str(files["planner-tls.json5"]),
                        "--instance",
                        f"inst-{i}",
                        "--cycle-delay",
                        "0.004",
                        "--log-level",
                        "warning",
                    ],
                    "serving",
                )
            )
        yield {"files": files, "router": procs[0], "instances": procs[1:]}
    finally:
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGCONT)
                p.terminate()
        for p in procs:
            try:
                p.communicate(timeout=15)
            except subprocess.TimeoutExpired:
                p.kill()
                p.communicate()


@pytest.mark.slow
def test_router_three_instances_clients_in_processes_kill_and_freeze(deployment):
    files = deployment["files"]
    user = zenoh.Config.from_file(str(files["user-tls.json5"]))
    with EosClient.open(user) as watcher:
        assert watcher.wait_for_instances(3, timeout=20) == ["inst-0", "inst-1", "inst-2"]
        running: dict[str, set[str]] = {"inst-2": set()}
        lock = threading.Lock()

        def on_status(kind: str, msg: dict) -> None:
            if kind == "status" and msg.get("instance") == "inst-2":
                with lock:
                    (running["inst-2"].add if msg["state"] == "running" else running["inst-2"].discard)(
                        msg["goal_id"]
                    )

        sub = watcher.watch(on_status)
        clients = [
            subprocess.Popen(
                [
                    *EOS,
                    "client",
                    "plan",
                    "--config",
                    str(files["user-tls.json5"]),
                    "--goal-id",
                    f"c{k}",
                    "--repeat",
                    "10",
                    "--json",
                    "--quiet",
                    "--seed",
                    str(k + 1),
                ],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                cwd=ROOT,
            )
            for k in range(3)
        ]

        def inst2_busy() -> bool:
            with lock:
                return bool(running["inst-2"])

        # SIGKILL inst-2 while it runs a plan
        assert wait_until(inst2_busy, 60, interval=0.005), "inst-2 never ran a plan"
        deployment["instances"][2].send_signal(signal.SIGKILL)
        outputs = [c.communicate(timeout=120) for c in clients]
        sub.undeclare()
        lines = [
            json.loads(line) for out, _err in outputs for line in out.splitlines() if line.startswith("{")
        ]
        assert all(c.returncode in (0, 1) for c in clients), [err[-500:] for _out, err in outputs]
        assert sorted(x["goal_id"] for x in lines) == sorted(
            f"c{k}-{j}" for k in range(3) for j in range(1, 11)
        )
        assert all(
            x["complete"] and x["result"]["cycles"] > 1 for x in lines
        )  # no plan lost, every stream whole
        used = {x["instance"] for x in lines}
        assert {"inst-0", "inst-1"} <= used  # spread over the survivors
        assert any(x["attempts"] > 1 and x["instance"] != "inst-2" for x in lines)  # retried elsewhere

        # SIGSTOP inst-1: its token goes when the router's lease (1 s) expires
        deployment["instances"][1].send_signal(signal.SIGSTOP)
        t0 = time.monotonic()
        while "inst-1" in watcher.instances() and time.monotonic() < t0 + 10:
            time.sleep(0.01)
        detected = time.monotonic() - t0
        assert "inst-1" not in watcher.instances()
        assert detected < 3.0, detected
        assert watcher.plan(PlanRequest(seed=5)).instance == "inst-0"
