"""The accuracy experiment: noise-free goals (fast) and the full table (slow)."""

from __future__ import annotations

import json

import pytest

from eos_svc.experiments import accuracy


def test_noise_free_goals_met():
    rows = accuracy.run_noise_free()
    assert [r.case for r in rows] == [c[0] for c in accuracy.CASES]
    for r in rows:
        assert r.ok, r
        assert r.max_slip < 1e-6 and r.max_gap < 1e-5
    table = accuracy.format_tables(rows, [])
    assert table.count("PASS") == len(rows)


def test_main_prints_a_table(capsys):
    assert accuracy.main(["--no-noise"]) == 0
    out = capsys.readouterr().out
    assert "| sphere R=8 cm |" in out and "all goals met: True" in out
    assert accuracy.main(["--no-noise", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["all_ok"] and len(d["noise_free"]) == 7


@pytest.mark.slow
def test_noisy_median_radius_error_within_five_percent():
    rows = accuracy.run_noisy(seeds=8)
    for r in rows:
        assert r.median_radius_error <= 0.05, r


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--seeds", "0"], "--seeds"),
        (["--noise", "nan"], "--noise"),
        (["--target-rating", "1.5"], "--target-rating"),
    ],
)
def test_bad_options_exit_2_naming_the_option(argv, option, capsys):
    with pytest.raises(SystemExit) as exit_info:
        accuracy.main(argv)
    assert exit_info.value.code == 2 and f"argument {option}:" in capsys.readouterr().err
