"""Ratings and weights: the paper's Table 1 and validation."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from eos_svc import (
    ActionResult,
    Agent,
    Board,
    Controller,
    CycleContext,
    Outcome,
    ValidationError,
    Weights,
)


class Fixed(Agent):
    """An agent whose opportunistic sub-rating is a fixed number."""

    def __init__(self, name: str, default: float, opportunistic: float, stages=("s",)) -> None:
        super().__init__(name, stages, default)
        self.value = opportunistic

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return self.value

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        return ActionResult(Outcome.PROGRESS, f"{self.name} acted")


TABLE_1 = [  # paper Table 1: (agent, P(A|B_d), P(A|B_o), P(A))
    ("Agent1", 0.90, 0.00, 0.45),
    ("Agent2", 0.60, 0.80, 0.70),
    ("Agent3", 1.00, 0.20, 0.60),
    ("Agent4", 0.40, 0.50, 0.45),
]


def table1_controller() -> Controller:
    agents = [Fixed(name, d, o) for name, d, o, _ in TABLE_1]
    # A warm-up stage makes the opportunistic sub-ratings live in stage "s"
    # (at a stage's first cycle they are 0 by rule), so we rate in cycle 2.
    return Controller([Warmup(), *agents], ["w", "s"], Weights(0.5, 0.5), max_cycles=3)


class Warmup(Agent):
    def __init__(self) -> None:
        super().__init__("warmup", ["w", "s"], default=0.0)

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        if ctx.stage == "w":
            return ActionResult(Outcome.STAGE_COMPLETE, "to s")
        return ActionResult(Outcome.PROGRESS, "tick")


def test_table1_totals_by_weights():
    weights = Weights(0.5, 0.5)
    for _name, d, o, expected in TABLE_1:
        assert weights.total(d, o) == pytest.approx(expected, abs=1e-12)


def test_table1_through_the_controller_agent2_wins():
    result = table1_controller().run()
    record = result.trace[2]  # w:warmup, s:cycle0 (opportunistic 0), s:cycle1 rates Table 1
    assert record.stage == "s" and record.stage_cycle == 1
    totals = {r.name: r.total for r in record.ratings}
    for name, d, o, expected in TABLE_1:
        row = record.rating_of(name)
        assert (row.default, row.opportunistic) == (d, o)
        assert totals[name] == pytest.approx(expected, abs=1e-12)
    assert record.chosen == "Agent2"


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"default": 1.2, "opportunistic": -0.2}, "weights.default"),
        ({"default": -0.1, "opportunistic": 1.1}, "weights.default"),
        ({"default": 0.5, "opportunistic": 0.6}, "weights"),
        ({"default": math.nan, "opportunistic": 0.5}, "weights.default"),
        ({"default": 0.5, "opportunistic": 0.5, "learned": 0.1}, "weights"),
        ({"default": "0.5", "opportunistic": 0.5}, "weights.default"),
    ],
)
def test_bad_weights_are_rejected_naming_the_field(kwargs, field):
    with pytest.raises(ValidationError) as info:
        Weights(**kwargs)
    assert info.value.field == field
    assert field in str(info.value)


def test_weights_are_not_clipped():
    with pytest.raises(ValidationError, match="must be in"):
        Weights(1.0000001, 0.0)


@pytest.mark.parametrize("value", [-0.01, 1.01, math.nan, math.inf])
def test_bad_default_subrating_is_rejected(value):
    with pytest.raises(ValidationError) as info:
        Fixed("a", value, 0.0)
    assert info.value.field == "agents.a.default"


def test_bad_opportunistic_subrating_ends_run_with_error_naming_it():
    agents = [Warmup(), Fixed("bad", 0.5, 1.5)]
    result = Controller(agents, ["w", "s"], max_cycles=5).run()
    assert result.status.value == "error"
    assert "agents.bad.opportunistic" in result.reason


def test_weights_from_dict_validates():
    assert Weights.from_dict({"default": 0.3, "opportunistic": 0.7}) == Weights(0.3, 0.7, 0.0)
    with pytest.raises(ValidationError) as info:
        Weights.from_dict({"default": 0.3})
    assert info.value.field == "weights.opportunistic"
    with pytest.raises(ValidationError) as info:
        Weights.from_dict({"default": 0.3, "opportunistic": 0.7, "bogus": 0})
    assert info.value.field == "weights.bogus"


@given(
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
)
def test_total_is_a_probability(wd_raw, wo_raw, wl_raw, d, o, lr):
    s = wd_raw + wo_raw + wl_raw
    if s == 0:
        return
    wd, wo = wd_raw / s, wo_raw / s
    wl = 1.0 - wd - wo
    if wl < 0:
        wl = 0.0
    try:
        weights = Weights(wd, wo, wl)
    except ValidationError:
        return  # rounding pushed the sum off 1 by more than the tolerance
    total = weights.total(d, o, lr)
    assert -1e-12 <= total <= 1 + 1e-9
