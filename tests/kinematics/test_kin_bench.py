"""The kinematics benchmark runs (a few calls only; the numbers are in docs/kinematics.md)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_kinematics.py"


def test_bench_smoke(capsys: pytest.CaptureFixture[str]) -> None:
    spec = importlib.util.spec_from_file_location("bench_kinematics", BENCH)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.main(number=20, repeat=2)
    assert out["update_us"] > 0 and out["ratio"] > 0
    assert "floor" in capsys.readouterr().out
