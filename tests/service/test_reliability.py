"""Quick bounded versions of the reliability runs (the full ones: python benchmarks/reliability.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from eos_svc.service import protocol as proto

# the reliability runs are a developer's harness in benchmarks/, importing each other as scripts do
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from reliability import RSS_BOUND_MB, print_table, run, run_abuse
from slow_watcher import run_slow_watcher


# time_limit_s counts from the instances' start: 90 s leaves room for a loaded machine (30 s failed
# once with three Drake runs beside it); an unloaded run takes a few seconds
def test_quick_load_every_request_answered_once_nothing_lost():
    report = run("load", instances=2, clients=3, plans=6, planner="root", time_limit_s=90)
    print_table([report.row()])
    assert report.ok, report
    assert report.answered == 18 and report.cycles_received == report.observer_cycles > 0
    assert all(
        s is not None and s["received"] == s["replied_ok"] + s["replied_err"] + s["left_to_peers"]
        for s in report.server_stats.values()
    )


def test_quick_fault_sigkill_one_instance_mid_load():
    report = run("fault", instances=2, clients=3, plans=6, planner="root", time_limit_s=90, cycle_delay=0.003)
    print_table([report.row()])
    assert report.ok, report
    assert report.answered == 18
    assert report.server_stats["inst-1"] is None  # killed


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["load", "fault", "freeze"])
def test_full_reliability_runs_with_the_grasp_planner(mode):
    report = run(mode, instances=2, clients=4, plans=15, planner="grasp", time_limit_s=120)
    print_table([report.row()])
    assert report.ok, report


def _check_abuse(rows, big: int, mutated: int) -> None:
    print_table(rows)
    by_name = {r.name.split(" ")[0] if r.name[0].isdigit() else r.name: r for r in rows}
    assert all(r.ok for r in rows), [r for r in rows if not r.ok]
    assert by_name[str(big)].codes == {proto.E_TOO_LARGE: big}
    mutants = by_name[str(mutated)]
    assert mutants.answered_once == mutated and mutants.codes[proto.E_INTERNAL] == 0
    memory = next(r for r in rows if r.name.startswith("memory"))
    assert f"bound +{RSS_BOUND_MB:.0f}" in memory.detail
    assert by_name["counters of every instance"].ok
    assert by_name["squatter holds the guessed next 3 goal ids"].codes[proto.E_DUPLICATE] == 0


def test_quick_abuse_memory_stays_bounded_and_every_probe_gets_its_answer():
    """Server in its own process: 20 x 10 MB payloads and 1,500 mutated requests, RSS within +50 MB."""
    _check_abuse(run_abuse(big=20, mutated=1500), 20, 1500)


@pytest.mark.slow
def test_full_abuse_100_big_payloads_and_10000_mutated_requests():
    _check_abuse(run_abuse(big=100, mutated=10_000), 100, 10_000)


@pytest.mark.slow
def test_a_slow_watcher_for_20_s_leaves_the_others_p99_within_1_5x():
    row = run_slow_watcher(window_s=20.0, clients=4, planner="grasp")
    print_table([row])
    assert row.ok, row.detail
