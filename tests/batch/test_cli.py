"""``eos batch``: a clear error without the batch extra or with a bad spec; the planner's own
commands import neither Ray nor pyarrow; the command end to end (slow: it starts its own Ray)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from eos_svc.cli import batch as batch_cli
from eos_svc.cli import main


def test_without_the_batch_extra_the_error_says_how_to_install_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = tmp_path / "s.toml"
    spec.write_text('[objects]\nsuite = "quick"\n')
    real = batch_cli.importlib.util.find_spec
    monkeypatch.setattr(
        batch_cli.importlib.util, "find_spec", lambda name: None if name == "ray" else real(name)
    )
    with pytest.raises(SystemExit) as exc:
        main(["batch", str(spec)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "ray not installed" in err and "pip install 'eos_svc[batch]'" in err


def test_a_bad_spec_exits_2_naming_the_field(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "s.toml"
    spec.write_text('world = "mujoco"\n[objects]\nsuite = "quick"\n')
    with pytest.raises(SystemExit) as exc:
        main(["batch", str(spec)])
    assert exc.value.code == 2 and "world: must be one of 'kinematic', 'drake'" in capsys.readouterr().err


def test_planning_imports_neither_ray_nor_pyarrow() -> None:
    code = (
        "import sys\n"
        "import eos_svc.agents, eos_svc.batch, eos_svc.cli, eos_svc.cli.plan, eos_svc.cli.batch\n"
        "from eos_svc.agents import PlanRequest, plan\n"
        "plan(PlanRequest(), keep_trace=False)\n"
        "print(sorted({'ray', 'pyarrow'} & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.slow
def test_eos_batch_runs_a_spec_and_a_rerun_skips_it(tmp_path: Path) -> None:
    spec = tmp_path / "s.toml"
    spec.write_text('name = "two"\nseeds = [1, 2]\n[objects]\nsuite = "quick"\n')
    command = [sys.executable, "-m", "eos_svc.cli", "batch", str(spec), "--out", str(tmp_path / "o")]
    first = subprocess.run([*command, "--workers", "2", "--json"], capture_output=True, text=True, check=True)
    assert json.loads(first.stdout)["planned"] == 10
    again = subprocess.run([*command, "--json", "--no-progress"], capture_output=True, text=True, check=True)
    assert (json.loads(again.stdout)["planned"], json.loads(again.stdout)["skipped"]) == (0, 10)


@pytest.mark.slow
def test_a_driver_killed_mid_run_is_resumed_by_a_rerun_without_a_duplicate(tmp_path: Path) -> None:
    import os
    import signal
    import time

    from eos_svc.batch.store import read_manifest, read_rows

    spec = tmp_path / "s.toml"
    spec.write_text(
        'seeds = { first = 1, count = 6 }\n[objects]\nsuite = "quick"\n'
        "[run]\nplans_per_task = 1\nrows_per_file = 2\nflush_seconds = 0.0\n"
    )
    out = tmp_path / "o"
    command = [sys.executable, "-m", "eos_svc.cli", "batch", str(spec), "--out", str(out), "--no-progress"]
    driver = subprocess.Popen([*command, "--workers", "2"], start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while len(read_manifest(out)) < 2 and driver.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert driver.poll() is None, "the batch finished before it could be killed"
        os.killpg(driver.pid, signal.SIGKILL)  # the driver and the local Ray it started
    finally:
        driver.wait()
    done = sum(e["rows"] for e in read_manifest(out))
    assert 0 < done < 30
    again = subprocess.run([*command, "--json"], capture_output=True, text=True, check=True)
    summary = json.loads(again.stdout)
    assert summary["skipped"] >= done and summary["planned"] + summary["skipped"] == 30
    keys = read_rows(out).column("key").to_pylist()
    assert len(keys) == 30 == len(set(keys))
