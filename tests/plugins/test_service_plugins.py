"""A service instance offers plug-ins; requests name them (real Zenoh sessions on loopback)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import EosClient
from eos_svc.service.plugins import offered_plugins
from eos_svc.service.server import PlanService
from eos_svc.service.session import free_port, loopback, make_config

ROOT = Path(__file__).resolve().parents[2]
TILTED = ObjectSpec("ellipsoid", {"radii": (0.04, 0.02, 0.03)}, (0.21, 0.02, -0.015), (0.3, 0.2, 0.5))
SPEC = "eos_svc.agents.plugins.sampled_grasp_points:SampledGraspPointsAgent"


@pytest.fixture
def service_and_client(request) -> Iterator[tuple[PlanService, EosClient]]:
    port = free_port()
    service = PlanService.open(make_config(listen=[loopback(port)]), plugins=request.param)
    client = EosClient.open(make_config(connect=[loopback(port)]))
    client.wait_for_instances(1, timeout=10.0)
    yield service, client
    client.close()
    service.stop()


@pytest.mark.parametrize("service_and_client", [offered_plugins([f"sampled={SPEC}"])], indirect=True)
def test_requests_name_the_plugins_an_instance_offers(service_and_client) -> None:
    _, client = service_and_client
    base = client.plan(PlanRequest(obj=TILTED, seed=1))
    outcome = client.plan(PlanRequest(obj=TILTED, seed=1, agents=("sampled",)))
    assert outcome.status == base.status == "success"
    chosen = [msg["record"]["chosen"] for msg in outcome.cycles]
    assert "sampled_grasp_points" in chosen and "grasp_points" not in chosen
    assert outcome.result["request"]["agents"] == ["sampled"]
    assert outcome.result["epsilon"] > base.result["epsilon"]
    rows = [r for msg in outcome.cycles for r in msg["record"]["ratings"]]
    assert {r["where"] for r in rows} == {"local"} and all("latency_s" in r for r in rows)
    with pytest.raises(proto.RequestError) as err:
        client.plan(PlanRequest(seed=1, agents=("sampled", SPEC)))
    assert err.value.field == "agents[1]"
    assert "not offered here (offered: sampled)" in err.value.reason


@pytest.mark.parametrize("service_and_client", [None], indirect=True)
def test_an_instance_without_plugins_imports_nothing_a_request_names(service_and_client) -> None:
    _, client = service_and_client
    with pytest.raises(proto.RequestError) as err:
        client.plan(PlanRequest(seed=1, agents=(SPEC,)))
    assert err.value.field == "agents[0]"
    assert "offered: none" in err.value.reason


def test_offered_specs_are_checked() -> None:
    assert set(offered_plugins([SPEC, "s2=" + SPEC])) == {SPEC, "s2"}
    with pytest.raises(Exception) as err:
        offered_plugins(["a=" + SPEC, "a=" + SPEC])
    assert "given twice" in str(err.value)


def test_eos_serve_refuses_a_bad_agent_spec() -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "eos_svc.cli",
            "serve",
            "--agent",
            "nope.nowhere:X",
            "--listen",
            "tcp/127.0.0.1:0",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert proc.returncode == 2
    assert "--agent: cannot import module 'nope.nowhere'" in proc.stderr


def test_eos_serve_offers_the_plugins_it_is_given() -> None:
    port = free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "eos_svc.cli",
            "serve",
            "--agent",
            f"sampled={SPEC}",
            "--listen",
            loopback(port),
        ],
        stdout=subprocess.PIPE,
        text=True,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "plug-ins offered: sampled" in line, line
        client = EosClient.open(make_config(connect=[loopback(port)]))
        try:
            client.wait_for_instances(1, timeout=10.0)
            outcome = client.plan(PlanRequest(obj=TILTED, seed=1, agents=("sampled",)))
        finally:
            client.close()
        assert outcome.status == "success"
        assert "sampled_grasp_points" in [msg["record"]["chosen"] for msg in outcome.cycles]
    finally:
        proc.terminate()
        proc.wait(timeout=30)
