"""Another planner reuses the core: a root-finding problem solved by custom agents."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import eos_svc
from eos_svc import RunStatus, Weights
from eos_svc.demo import RootProblem, default_problem, solve_root


def test_root_finding_with_both_subratings():
    result, board = solve_root(default_problem())
    assert result.status is RunStatus.COMPLETED
    assert board["root"] == pytest.approx(0.7390851332151607, abs=1e-9)
    assert result.stages_completed == ("bracket", "refine")
    assert set(result.agents_run()) >= {"scan", "widen", "secant", "done"}


def test_same_problem_same_cycles():
    first, _ = solve_root(default_problem())
    second, _ = solve_root(default_problem())
    assert [r.chosen for r in first.trace] == [r.chosen for r in second.trace]


@pytest.mark.parametrize(
    "f,start,root",
    [
        (lambda x: x**3 - 2.0, (5.0, 6.0), 2 ** (1 / 3)),
        (lambda x: math.exp(x) - 3.0, (-4.0, -3.0), math.log(3.0)),
    ],
)
def test_other_functions(f, start, root):
    result, board = solve_root(RootProblem(f, start, 1e-10))
    assert result.status is RunStatus.COMPLETED
    assert board["root"] == pytest.approx(root, abs=1e-8)


def test_default_only_runs_a_fixed_sequence_and_stops():
    result, _ = solve_root(default_problem(), Weights(1.0, 0.0))
    assert result.agents_run() == ["scan", "widen"]
    assert result.status is RunStatus.STALLED


def test_the_core_modules_import_no_domain_library():
    """The package root (board, agent, ratings, controller, records, recording, errors) is
    domain-free: importing it in a fresh interpreter loads no Pinocchio, coal, Drake or Zenoh."""
    import subprocess
    import sys

    code = (
        "import sys, eos_svc, eos_svc.recording, eos_svc.demo\n"
        "print(sorted(m for m in ('pinocchio', 'coal', 'pydrake', 'zenoh', 'numpy') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True,
        env={"PYTHONPATH": str(Path(eos_svc.__file__).parents[1]), "PATH": "/usr/bin:/bin"},
    ).stdout  # fmt: skip
    assert out.strip() == "[]"
