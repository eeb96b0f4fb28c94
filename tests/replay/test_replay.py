"""eos plan --record / eos replay (determinism check) and eos plan --picture."""

from __future__ import annotations

import json

import pytest

from eos_svc.cli import main
from eos_svc.cli.replay import verify
from eos_svc.recording import RecordFileError, first_difference, read_recording, record_from_dict


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("replay") / "run.jsonl"
    assert main(["plan", "--quiet", "--seed", "3", "--record", str(path)]) == 0
    return path


def test_record_file_layout(recorded):
    header, *cycles, footer = [json.loads(line) for line in recorded.read_text().splitlines()]
    assert header == {"eos_record": "header", "schema": 1, "request": header["request"], "hand": "hand3x3"}
    assert header["request"]["seed"] == 3 and header["request"]["friction"] == 0.5
    assert [c["seq"] for c in cycles] == list(range(1, len(cycles) + 1))
    assert all("eos_record" not in c for c in cycles)
    assert footer["eos_record"] == "result" and footer["result"]["cycles"] == len(cycles)
    assert "trace" not in footer["result"] and len(footer["result"]["q_final"]) == 15


def test_cycle_lines_round_trip_through_cycle_record(recorded):
    rec = read_recording(recorded)
    for data in rec.cycles:
        assert record_from_dict(data).to_dict() == data


def test_replay_prints_trace_and_result_and_is_deterministic(recorded, capsys):
    assert main(["plan", "--seed", "3"]) == 0
    planned = capsys.readouterr().out
    assert main(["replay", str(recorded)]) == 0
    replayed = capsys.readouterr().out
    # the same trace lines and summary as `eos plan` (timing line aside)
    strip = [line for line in planned.splitlines() if not line.startswith("seed ")]
    assert [line for line in replayed.splitlines() if not line.startswith("seed ")][: len(strip)] == strip
    assert "replay: deterministic" in replayed


def test_replay_reports_a_divergence(recorded, tmp_path, capsys):
    lines = recorded.read_text().splitlines()
    cycle = json.loads(lines[5])
    cycle["detail"] = "tampered"
    lines[5] = json.dumps(cycle)
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join(lines) + "\n")
    assert main(["replay", "--quiet", str(bad)]) == 1
    out = capsys.readouterr().out
    assert "DIVERGED — first at cycle 5: detail" in out and "recorded: tampered" in out


def test_replay_detects_a_changed_result(recorded, tmp_path):
    lines = recorded.read_text().splitlines()
    footer = json.loads(lines[-1])
    footer["result"]["epsilon"] = 0.0
    lines[-1] = json.dumps(footer)
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join(lines) + "\n")
    v = verify(read_recording(bad))
    assert not v.identical and v.divergences == [
        ("result", "epsilon", 0.0, pytest.approx(v.replayed_result["epsilon"]))
    ]


def test_replay_without_verification(recorded, capsys):
    assert main(["replay", "--no-verify", str(recorded)]) == 0
    out = capsys.readouterr().out
    assert "status: success" in out and "replay:" not in out


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "empty file"),
        ("not json\n", "line 1: not JSON"),
        ('{"seq": 1}\n', "line 1: no header"),
        ('{"eos_record": "header", "schema": 99, "request": {}}\n', "schema 99"),
        ('{"eos_record": "header", "schema": 1, "request": {}}\n{"seq": 2}\n', "out of order"),
        ('{"eos_record": "header", "schema": 1, "request": {}}\n[1]\n', "line 2: not a JSON object"),
    ],
)
def test_bad_record_files(tmp_path, content, message):
    path = tmp_path / "r.jsonl"
    path.write_text(content)
    with pytest.raises(RecordFileError, match=message):
        read_recording(path)


def test_bad_record_file_exits_2(tmp_path, capsys):
    path = tmp_path / "r.jsonl"
    path.write_text("nope\n")
    with pytest.raises(SystemExit) as exc:
        main(["replay", str(path)])
    assert exc.value.code == 2 and "not JSON" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["replay", str(tmp_path / "missing.jsonl")])
    assert "cannot read" in capsys.readouterr().err


def test_first_difference_paths():
    assert (
        first_difference({"a": [1, {"b": 2}], "elapsed_s": 1.0}, {"a": [1, {"b": 2}], "elapsed_s": 2.0})
        is None
    )
    assert first_difference({"a": [1, {"b": 2}]}, {"a": [1, {"b": 3}]}) == ("a[1].b", 2, 3)
    assert first_difference({"a": [1]}, {"a": [1, 2]}) == ("a (length)", 1, 2)
    assert first_difference({"a": 1}, {"a": 1.0}) == ("a", 1, 1.0)
    assert first_difference({"a": 1}, {}) == ("a", 1, "<absent>")


def test_plan_picture(tmp_path, capsys):
    png = tmp_path / "grasp.png"
    assert main(["plan", "--quiet", "--picture", str(png)]) == 0
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_unknown_hand_in_a_recording(recorded, tmp_path, capsys):
    lines = recorded.read_text().splitlines()
    header = json.loads(lines[0])
    header["hand"] = "octopus"
    lines[0] = json.dumps(header)
    bad = tmp_path / "hand.jsonl"
    bad.write_text("\n".join(lines) + "\n")
    assert read_recording(bad).hand == "octopus"
    with pytest.raises(SystemExit) as exc:
        main(["replay", "--quiet", str(bad)])
    assert exc.value.code == 2 and "unknown hand 'octopus'" in capsys.readouterr().err


def test_recorded_hand_is_replayed(tmp_path, capsys):
    path = tmp_path / "allegro.jsonl"
    assert main(["plan", "--quiet", "--hand", "allegro", "--max-cycles", "30", "--record", str(path)]) in (
        0,
        1,
    )
    assert json.loads(path.read_text().splitlines()[0])["hand"] == "allegro"
    capsys.readouterr()
    assert main(["replay", "--quiet", str(path)]) == 0
    assert "replay: deterministic" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("field", "value"), [("contacts", [1, 2]), ("ground_truth", "a sphere"), ("friction", "high")]
)
def test_a_hand_edited_result_line_exits_2(recorded, tmp_path, capsys, field, value):
    lines = recorded.read_text().splitlines()
    last = json.loads(lines[-1])
    last["result"][field] = value
    path = tmp_path / "edited.jsonl"
    path.write_text("\n".join([*lines[:-1], json.dumps(last)]) + "\n")
    with pytest.raises(SystemExit) as exc:
        main(["replay", str(path), "--quiet", "--no-verify"])
    assert exc.value.code == 2 and "the result line is not a plan result" in capsys.readouterr().err
