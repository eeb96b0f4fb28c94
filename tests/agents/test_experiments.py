"""The experiments run the real planner and write their files; the paper's outcomes hold."""

from __future__ import annotations

import json

from eos_svc.experiments import ablation, shapes


def test_ablation_reproduces_the_paper(tmp_path):
    data = ablation.run(seeds=2, sweep_points=3, out=tmp_path, quiet=True)
    one = data["one_seed"]
    assert one["1.0,0.0"]["status"] == "stalled" and one["1.0,0.0"]["stages_completed"] == []
    assert sorted(one["1.0,0.0"]["agents_run"]) == ["finger1", "finger2", "finger3", "wrist"]
    assert one["0.0,1.0"]["stages_completed"] == ["search", "information"]
    assert one["0.0,1.0"]["status"] == "stalled"
    assert one["0.5,0.5"]["all_stages"]
    sweep = {row["default_weight"]: row["completion_rate"] for row in data["sweep"]}
    assert sweep == {0.0: 0.0, 0.5: 1.0, 1.0: 0.0}
    assert json.loads((tmp_path / "ablation.json").read_text())["seeds"] == 2
    assert (tmp_path / "ablation.png").stat().st_size > 1000


def test_shapes_experiment_grasps_every_class(tmp_path, monkeypatch):
    monkeypatch.setattr(shapes, "OBJECTS", shapes.OBJECTS[:10:2])  # one size per class keeps it quick
    data = shapes.run(seeds=1, out=tmp_path, quiet=True)
    rows = {row["shape"]: row for row in data["rows"]}
    assert set(rows) == {"sphere", "ellipsoid", "cylinder", "capsule", "box"}
    assert all(row["grip_rate"] == 1.0 for row in rows.values()), data["rows"]  # a precision grip each
    assert rows["sphere"]["success_rate"] == 1.0  # and a good one on the sphere
    assert all(row["success_rate"] <= row["grip_rate"] for row in rows.values())  # success needs a grip
    assert (tmp_path / "shapes.csv").read_text().startswith("object,")


def test_shapes_experiment_measures_the_grasp_stage_with_the_true_object(tmp_path, monkeypatch):
    upright = [row for row in shapes.OBJECTS if row[0] == "cylinder r20 l80 upright"]
    monkeypatch.setattr(shapes, "OBJECTS", tuple(upright))
    data = shapes.run(seeds=1, out=tmp_path, quiet=True, oracle=True)
    (row,) = data["rows"]
    # the grasp stage alone: with the true (upright) cylinder as postulate the wrist turns and
    # closes across the axis, a good grasp
    assert row["oracle_success_rate"] == 1.0 and row["oracle_statuses"] == "success"
    assert "oracle success" in shapes.report(data)


def test_recognition_experiment_writes_its_files(tmp_path):
    from eos_svc.experiments import recognition

    data = recognition.run(seeds=1, sizes=1, noises=(2e-4,), search_seeds=4, out=tmp_path, quiet=True)
    rows = json.loads((tmp_path / "recognition.json").read_text())["rows"]
    assert {r["truth"] for r in rows} == set(recognition.CLASSES)
    d = data["per_noise"]["0.0002"]
    assert sum(sum(row.values()) for row in d["confusion"].values()) == len(rows) == 5
    assert data["search"]["seeds"] == 4 and data["search"]["hit_limit"] == 0
    for name in ("recognition_confusion.png", "recognition_calibration.png", "recognition_search.png"):
        assert (tmp_path / name).stat().st_size > 1000


def test_learning_stream_without_repeats_reports_none(tmp_path):
    from eos_svc.experiments import learning

    data = learning.run(repeats=1, seed=1, out=tmp_path, quiet=True)  # every object once: no repeat
    assert not any(row["repeat"] for row in data["rows"]) and len(data["rows"]) == len(learning.OBJECTS)
    assert data["summary"]["repeated"] == {"without": None, "with": None}
    assert data["summary"]["repeated_reduction"] is None
    saved = json.loads((tmp_path / "learning.json").read_text())  # strict JSON: no NaN
    assert saved["summary"]["new"] == data["summary"]["new"]
    assert "repeated: none (- fewer)" in learning.report(data)
