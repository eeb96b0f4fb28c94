"""The learned sub-rating end to end: a repeated object is grasped in fewer cycles."""

from __future__ import annotations

from eos_svc import Weights
from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.memory import GraspMemory

LEARNING = Weights(0.25, 0.25, 0.5)


def test_repeated_object_takes_fewer_grasp_cycles(tmp_path):
    path = tmp_path / "memory.sqlite"
    first = plan(PlanRequest(seed=3, weights=LEARNING), memory=GraspMemory(path))
    assert first.status == "success"
    assert "recall" not in first.agents_run()  # nothing remembered yet: behaves as without learning
    # a new process would open the same file: the memory survives the restart
    second = plan(PlanRequest(seed=3, weights=LEARNING), memory=GraspMemory(path))
    assert second.status == "success"
    assert "recall" in second.agents_run()
    row = next(r for r in second.trace if r.chosen == "recall")
    assert row.rating_of("recall").learned > 0.5
    assert second.cycles_per_stage["grasping"] <= 0.7 * first.cycles_per_stage["grasping"]


def test_without_learned_weight_recall_is_never_chosen(tmp_path):
    memory = GraspMemory(tmp_path / "m.sqlite")
    plan(PlanRequest(seed=3, weights=LEARNING), memory=memory)
    again = plan(PlanRequest(seed=3), memory=memory)  # weights (0.5, 0.5, 0)
    assert "recall" not in again.agents_run()
    assert again.status == "success"


def test_first_sighting_matches_the_plain_planner(tmp_path):
    learned = plan(PlanRequest(seed=4, weights=LEARNING), memory=GraspMemory(tmp_path / "m.sqlite"))
    plain = plan(PlanRequest(seed=4))
    assert learned.agents_run() == plain.agents_run()
