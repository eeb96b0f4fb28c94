"""``eos experiment grasps`` end to end on a tiny subset: files written, numbers consistent."""

from __future__ import annotations

import csv
import json

import numpy as np

from eos_svc.experiments import grasps, grasps_report
from eos_svc.experiments.grasp_suite import fixed_suite, held_back_suite, quick_suite, random_draw


def test_suites_cover_every_class_and_differ():
    fixed, held_back = fixed_suite(), held_back_suite()
    classes = {"sphere", "ellipsoid", "cylinder", "capsule", "box"}
    assert {o.spec.shape for o in fixed} == classes == {o.spec.shape for o in held_back}
    assert {o.spec.shape for o in quick_suite()} == classes
    assert len({o.label for o in fixed}) == len(fixed)  # labels name rows: unique
    fixed_specs = {(o.spec.shape, tuple(o.spec.size.items()), o.spec.position, o.spec.rpy) for o in fixed}
    assert not fixed_specs & {
        (o.spec.shape, tuple(o.spec.size.items()), o.spec.position, o.spec.rpy) for o in held_back
    }
    assert held_back_suite() == held_back  # seeded: the same objects every time
    assert held_back_suite(seed=7) != held_back


def test_tiny_suite_end_to_end(tmp_path):
    by_label = {o.label: o for o in fixed_suite()}
    objects = [by_label["sphere d/h 0.50"], by_label["box cube 50 yaw 0"]]
    data = grasps.run(
        objects, seeds=1, out=tmp_path, quiet=True, validation={"seconds": 0.4, "directions": 2}
    )
    for name in ("grasps.json", "grasps.csv", "grasps_runs.csv", "grasps.png"):
        assert (tmp_path / name).stat().st_size > 100, name
    saved = json.loads((tmp_path / "grasps.json").read_text())
    assert saved["totals"] == data["totals"]
    runs = data["runs"]
    assert [r["object"] for r in runs] == [o.label for o in objects]
    totals = data["totals"]
    assert sum(totals["confusion"].values()) == totals["runs"] == len(runs)
    assert totals["confusion"]["good_held"] == sum(r["good_grasp"] and r["held"] for r in runs)
    for row, run in zip(data["rows"], runs, strict=True):
        assert row["runs"] == 1
        assert row["good_grasp_rate"] == float(run["good_grasp"]) and row["held_rate"] == float(run["held"])
        assert row["median_plan_time_s"] == run["plan_time_s"] > 0
    sphere = runs[0]
    assert sphere["status"] == "success" and sphere["good_grasp"] and sphere["held"], sphere
    with (tmp_path / "grasps_runs.csv").open() as f:
        assert [r["object"] for r in csv.DictReader(f)] == [o.label for o in objects]
    assert "confusion" in grasps_report.report(data)


def test_random_draw_is_seeded_and_within_its_ranges():
    from eos_svc.experiments.grasp_suite import (
        DRAW_CLASSES,
        DRAW_POSITION_SPREAD,
        random_draw,
    )
    from eos_svc.schema.request import ObjectSpec

    span = 0.2
    draw = random_draw(60, draw_seed=5, sizes=(0.2, 0.4), span=span)
    assert draw == random_draw(60, draw_seed=5, sizes=(0.2, 0.4), span=span)  # seeded
    assert draw != random_draw(60, draw_seed=6, sizes=(0.2, 0.4), span=span)
    assert {o.spec.shape for o in draw} == set(DRAW_CLASSES)
    assert len({o.label for o in draw}) == len(draw)
    base = ObjectSpec().position  # the default request's
    for o in draw:
        size = o.spec.size
        widths = (
            ([2 * size["radius"]] if "radius" in size else [])
            + [2 * r for r in size.get("radii", ())]
            + list(size.get("size", ()))
            + ([size["length"]] if "length" in size else [])
        )
        for w in widths:  # every full width in [0.2, 0.4] x span (rounded to 0.1 mm)
            assert 0.2 * span - 2e-4 <= w <= 0.4 * span + 2e-4, (o.label, size)
        for p, b, s in zip(o.spec.position, base, DRAW_POSITION_SPREAD, strict=True):
            assert abs(p - b) <= s + 1e-4
        assert o.seed >= 1


def test_random_draw_experiment_lists_failures_and_refusals(tmp_path, capsys):
    code = grasps.main(["--random", "8", "--draw-seed", "2", "--no-validate", "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "grasps_random.json").read_text())
    totals = data["totals"]
    assert totals["runs"] + totals["rejected"] == 8
    assert sum(totals["refused_by_field"].values()) == totals["rejected"]
    assert totals["validated"] == 0 and all(r["held"] is None for r in data["runs"])
    not_good = [r for r in data["runs"] if r["status"] != "rejected" and not r["good_grasp"]]
    assert [f["object"] for f in totals["failures"]] == [r["object"] for r in not_good]
    for f in totals["failures"]:  # every failure named, with its status and reason
        assert f"{f['object']} seed {f['seed']}: {f['status']}" in out
    assert totals["success_without_good_grasp"] == 0
    assert "refused by admission" in out
    # recognition and the touches and probes of every admitted plan
    admitted = [r for r in data["runs"] if r["status"] != "rejected"]
    assert totals["touches_median"] == np.median([r["touches"] for r in admitted])
    assert all(r["probes"] >= r["touches"] - 2 for r in admitted)  # EP1's two contacts: its runs
    assert totals["class_right_rate"] == np.mean([r["class_right"] for r in admitted])
    assert "touches median" in out and "shape error p90" in out


def test_random_draw_sizes_are_checked(capsys):
    import pytest

    with pytest.raises(SystemExit) as exc:
        grasps.main(["--random", "2", "--sizes", "0.5", "0.2"])
    assert exc.value.code == 2
    assert "--sizes: LO must be ≤ HI" in capsys.readouterr().err


def test_random_draw_counts_the_fit_rule(tmp_path):
    # large objects: the refusals for size are exactly those the fit rule refuses
    from eos_svc.world.fingertip_fit import fit_refusal
    from eos_svc.world.hand_context import default_context

    code = grasps.main(
        [
            "--random",
            "6",
            "--draw-seed",
            "4",
            "--sizes",
            "0.7",
            "1.0",
            "--no-validate",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / "grasps_random.json").read_text())
    ctx = default_context()
    too_large = [
        o for o in random_draw(6, 4, (0.7, 1.0)) if fit_refusal(o.spec, ctx.opening, ctx.params.clearance)
    ]
    assert too_large  # objects this large mostly do not fit
    assert data["totals"]["refused_by_reason"]["too large"] == len(too_large)
    assert data["totals"]["good_goal"] == grasps_report.GOOD_GOAL
