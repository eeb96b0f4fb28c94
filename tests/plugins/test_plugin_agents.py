"""Plug-in agents: plan(..., agents=[...]), names (entry points, module:attr), the contract."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import ClassVar

import pytest

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome
from eos_svc.agents.base import INFO
from eos_svc.agents.planner import plan
from eos_svc.agents.plugins import loading
from eos_svc.agents.plugins.sampled_grasp_points import SampledGraspPointsAgent
from eos_svc.board import Board
from eos_svc.errors import ValidationError
from eos_svc.records import RunStatus
from eos_svc.schema.board_entries import Entry
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world.world import GraspWorld

#: an ellipsoid on which sampling every orientation finds a better grasp than the stock rule
TILTED = ObjectSpec("ellipsoid", {"radii": (0.04, 0.02, 0.03)}, (0.21, 0.02, -0.015), (0.3, 0.2, 0.5))
#: a box on which six sampled closing axes alone find worse grasps than GraspIt's faces
BOX = ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.21, 0.02, -0.015))


def grasp_choice(result) -> tuple[str, dict]:
    """Which agent chose the grasp, and the record of that cycle."""
    for record in result.trace:
        if record.chosen is not None and "grasp_points" in record.chosen:
            return record.chosen, record
    raise AssertionError("no grasp agent acted")


def test_plugin_chosen_when_its_grasp_is_better() -> None:
    request = PlanRequest(obj=TILTED, seed=1)
    base = plan(request)
    with_plugin = plan(request, agents=[SampledGraspPointsAgent], check_board=True)
    chosen, record = grasp_choice(with_plugin)
    assert chosen == "sampled_grasp_points"
    plug = record.rating_of("sampled_grasp_points")
    stock = record.rating_of("grasp_points")
    assert plug.total > stock.total
    assert grasp_choice(base)[0] == "grasp_points"
    # the plan's result follows the chosen grasp: the better predicted grasp is the better grasp here
    assert with_plugin.status == base.status == "success"
    assert with_plugin.epsilon > base.epsilon


def test_plugin_passed_over_when_its_grasp_is_worse() -> None:
    request = PlanRequest(obj=BOX, seed=1)
    weak = functools.partial(SampledGraspPointsAgent, samples=6, primitive_frames=False)
    base = plan(request)
    with_plugin = plan(request, agents=[weak])
    chosen, record = grasp_choice(with_plugin)
    assert chosen == "grasp_points"
    assert record.rating_of("sampled_grasp_points").opportunistic == 0.0
    # passed over: the plan is the plan without it
    assert with_plugin.epsilon == base.epsilon
    assert with_plugin.cycles == base.cycles
    assert [r.chosen for r in with_plugin.trace] == [r.chosen for r in base.trace]


def test_plugins_join_before_end_and_the_default_plan_is_unchanged() -> None:
    request = PlanRequest(seed=2)
    base = plan(request)
    result = plan(request, agents=[SampledGraspPointsAgent, Tally])
    names = [row.name for row in grasp_choice(result)[1].ratings]
    assert names[-3:] == ["grasp_points", "sampled_grasp_points", "tally"]  # in order, after the built-ins
    assert result.trace[-1].ratings[-1].name == "end"
    assert plan(request).epsilon == base.epsilon  # plug-ins are per plan: nothing left behind


class Tally(Agent):
    """A plug-in with a board entry of its own, written once at the information stage's start
    (a plain core agent: no world needed)."""

    reads: ClassVar[frozenset[str]] = frozenset({"tally"})
    writes: ClassVar[frozenset[str]] = frozenset({"tally"})
    board_entries: ClassVar[dict[str, Entry]] = {"tally": Entry(int, "cycles the tally counted")}
    value: object = 1

    def __init__(self, world: GraspWorld) -> None:
        super().__init__("tally", (INFO,), 0.1)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 1.0 if "tally" not in board else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        board.set("tally", self.value)
        return ActionResult(Outcome.PROGRESS, "counted")


class BadTally(Tally):
    value = "one"


class Snoop(Tally):
    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        board.get("shape")  # not declared in reads
        return super().act(board, ctx)


def test_own_entries_are_checked_in_check_board_mode() -> None:
    good = plan(PlanRequest(seed=1), agents=[Tally], check_board=True)
    assert good.status == "success"
    assert "tally" in good.agents_run()
    bad = plan(PlanRequest(seed=1), agents=[BadTally], check_board=True)
    assert bad.status == RunStatus.ERROR.value
    assert "board.tally" in bad.reason and "tally" in bad.reason
    unchecked = plan(PlanRequest(seed=1), agents=[BadTally])  # checks are the debug mode's
    assert unchecked.status == "success"
    snoop = plan(PlanRequest(seed=1), agents=[Snoop], check_board=True)
    assert snoop.status == RunStatus.ERROR.value
    assert "'shape'" in snoop.reason and "'tally'" in snoop.reason


def test_names_resolve_through_module_attr_and_entry_points(tmp_path: Path, monkeypatch) -> None:
    by_path = plan(
        PlanRequest(obj=TILTED, seed=1),
        agents=["eos_svc.agents.plugins.sampled_grasp_points:SampledGraspPointsAgent"],
    )
    assert grasp_choice(by_path)[0] == "sampled_grasp_points"
    # an installed package: a distribution's metadata with an entry point in the group
    dist = tmp_path / "other_planner-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: other-planner\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[eos_svc.agents]\nsampled = eos_svc.agents.plugins.sampled_grasp_points:SampledGraspPointsAgent\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "sampled" in loading.available()
    by_entry_point = plan(PlanRequest(obj=TILTED, seed=1, agents=("sampled",)))
    assert grasp_choice(by_entry_point)[0] == "sampled_grasp_points"
    assert by_entry_point.request["agents"] == ["sampled"]
    assert by_entry_point.epsilon == by_path.epsilon


class NotAnAgent:
    def __init__(self, world: GraspWorld) -> None:
        self.name = "x"


class Imposter(Tally):
    def __init__(self, world: GraspWorld) -> None:
        Agent.__init__(self, "grasp_points", (INFO,), 0.1)


class Elsewhere(Tally):
    def __init__(self, world: GraspWorld) -> None:
        Agent.__init__(self, "elsewhere", ("packing",), 0.1)


class Undeclared(Tally):
    board_entries: ClassVar[dict[str, Entry]] = {}


class Redeclares(Tally):
    board_entries: ClassVar[dict[str, Entry]] = {"shape": Entry(dict, "mine")}


@pytest.mark.parametrize(
    ("plugin", "field", "words"),
    [
        ("no_such_plugin", "agents[0]", "no plug-in named 'no_such_plugin'"),
        ("eos_svc.nowhere:Agent", "agents[0]", "cannot import module"),
        ("eos_svc.agents.planner:NoSuch", "agents[0]", "has no attribute"),
        (NotAnAgent, "agents[0]", "must make an eos_svc.Agent"),
        (Imposter, "agents[0].name", "already taken"),
        (Elsewhere, "agents[0].stages", "unknown stage"),
        (Undeclared, "agents[0].reads", "no one declares a type"),
        (Redeclares, "agents[0].board_entries", "redeclares"),
        (42, "agents[0]", "must be a name, a factory or an Agent"),
    ],
)
def test_contract_breaches_are_refused_before_the_first_cycle(plugin, field: str, words: str) -> None:
    with pytest.raises(ValidationError) as err:
        plan(PlanRequest(seed=1), agents=[plugin])
    assert err.value.field == field
    assert words in err.value.reason


def test_offered_plugins_only() -> None:
    offered = {"sampled": SampledGraspPointsAgent}
    result = plan(PlanRequest(obj=TILTED, seed=1, agents=("sampled",)), offered=offered)
    assert grasp_choice(result)[0] == "sampled_grasp_points"
    with pytest.raises(ValidationError) as err:
        plan(
            PlanRequest(
                seed=1, agents=("eos_svc.agents.plugins.sampled_grasp_points:SampledGraspPointsAgent",)
            ),
            offered=offered,
        )
    assert err.value.field == "agents[0]"
    assert "not offered here (offered: sampled)" in err.value.reason


@pytest.mark.parametrize(
    ("agents", "field"),
    [
        ("sampled", "agents"),
        ([""], "agents[0]"),
        (["a", "a"], "agents[1]"),
        ([1], "agents[0]"),
        (["x"] * 17, "agents"),
    ],
)
def test_request_names_are_validated(agents: object, field: str) -> None:
    with pytest.raises(ValidationError) as err:
        PlanRequest.from_dict({"agents": agents})
    assert err.value.field == field


def test_request_round_trips_its_plugin_names() -> None:
    request = PlanRequest.from_dict({"agents": ["sampled"], "seed": 4})
    assert request.agents == ("sampled",)
    assert PlanRequest.from_dict(request.to_dict()) == request
    assert "agents" not in PlanRequest().to_dict()  # old readers see the same JSON


def test_sampled_agent_checks_its_settings() -> None:
    from eos_svc.agents.planner import build_world

    world = build_world(PlanRequest())
    with pytest.raises(ValidationError) as err:
        SampledGraspPointsAgent(world, samples=0)
    assert err.value.field == "agents.sampled_grasp_points.samples"


def test_the_plugins_experiment_on_two_objects(tmp_path: Path) -> None:
    from eos_svc.experiments import plugins as experiment

    rows = []
    for spec in (TILTED, BOX):
        request = PlanRequest(obj=spec, seed=1)
        base = plan(request)
        rows += [experiment.one("x", request, base, config) for config in experiment.CONFIGS]
    for config in experiment.CONFIGS:
        summary = experiment.summarize([r for r in rows if r["config"] == config])
        assert summary["choice_follows_comparison"] == summary["compared"] == 2
        assert summary["passed_over_same_eps"] == summary["passed_over"]
    tilted = next(
        r
        for r in rows
        if r["config"] == "sampled+primitive" and r["predicted_eps_plugin"] and r["plugin_better"]
    )
    assert tilted["chosen"] == "sampled_grasp_points" and tilted["eps"] > tilted["eps_without"]
    assert experiment.plot(rows, tmp_path / "p.png").stat().st_size > 0
