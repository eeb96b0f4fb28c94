"""The animation timeline built from cycle records (JSON form)."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, keys, plan
from eos_svc.agents.planner import default_hand
from eos_svc.view.timeline import CYCLE_FRAMES, MAX_STEP_M, MAX_STEP_RAD, build_timeline


@pytest.fixture(scope="module")
def planned():
    result = plan(PlanRequest(seed=3))
    return result, [r.to_dict() for r in result.trace]


def test_keyframes_visit_every_recorded_configuration_in_order(planned):
    result, records = planned
    tl = build_timeline(records, default_hand().neutral())
    frames = [f for f, _ in tl.keyframes]
    assert frames == sorted(frames) and frames[0] == 0
    visited = [q for _, q in tl.keyframes]
    for record in records:
        for change in record["changes"]:
            if change["key"] == keys.HAND_Q:
                assert tuple(change["new"]) in visited
    assert np.allclose(tl.keyframes[-1][1], result.q_final, atol=1e-7)
    # small steps between keyframes where joints turn: the bodies follow the kinematics between
    # them (a pure wrist translation needs none: every body translates with the wrist)
    for (_, a), (_, b) in zip(tl.keyframes, tl.keyframes[1:], strict=False):
        a, b = np.array(a), np.array(b)
        if np.any(a[3:] != b[3:]):
            assert np.linalg.norm(b[:3] - a[:3]) <= MAX_STEP_M + 1e-9
            assert np.max(np.abs(b[3:] - a[3:])) <= MAX_STEP_RAD + 1e-9


def test_cycle_spans_tile_the_time_and_ep1_takes_longer(planned):
    _, records = planned
    tl = build_timeline(records, default_hand().neutral())
    assert [s.seq for s in tl.spans] == [r["seq"] for r in records]
    assert tl.spans[0].start == 0
    for a, b in zip(tl.spans, tl.spans[1:], strict=False):
        assert b.start == a.end and a.end - a.start >= CYCLE_FRAMES
    ep1 = [s for s in tl.spans if s.chosen == "ep1"]
    search = [s for s in tl.spans if s.stage == "search"]
    assert min(s.end - s.start for s in ep1) > 4 * max(s.end - s.start for s in search)
    assert tl.frames == tl.spans[-1].end and tl.duration_s == tl.frames / tl.fps
    assert tl.verdict is not None and tl.verdict[0] == tl.spans[-1].end  # end judged in the last cycle


def test_records_without_the_hand_configuration_give_a_still_hand():
    """An older recording (no hand_q): one keyframe, the cycles still on the timeline."""
    records = [
        {"seq": 1, "stage": "search", "chosen": "wrist", "outcome": "progress", "detail": "", "changes": []},
        {
            "seq": 2,
            "stage": "search",
            "chosen": "wrist",
            "outcome": "progress",
            "detail": "",
            "changes": [{"key": keys.HAND_Q, "old": None, "new": [1.0, "x"]}],
        },  # malformed: ignored
    ]
    tl = build_timeline(records, default_hand().neutral())
    assert len(tl.keyframes) == 1 and len(tl.spans) == 2 and tl.frames == 2 * CYCLE_FRAMES
