"""The `eos` command line: plan, experiments, demo; errors name the option."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from eos_svc.cli import main


def eos(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "eos_svc.cli", *args], capture_output=True, text=True, timeout=120, check=False
    )


def test_plan_json_result():
    proc = eos("plan", "--json", "--seed", "2")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["status"] == "success"
    assert data["seed"] == 2
    assert set(data["contacts"]) == {"finger1", "finger2", "finger3"}


def test_plan_poor_grip_is_completed_with_exit_1(capsys):
    # μ = 0: every fingertip touches, but a frictionless grip of a sphere cannot hold it
    assert main(["plan", "--json", "--friction", "0"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "completed" and data["good_grasp"] is False
    assert "not good" in data["reason"] and data["stages_completed"][-1] == "grasping"


def test_plan_exit_code_follows_the_status():
    from eos_svc.cli.plan import plan_exit_code

    assert plan_exit_code("success") == 0
    for status in ("completed", "failed", "stalled", "cycle_limit", "deadline", "cancelled", "error"):
        assert plan_exit_code(status) == 1


def test_plan_trace_and_record(tmp_path, capsys):
    record = tmp_path / "cycles.jsonl"
    assert main(["plan", "--record", str(record)]) == 0
    out = capsys.readouterr().out
    assert "status: success" in out and "-> wrist [progress]:" in out
    header, *lines, footer = [json.loads(line) for line in record.read_text().splitlines()]
    assert header["eos_record"] == "header" and footer["eos_record"] == "result"
    assert [r["seq"] for r in lines] == list(range(1, len(lines) + 1))
    assert {"stage", "ratings", "weights", "chosen", "outcome", "changes"} <= set(lines[0])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--radius", "-0.01"], "--radius"),
        (["--radius", "nan"], "--radius"),
        (["--shape", "cone"], "--shape: unknown shape"),
        (["--w-default", "0.9"], "must sum to 1"),
        (["--position", "2", "0", "0"], "--position"),
        (["--shape", "box"], "--size"),
        (["--noise", "-1"], "--noise"),
    ],
)
def test_plan_bad_options_exit_2_naming_the_option(args, message):
    proc = eos("plan", *args)
    assert proc.returncode == 2
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr


def test_unknown_command():
    proc = eos("fly")
    assert proc.returncode == 2 and "unknown command" in proc.stderr


def test_demo_runs(capsys):
    assert main(["demo", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "completed" and abs(data["root"] - 0.7390851332) < 1e-8


def test_ratio_experiment_writes_files(tmp_path):
    proc = eos("experiment", "ratio", "--seeds", "1", "--ratios", "0.3", "0.8", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    data = json.loads((tmp_path / "ratio.json").read_text())
    rows = {row["ratio"]: row for row in data["rows"]}
    assert rows[0.3]["mean_grasp_cycles"] > rows[0.8]["mean_grasp_cycles"]
    assert (tmp_path / "ratio.png").stat().st_size > 1000
    assert (tmp_path / "ratio.csv").read_text().startswith("ratio,")
