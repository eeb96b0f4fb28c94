"""The controller: choice, stages, ends, records and callbacks."""

from __future__ import annotations

import threading
import time

import pytest

from eos_svc import (
    ActionResult,
    Agent,
    Board,
    CancelToken,
    Controller,
    CycleContext,
    CycleRecord,
    Outcome,
    RepeatPolicy,
    RunStatus,
    ValidationError,
    Weights,
)


class Scripted(Agent):
    """Acts by a script of outcomes; opportunistic sub-rating from a board entry."""

    def __init__(self, name, stages, default, outcomes=(Outcome.PROGRESS,), key=None, sets=None):
        super().__init__(name, stages, default)
        self.outcomes = list(outcomes)
        self.key = key
        self.sets = sets or {}
        self.calls = 0

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return board.get(self.key) if self.key else None

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        outcome = self.outcomes[min(self.calls, len(self.outcomes) - 1)]
        self.calls += 1
        board.set(f"{self.name}.calls", self.calls)
        return ActionResult(
            outcome,
            f"{self.name} call {self.calls}",
            ratings=self.sets,
            succeeded=True if outcome is Outcome.FINISHED else None,
        )


def test_tie_goes_to_the_agent_listed_first():
    a = Scripted("a", ["s"], 0.5, [Outcome.FINISHED])
    b = Scripted("b", ["s"], 0.5, [Outcome.FINISHED])
    result = Controller([a, b], ["s"]).run()
    assert result.agents_run() == ["a"]
    result = Controller(
        [Scripted("b", ["s"], 0.5, [Outcome.FINISHED]), Scripted("a", ["s"], 0.5, [Outcome.FINISHED])], ["s"]
    ).run()
    assert result.agents_run() == ["b"]


def test_only_agents_allowed_in_the_stage_are_rated():
    s1 = Scripted("s1", ["one"], 0.2, [Outcome.STAGE_COMPLETE])
    s2 = Scripted("s2", ["two"], 0.1, [Outcome.STAGE_COMPLETE])
    high = Scripted("high", ["two"], 0.9, [Outcome.PROGRESS])  # would win stage one if rated
    result = Controller([high, s1, s2], ["one", "two"], Weights(1.0, 0.0)).run()
    first = result.trace[0]
    assert [r.name for r in first.ratings] == ["s1"]
    assert first.chosen == "s1"
    assert [r.name for r in result.trace[1].ratings] == ["high", "s2"]
    assert result.agents_run() == ["s1", "high", "s2"]
    assert result.status is RunStatus.COMPLETED
    assert result.stages_completed == ("one", "two")
    assert result.cycles_per_stage == {"one": 1, "two": 2}


def test_agent_that_cannot_act_stalls_the_run():
    a = Scripted("a", ["s"], 0.9, [Outcome.CANNOT_ACT])
    result = Controller([a], ["s"]).run()
    assert result.status is RunStatus.STALLED
    assert "'a' cannot act" in result.reason
    assert result.trace[-1].outcome is Outcome.CANNOT_ACT


def test_default_only_gives_each_agent_once_then_stalls():
    # Paper §4.1, weights (1, 0): a fixed sequence, each agent once, then it stops.
    agents = [Scripted(n, ["s"], d, key="want") for n, d in [("f1", 0.9), ("f2", 0.8), ("w", 0.6)]]
    board = Board({"want": 1.0})
    result = Controller(agents, ["s"], Weights(1.0, 0.0)).run(board)
    assert result.agents_run() == ["f1", "f2", "w"]
    assert result.status is RunStatus.STALLED
    assert result.trace[-1].chosen is None
    assert not any(r.eligible for r in result.trace[-1].ratings)


def test_opportunistic_weight_lets_agents_repeat():
    agents = [Scripted(n, ["s"], d, key="want") for n, d in [("f1", 0.9), ("f2", 0.8)]]
    board = Board({"want": 1.0})
    result = Controller(agents, ["s"], Weights(0.5, 0.5), max_cycles=5).run(board)
    assert result.status is RunStatus.CYCLE_LIMIT
    assert result.agents_run() == ["f1", "f1", "f1", "f1", "f1"]
    assert result.cycles == 5


def test_always_policy_repeats_on_default_alone():
    a = Scripted("a", ["s"], 0.9)
    result = Controller([a], ["s"], Weights(1.0, 0.0), max_cycles=3, repeat_policy=RepeatPolicy.ALWAYS).run()
    assert result.agents_run() == ["a", "a", "a"]
    assert result.status is RunStatus.CYCLE_LIMIT


def test_opportunistic_asked_at_stage_start_and_set_by_previous_actor():
    # a sets b's opportunistic sub-rating; at the stage's first cycle every precondition test
    # is asked too (a's says 1.0), and nothing carries over from before the stage.
    a = Scripted("a", ["s"], 0.6, sets={"b": 1.0}, key="a_want")
    b = Scripted("b", ["s"], 0.1, [Outcome.FINISHED])
    board = Board({"a_want": 1.0})
    result = Controller([a, b], ["s"], Weights(0.5, 0.5)).run(board)
    first, second = result.trace[0], result.trace[1]
    assert first.rating_of("a").opportunistic == 1.0
    assert first.rating_of("b").opportunistic == 0.0
    assert first.rating_of("a").total == pytest.approx(0.8)
    assert first.chosen == "a"
    # cycle 2: a's own test says 1.0 (0.3 + 0.5), b was set to 1.0 by a (0.05 + 0.5)
    assert second.rating_of("b").opportunistic == 1.0
    assert second.rating_of("a").total == pytest.approx(0.8)
    assert second.chosen == "a"


def test_only_opportunistic_picks_first_listed_at_stage_start():
    # Paper §4.1 / §5, weights (0, 1): all totals 0 at a stage's start -> first listed.
    a = Scripted("first", ["s"], 0.1, [Outcome.CANNOT_ACT])
    b = Scripted("second", ["s"], 0.9, [Outcome.FINISHED])
    result = Controller([a, b], ["s"], Weights(0.0, 1.0)).run()
    assert result.trace[0].chosen == "first"
    assert all(r.total == 0.0 for r in result.trace[0].ratings)
    assert result.status is RunStatus.STALLED


def test_cycle_limit():
    a = Scripted("a", ["s"], 0.5, key="want")
    result = Controller([a], ["s"], max_cycles=7).run(Board({"want": 1.0}))
    assert result.status is RunStatus.CYCLE_LIMIT
    assert result.cycles == 7
    assert [r.seq for r in result.trace] == list(range(1, 8))


class Slow(Agent):
    def opportunistic(self, board, ctx):
        return 1.0

    def act(self, board, ctx):
        time.sleep(0.01)
        return ActionResult(Outcome.PROGRESS, "slept")


def test_deadline_ends_the_run():
    t0 = time.monotonic()
    result = Controller([Slow("slow", ["s"], 0.5)], ["s"], deadline_s=0.05, max_cycles=10_000).run()
    assert result.status is RunStatus.DEADLINE
    assert time.monotonic() - t0 < 1.0
    assert 2 <= result.cycles <= 10


def test_cancel_from_another_thread():
    token = CancelToken()
    timer = threading.Timer(0.03, token.cancel, kwargs={"reason": "user asked"})
    timer.start()
    result = Controller([Slow("slow", ["s"], 0.5)], ["s"], max_cycles=10_000).run(cancel=token)
    timer.join()
    assert result.status is RunStatus.CANCELLED
    assert result.reason == "user asked"


def test_callbacks_receive_every_record_in_order():
    seen_a: list[CycleRecord] = []
    seen_b: list[int] = []
    a = Scripted("a", ["s"], 0.5, key="want")
    controller = Controller([a], ["s"], max_cycles=4, callbacks=[seen_a.append])
    controller.add_callback(lambda r: seen_b.append(r.seq))
    result = controller.run(Board({"want": 1.0}))
    assert seen_a == list(result.trace)
    assert seen_b == [1, 2, 3, 4]


def test_record_contents_and_board_changes():
    a = Scripted("a", ["s"], 0.5, [Outcome.FINISHED])
    result = Controller([a], ["s"], Weights(0.4, 0.6)).run()
    record = result.trace[0]
    assert record.weights == Weights(0.4, 0.6)
    assert record.outcome is Outcome.FINISHED
    assert [(c.key, c.old, c.new, c.created) for c in record.changes] == [("a.calls", None, 1, True)]
    as_dict = record.to_dict()
    assert as_dict["chosen"] == "a" and as_dict["ratings"][0]["total"] == pytest.approx(0.2)
    assert as_dict["changes"] == [{"key": "a.calls", "old": None, "new": 1}]


def test_agent_exception_is_a_status_not_a_crash():
    class Broken(Agent):
        def act(self, board, ctx):
            raise RuntimeError("boom")

    result = Controller([Broken("broken", ["s"], 0.5)], ["s"]).run()
    assert result.status is RunStatus.ERROR
    assert "boom" in result.reason and "broken" in result.reason
    assert len(result.trace) == 1


def test_broken_callback_is_reported():
    def bad(record):
        raise ValueError("observer bug")

    a = Scripted("a", ["s"], 0.5, key="want")
    result = Controller([a], ["s"], callbacks=[bad]).run(Board({"want": 1.0}))
    assert result.status is RunStatus.ERROR
    assert "observer bug" in result.reason


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"stages": []}, "stages"),
        ({"stages": ["s", "s"]}, "stages"),
        ({"max_cycles": 0}, "max_cycles"),
        ({"deadline_s": -1.0}, "deadline_s"),
        ({"deadline_s": float("nan")}, "deadline_s"),
    ],
)
def test_bad_controller_arguments(kwargs, field):
    args = {"agents": [Scripted("a", ["s"], 0.5)], "stages": ["s"], **kwargs}
    with pytest.raises(ValidationError) as info:
        Controller(**args)
    assert info.value.field == field


def test_duplicate_names_and_unknown_stages_are_rejected():
    with pytest.raises(ValidationError, match="used twice"):
        Controller([Scripted("a", ["s"], 0.5), Scripted("a", ["s"], 0.4)], ["s"])
    with pytest.raises(ValidationError) as info:
        Controller([Scripted("a", ["t"], 0.5)], ["s"])
    assert info.value.field == "agents.a.stages"


def test_board_records_only_real_changes():
    board = Board({"x": 1})
    board.begin_cycle()
    board.set("x", 2)
    board.set("x", 1)  # back to the start: no change
    board.set("y", [1, 2])
    board.delete("missing")
    changes = board.end_cycle()
    assert [(c.key, c.new, c.created) for c in changes] == [("y", [1, 2], True)]
    board.set("z", 3)  # outside a cycle: not recorded, but written
    assert board["z"] == 3
