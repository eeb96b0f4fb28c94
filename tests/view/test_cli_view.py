"""The view options of the command line: --html (plan, replay), --view; bad input names the option."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from eos_svc.cli import main


def eos(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "eos_svc.cli", *args], capture_output=True, text=True, timeout=120, check=False
    )


def _cycles(page):
    text = page.read_text(encoding="utf-8")
    return json.loads(re.search(r'id="eos-plan">(.*?)</script>', text).group(1))["cycles"]


def test_plan_and_replay_write_the_same_page_content(tmp_path, capsys):
    record, planned, replayed = tmp_path / "run.jsonl", tmp_path / "plan.html", tmp_path / "replay.html"
    shape = ["--shape", "capsule", "--radius", "0.02", "--length", "0.05", "--seed", "5"]
    # exit 0 or 1 by the plan's status: any status is drawn
    assert main(["plan", "--quiet", *shape, "--record", str(record), "--html", str(planned)]) in (0, 1)
    assert main(["replay", str(record), "--quiet", "--html", str(replayed)]) == 0
    out = capsys.readouterr().out
    assert "replay: deterministic" in out and f"html: {replayed}" in out
    cycles = [json.loads(line) for line in record.read_text().splitlines()[1:-1]]
    assert _cycles(planned) == _cycles(replayed)
    assert [c["seq"] for c in _cycles(planned)] == [c["seq"] for c in cycles]
    assert "capsule" in planned.read_text(encoding="utf-8")


def test_replay_of_a_recording_without_the_hand_configuration_uses_the_rerun(tmp_path, capsys):
    """A recording from before ``hand_q`` existed still verifies, and its page shows the hand moving
    (the re-run's configurations)."""
    record, page = tmp_path / "old.jsonl", tmp_path / "old.html"
    assert main(["plan", "--quiet", "--record", str(record)]) == 0
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    for cycle in lines[1:-1]:
        cycle["changes"] = [c for c in cycle["changes"] if c["key"] not in ("hand_q", "hand_path")]
    record.write_text("\n".join(json.dumps(x) for x in lines) + "\n")
    assert main(["replay", str(record), "--quiet", "--html", str(page)]) == 0
    assert "replay: deterministic" in capsys.readouterr().out
    unverified = tmp_path / "unverified.html"
    assert main(["replay", str(record), "--quiet", "--no-verify", "--html", str(unverified)]) == 0
    for drawn in (page, unverified):
        # the page animates the rolls planned again: an EP1 cycle lasts its roll, not 4 frames
        ep1 = [c for c in _cycles(drawn) if c["chosen"] == "ep1"]
        assert ep1 and min(c["t1"] - c["t0"] for c in ep1) > 1.0


def test_plan_view_serves_a_page_and_prints_its_url(tmp_path):
    proc = eos("plan", "--quiet", "--view", "--view-hold", "0")
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"view: http://\S+:\d+", proc.stderr)
    assert "status: success" in proc.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["plan", "--html", "/nonexistent-dir/plan.html"], "--html: cannot write"),
        (["plan", "--view", "--view-port", "0"], "--view-port: must be a port in [1024, 65535]"),
        (["plan", "--view", "--view-port", "80"], "--view-port: must be a port in [1024, 65535]"),
        (["plan", "--view-port", "9000"], "--view-port: needs --view"),
        (["plan", "--view", "--view-hold", "nan"], "--view-hold: must be finite"),
        (["client", "watch", "--view-port", "99999"], "--view-port: needs --view"),
        (["plan", "--view", "--view-wait", "-1"], "--view-wait"),
        (["replay", "/nonexistent-dir/run.jsonl", "--html", "x.html"], "FILE: cannot read"),
    ],
)
def test_bad_view_options_exit_2_naming_the_option(args, message):
    proc = eos(*args)
    assert proc.returncode == 2
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr


def test_replay_html_of_a_request_this_version_refuses_names_it(tmp_path):
    """--no-verify (no re-run) and a recorded request this version refuses: exit 2 naming the
    field, never a traceback."""
    record = tmp_path / "run.jsonl"
    assert main(["plan", "--quiet", "--record", str(record)]) == 0
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    lines[0]["request"]["object"]["shape"] = "cone"
    record.write_text("\n".join(json.dumps(x) for x in lines) + "\n")
    proc = eos("replay", str(record), "--quiet", "--no-verify", "--html", str(tmp_path / "b.html"))
    assert proc.returncode == 2 and "--html: the plan's request is not valid" in proc.stderr
    assert "object.shape" in proc.stderr and "Traceback" not in proc.stderr
