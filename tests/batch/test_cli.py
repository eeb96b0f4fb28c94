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
    spec.write_text('world = "drake"\n[objects]\nsuite = "quick"\n')
    with pytest.raises(SystemExit) as exc:
        main(["batch", str(spec)])
    assert exc.value.code == 2 and "world: only 'kinematic'" in capsys.readouterr().err


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
