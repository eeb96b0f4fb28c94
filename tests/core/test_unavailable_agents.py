"""Controller rule 5: an unavailable agent rates 0 and is skipped; every row says where and how long."""

from __future__ import annotations

from eos_svc import ActionResult, Agent, AgentUnavailableError, Board, Controller, Outcome, Weights
from eos_svc.recording import first_difference
from eos_svc.records import REPEAT_SKIP


class Step(Agent):
    """Reports progress; finishes the run on its third action."""

    def act(self, board, ctx):
        board.set("steps", board.get("steps", 0) + 1)
        if board["steps"] == 3:
            return ActionResult(Outcome.FINISHED, "three steps", succeeded=True)
        return ActionResult(Outcome.PROGRESS, "a step")

    def opportunistic(self, board, ctx):
        return 0.5


class Flaky(Agent):
    """Rated highest, but cannot rate itself in odd cycles nor act at all."""

    location = "remote"

    def opportunistic(self, board, ctx):
        if ctx.seq % 2:
            raise AgentUnavailableError("no reply within 5 ms")
        return 1.0

    def act(self, board, ctx):
        board.set("flaky", True)  # written, then the action fails: a remote proxy writes nothing
        raise AgentUnavailableError("its action's reply came too late")


def test_unavailable_agent_rates_zero_is_skipped_and_the_run_carries_on() -> None:
    controller = Controller([Step("step", ["s"], 0.5), Flaky("flaky", ["s"], 0.9)], ["s"], Weights(0.5, 0.5))
    result = controller.run(Board())
    assert result.status == "completed"
    assert result.reason.startswith("three steps; agent 'flaky' was unavailable in 5 cycle(s) from cycle 1")
    first, second = result.trace[0], result.trace[1]
    row = first.rating_of("flaky")
    assert (row.opportunistic, row.total, row.eligible) == (0.0, 0.0, False)
    assert row.skipped == "unavailable: no reply within 5 ms"
    assert row.where == "remote"
    assert first.chosen == "step"
    # cycle 2: flaky rates 0.95 and is chosen; its action fails: no outcome, the reason recorded
    assert second.chosen == "flaky"
    assert second.outcome is None
    assert "unavailable: its action's reply came too late" in second.detail
    assert second.rating_of("step").where == "local"
    assert all(r.latency_s >= 0.0 for rec in result.trace for r in rec.ratings)
    assert result.agents_run() == ["step", "flaky", "step", "flaky", "step"]
    as_json = first.to_dict()["ratings"][1]
    assert as_json["where"] == "remote" and as_json["skipped"].startswith("unavailable")


def test_repeat_rule_skips_say_so() -> None:
    class Once(Agent):
        def act(self, board, ctx):
            return ActionResult(Outcome.PROGRESS, "once")

    result = Controller([Once("a", ["s"], 0.6), Once("b", ["s"], 0.5)], ["s"], Weights(0.5, 0.5)).run()
    assert result.status == "stalled"
    last = result.trace[-1]
    assert [r.skipped for r in last.ratings] == [REPEAT_SKIP, REPEAT_SKIP]
    assert result.trace[0].rating_of("a").skipped is None


def test_records_written_before_the_new_fields_still_compare_equal() -> None:
    result = Controller([Step("step", ["s"], 0.5)], ["s"]).run()
    new = result.trace[0].to_dict()
    old = {
        **new,
        "ratings": [
            {k: v for k, v in r.items() if k not in ("where", "latency_s", "skipped")} for r in new["ratings"]
        ],
    }
    assert first_difference(old, new) is None
    assert first_difference(new, {**new, "ratings": [{**new["ratings"][0], "where": "remote"}]}) is not None


def test_the_plan_trace_marks_remote_agents_and_says_why_they_were_skipped() -> None:
    from eos_svc.cli.plan import format_cycle

    controller = Controller([Step("step", ["s"], 0.5), Flaky("flaky", ["s"], 0.9)], ["s"], Weights(0.5, 0.5))
    first = controller.run(Board()).trace[0]
    text = format_cycle(first)
    assert "flaky@remote=0.00·" in text and "step=0.50" in text
    assert "flaky skipped: unavailable: no reply within 5 ms" in text
