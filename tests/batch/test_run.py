"""Batches on a real local Ray: rows equal the same plans run serially, a rerun skips the rows
written, a worker SIGKILLed mid-run loses and duplicates nothing, validation fills its columns."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ray = pytest.importorskip("ray")

from eos_svc.agents import PlanRequest, plan  # noqa: E402
from eos_svc.batch import expand, spec_from_dict  # noqa: E402
from eos_svc.batch.runner import run_batch  # noqa: E402
from eos_svc.batch.store import read_rows  # noqa: E402

QUICK = {"name": "t", "objects": {"suite": "quick"}, "seeds": [1, 2]}


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """One local Ray with two workers for the module (run_batch uses a running session)."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level="ERROR")
    yield
    ray.shutdown()


def by_key(out: Path) -> dict[str, dict[str, Any]]:
    table = read_rows(out)
    keys = table.column("key").to_pylist()
    assert len(keys) == len(set(keys)), "a key written twice"
    return {r["key"]: r for r in table.to_pylist()}


def test_the_batch_rows_equal_the_same_plans_run_serially(local_ray: None, tmp_path: Path) -> None:
    spec = spec_from_dict({**QUICK, "conditions": {"friction": [0.3, 0.5]}, "run": {"plans_per_task": 3}})
    summary = run_batch(spec, tmp_path, progress=False)
    assert summary.planned == 20 and summary.lost == 0 and summary.skipped == 0
    got = by_key(tmp_path)
    assert len(got) == 20
    for key in expand(spec):
        row = got[key.key]
        serial = plan(PlanRequest.from_dict(key.request), keep_trace=False)
        assert (row["status"], row["reason"], row["cycles"]) == (serial.status, serial.reason, serial.cycles)
        assert row["epsilon"] == pytest.approx(serial.epsilon, rel=1e-6, abs=1e-9)
        assert serial.q_final is not None
        np.testing.assert_allclose(row["q_final"], serial.q_final, atol=1e-9)
        assert row["wrist_pose"] == row["q_final"][:6]
        assert row["good_grasp"] == serial.good_grasp and row["seed"] == key.seed
        assert [c["finger"] for c in row["contacts"]] == list(serial.contacts)
        assert row["validated"] is False and row["held"] is None


def test_a_rerun_skips_the_rows_written_and_plans_only_the_new(local_ray: None, tmp_path: Path) -> None:
    first = run_batch(spec_from_dict({**QUICK, "seeds": [1]}), tmp_path, progress=False)
    assert (first.planned, first.skipped) == (5, 0)
    again = run_batch(spec_from_dict({**QUICK, "seeds": [1]}), tmp_path, progress=False)
    assert (again.planned, again.skipped, again.files) == (0, 5, 0)
    grown = run_batch(spec_from_dict({**QUICK, "seeds": [1, 2]}), tmp_path, progress=False)
    assert (grown.planned, grown.skipped) == (5, 5)
    assert len(by_key(tmp_path)) == 10


def test_a_worker_killed_mid_run_loses_and_duplicates_no_row(local_ray: None, tmp_path: Path) -> None:
    spec = spec_from_dict(
        {**QUICK, "seeds": [1, 2, 3, 4], "run": {"plans_per_task": 2, "rows_per_file": 3, "max_retries": 3}}
    )
    killed: dict[str, Any] = {}

    def kill_a_busy_worker(rows: list[dict[str, Any]]) -> None:
        """At the first finished task, SIGKILL the worker that ran it: it has its next task."""
        if not killed:
            worker = rows[0]["worker"]
            killed["worker"] = worker
            os.kill(int(worker.rsplit(":", 1)[1]), signal.SIGKILL)
            killed["rows_before"] = len(rows)

    summary = run_batch(spec, tmp_path, progress=False, on_rows=kill_a_busy_worker)
    assert killed, "no worker was killed"
    got = by_key(tmp_path)
    assert summary.lost == 0 and summary.planned == 20
    assert sorted(got) == sorted(k.key for k in expand(spec))  # 0 lost, 0 duplicated (by_key)
    from_killed = [r for r in got.values() if r["worker"] == killed["worker"]]
    assert len(from_killed) == killed["rows_before"]  # its task in flight was run again elsewhere


def test_validation_fills_the_validation_columns(local_ray: None, tmp_path: Path) -> None:
    spec = spec_from_dict(
        {
            "objects": {"explicit": [{"shape": "sphere", "radius": 0.03, "position": [0.21, 0.02, -0.015]}]},
            "validate": {"enabled": True, "seconds": 0.1, "directions": 1},
        }
    )
    summary = run_batch(spec, tmp_path, progress=False)
    (row,) = by_key(tmp_path).values()
    assert row["status"] == "success" and row["validated"] is True and row["held"] is not None
    assert row["validation_s"] > 0 and row["max_displacement_m"] is not None and '"held"' in row["validation"]
    assert summary.validated == 1


def test_a_request_admission_refuses_is_a_refused_row(local_ray: None, tmp_path: Path) -> None:
    far = {"shape": "sphere", "radius": 0.03, "position": [2.0, 0.0, 0.0]}
    run_batch(spec_from_dict({"objects": {"explicit": [far]}}), tmp_path, progress=False)
    (row,) = by_key(tmp_path).values()
    assert row["status"] == "refused" and row["reason"].startswith("object.position")
    assert row["q_final"] is None and row["cycles"] == 0
