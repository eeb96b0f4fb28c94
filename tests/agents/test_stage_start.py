"""The grasp agents keep the paper's §5 rule themselves: at a stage's first cycle every
opportunistic sub-rating is 0 (the core asks every precondition test every cycle)."""

from __future__ import annotations

from eos_svc import ActionResult, Board, Controller, Outcome, Weights
from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.base import GraspAgent


class Eager(GraspAgent):
    """Its own test always says 1; acts twice then completes the stage."""

    def opportunistic(self, board, ctx):
        return 1.0

    def act(self, board, ctx):
        done = ctx.acted.get(self.name, 0) >= 1
        return ActionResult(Outcome.STAGE_COMPLETE if done else Outcome.PROGRESS, "acted")


def test_grasp_agent_test_is_zero_at_each_stage_start_then_asked():
    agent = Eager("eager", ["one", "two"], 0.4, world=None)  # type: ignore[arg-type]
    result = Controller([agent], ["one", "two"], Weights(0.5, 0.5)).run(Board())
    opp = [(r.stage, r.stage_cycle, r.ratings[0].opportunistic) for r in result.trace]
    assert opp == [("one", 0, 0.0), ("one", 1, 1.0), ("two", 0, 0.0), ("two", 1, 1.0)]


def test_every_stage_of_a_plan_starts_with_zero_opportunistic_ratings():
    for seed in (2, 9):
        result = plan(PlanRequest(seed=seed))
        firsts = [r for r in result.trace if r.stage_cycle == 0]
        assert [r.stage for r in firsts] == ["search", "information", "grasping"]
        assert all(row.opportunistic == 0.0 for r in firsts for row in r.ratings)
        # and later cycles are asked: some opportunistic rating is positive in every stage
        for stage in ("search", "information", "grasping"):
            later = [r for r in result.trace if r.stage == stage and r.stage_cycle > 0]
            assert any(row.opportunistic > 0.0 for r in later for row in r.ratings), stage
