"""A grasp-planner service loads the shape fit's compiled kernels in the background at start,
answering plans meanwhile (its fits run the numpy reference, the same results, until then)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import time
    from eos_svc.schema.request import PlanRequest
    from eos_svc.service import EosClient, PlanService, free_port, loopback, make_config
    from eos_svc.shape import kernels

    assert not kernels.ready()  # a fresh process: numpy until loaded
    port = free_port()
    service = PlanService.open(make_config(listen=[loopback(port)]), instance="k1", workers=1)
    client = EosClient.open(make_config(connect=[loopback(port)]))
    client.wait_for_instances(1, timeout=15)
    first = client.plan(PlanRequest(seed=2), watch=False)
    end = time.monotonic() + 60  # a first compilation on a new install takes ~11-15 s
    while not kernels.ready() and time.monotonic() < end:
        time.sleep(0.05)
    second = client.plan(PlanRequest(seed=2), watch=False)
    print(first.result["status"], second.result["status"], kernels.ready(), kernels.error)
    a, b = first.result, second.result
    print(a["q_final"] == b["q_final"], a["cycles"] == b["cycles"])
    client.close()
    service.stop()
    """
)


def test_a_grasp_service_loads_the_fit_kernels_in_the_background_and_plans_the_same():
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    statuses, same = out.stdout.strip().splitlines()[-2:]
    first, second, ready, error = statuses.split(" ", 3)
    assert first == second == "success"
    assert ready == "True" and error == "None"
    assert same == "True True"  # the plan before the kernels and the plan with them: identical
