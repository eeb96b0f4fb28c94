"""The package people install: the wheel carries the URDF, and an installed eos_svc loads it
through importlib.resources and plans from a directory outside the checkout.

The wheel is built by pip as a user would (``pip wheel .``, build isolation) from a copy of the
sources, so the checkout is left clean. The quick tests install it with ``--target`` and run it
on this interpreter's dependencies; the slow one installs it with its dependencies into a fresh
venv without the system's site-packages.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "hand3x3.urdf"

EMBED = """
import importlib.resources, json, sys
import eos_svc
from eos_svc import ActionResult, Agent, Controller, Outcome, Weights
from eos_svc.agents import PlanRequest, plan
from eos_svc.kinematics import HAND3X3_URDF, load_hand

class Once(Agent):
    def act(self, board, ctx):
        return ActionResult(Outcome.FINISHED, "done", succeeded=True)

core = Controller([Once("once", ["s"], 0.5)], ["s"], Weights(0.5, 0.5)).run()
result = plan(PlanRequest(seed=3))
described = plan(PlanRequest(seed=1, hand="trifinger"))  # a shipped description (package data)
resource = importlib.resources.files("eos_svc.data").joinpath("hand3x3.urdf")
print(json.dumps({
    "package": eos_svc.__file__,
    "urdf": str(HAND3X3_URDF),
    "resource": str(resource),
    "nq": load_hand().nq,
    "core": core.status.value,
    "plan": result.status,
    "cycles": result.cycles,
    "trifinger": described.status,
    "trifinger_fingers": sorted(described.contacts),
}))
"""


def _outside_env() -> dict[str, str]:
    """The environment without the caller's PYTHONPATH (a checkout on it would count as eos_svc
    installed already) and VIRTUAL_ENV (the fresh venv's own interpreter and pip run)."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


def _pip(*args: str, python: str = sys.executable, cwd: Path | None = None) -> None:
    subprocess.run(
        [python, "-m", "pip", *args], check=True, cwd=cwd, env=_outside_env(), capture_output=True, text=True
    )


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for name in ("eos_svc", "urdf"):
        shutil.copytree(ROOT / name, src / name, ignore=ignore)
    out = tmp_path_factory.mktemp("wheelhouse")
    _pip("wheel", "--no-deps", "--quiet", "-w", str(out), str(src))
    (built,) = out.glob("eos_svc-*.whl")
    return built


def test_the_wheel_carries_the_urdf_every_module_and_data_file(wheel: Path):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert zipfile.ZipFile(wheel).read("eos_svc/data/hand3x3.urdf") == URDF.read_bytes()
    files = {
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "eos_svc").rglob("*")
        if p.is_file() and p.suffix != ".pyc" and "__pycache__" not in p.parts
    }
    assert any(f.endswith(".py") for f in files)
    assert files <= names, sorted(files - names)  # every module and every data file
    assert not any(n.startswith(("urdf/", "tests/", "benchmarks/")) for n in names)
    # the worked plug-in agent, nameable by an installed eos_svc (docs/extending.md)
    entry_points = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert "[eos_svc.agents]\nsampled_grasp_points = " in zipfile.ZipFile(wheel).read(entry_points).decode()


def test_installed_package_loads_its_urdf_through_importlib_resources(wheel: Path, tmp_path: Path):
    target = tmp_path / "site"
    _pip("install", "--no-deps", "--quiet", "--target", str(target), str(wheel))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target)}
    out = subprocess.run(
        [sys.executable, "-c", EMBED], cwd=elsewhere, env=env, check=True, capture_output=True, text=True
    ).stdout
    seen = json.loads(out)
    assert seen["package"].startswith(str(target))  # the installed copy, not the checkout
    assert seen["urdf"] == seen["resource"] == str(target / "eos_svc" / "data" / "hand3x3.urdf")
    assert seen["nq"] == 15 and seen["core"] == "completed" and seen["plan"] == "success"
    assert seen["trifinger"] == "success" and seen["trifinger_fingers"] == ["finger1", "finger2", "finger3"]


def test_the_wheel_declares_the_pytest_plugin(wheel: Path):
    """pytest loads eos_svc's fixtures wherever the wheel is installed (entry point pytest11)."""
    archive = zipfile.ZipFile(wheel)
    (entry_points,) = [n for n in archive.namelist() if n.endswith(".dist-info/entry_points.txt")]
    text = archive.read(entry_points).decode()
    assert "[pytest11]" in text
    assert "eos_svc.testing.pytest_plugin = eos_svc.testing.pytest_plugin" in text


@pytest.mark.slow
def test_fresh_venv_installs_the_wheel_and_runs_plan_ep1_and_an_embedding(wheel: Path, tmp_path: Path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)  # no system site-packages
    python = str(venv / "bin" / "python")
    _pip("install", "--quiet", str(wheel), python=python)  # dependencies from the index (pip cache)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = _outside_env()
    eos = str(venv / "bin" / "eos")
    plan = subprocess.run([eos, "plan", "--json"], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert plan.returncode == 0, plan.stderr
    assert json.loads(plan.stdout)["status"] == "success"
    ep1 = subprocess.run(
        [eos, "ep1", "--shape", "sphere", "--radius", "0.04"], cwd=elsewhere, env=env, capture_output=True,
        text=True,
    )  # fmt: skip
    assert ep1.returncode == 0, ep1.stderr
    assert "radius error" in ep1.stdout
    embed = subprocess.run(
        [python, "-c", EMBED], cwd=elsewhere, env=env, check=True, capture_output=True, text=True
    ).stdout
    seen = json.loads(embed)
    assert seen["package"].startswith(str(venv))
    assert seen["urdf"] == seen["resource"] and seen["urdf"].startswith(str(venv))
    assert seen["plan"] == "success"
