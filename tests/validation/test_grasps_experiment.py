"""``eos experiment grasps`` end to end on a tiny subset: files written, numbers consistent."""

from __future__ import annotations

import csv
import json

from eos_svc.experiments import grasps
from eos_svc.experiments.grasp_suite import fixed_suite, held_back_suite, quick_suite


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
    assert "confusion" in grasps.report(data)
