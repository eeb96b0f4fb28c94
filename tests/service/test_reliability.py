"""Quick bounded versions of the reliability runs (the full ones: python -m eos_svc.service.reliability)."""

from __future__ import annotations

import pytest

from eos_svc.service.reliability import run


def test_quick_load_every_request_answered_once_nothing_lost():
    report = run("load", instances=2, clients=3, plans=6, planner="root", time_limit_s=30)
    report.print()
    assert report.ok, report
    assert report.answered == 18 and report.cycles_received == report.observer_cycles > 0
    assert all(
        s is not None and s["received"] == s["replied_ok"] + s["replied_err"]
        for s in report.server_stats.values()
    )


def test_quick_fault_sigkill_one_instance_mid_load():
    report = run("fault", instances=2, clients=3, plans=6, planner="root", time_limit_s=30, cycle_delay=0.003)
    report.print()
    assert report.ok, report
    assert report.answered == 18
    assert report.server_stats["inst-1"] is None  # killed


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["load", "fault", "freeze"])
def test_full_reliability_runs_with_the_grasp_planner(mode):
    report = run(mode, instances=2, clients=4, plans=15, planner="grasp", time_limit_s=120)
    report.print()
    assert report.ok, report
