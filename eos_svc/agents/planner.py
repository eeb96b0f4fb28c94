"""The grasp planner: the paper's eight agents (and ep2) under the EOS controller, from one call.

    from eos_svc.agents import PlanRequest, plan
    result = plan(PlanRequest(seed=3), on_cycle=print)

The agents and their default sub-ratings: :data:`DEFAULT_RATINGS` (the table in
docs/planner.md). Another hand brings one finger agent per finger (:func:`finger_ratings`) and
its own :class:`~eos_svc.world.hand_context.HandContext`. The same request with the same seed
gives the same cycles and result.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from eos_svc.agent import Agent
from eos_svc.agents.base import STAGES
from eos_svc.agents.end import EndAgent
from eos_svc.agents.ep1 import EP1Agent
from eos_svc.agents.ep2 import EP2Agent
from eos_svc.agents.finger import FingerAgent, TargetLandings
from eos_svc.agents.grasp_points import GraspPointsAgent
from eos_svc.agents.memory import GraspMemory
from eos_svc.agents.plugins.loading import PluginSpec, plugin_agents, plugin_entries, requested_plugins
from eos_svc.agents.post_shape import PostShapeAgent
from eos_svc.agents.recall import RecallAgent
from eos_svc.agents.relocate import RelocateAgent
from eos_svc.agents.wrist import WristAgent
from eos_svc.board import Board
from eos_svc.controller import CancelToken, Controller
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.drivers.protocol import HandDriver
from eos_svc.drivers.worlds import check_world, make_driver
from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.hands import DEFAULT_HAND, load_hand_named
from eos_svc.kinematics import HandModel, Scene, TactileSensor
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.records import CycleRecord
from eos_svc.schema import keys
from eos_svc.schema.board_entries import check_entry
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.schema.result import PlanResult
from eos_svc.world.admission import check_plannable
from eos_svc.world.hand_context import HandContext, context_for, default_context
from eos_svc.world.joint_sensing import JointSensing
from eos_svc.world.parameters import WorldParameters
from eos_svc.world.pose_board import PoseBoard
from eos_svc.world.world import GraspWorld

CycleCallback = Callable[[CycleRecord], None]

#: default sub-ratings P(A|B_d), fixed at creation (the table in docs/planner.md); a hand with
#: other finger names rates its fingers by position (:func:`finger_ratings`)
DEFAULT_RATINGS: dict[str, float] = {
    "finger1": 0.8,
    "finger2": 0.7,
    "finger3": 0.6,
    "wrist": 0.9,
    "ep1": 0.9,
    "ep2": 0.8,
    "post_shape": 0.7,
    "grasp_points": 0.6,
    "end": 0.2,
}
#: relocate's default sub-rating (it joins only a world whose object can move: ahead of grasp_points)
RELOCATE_RATING = 0.65


#: default sub-ratings of the finger agents by their position in the hand's finger list;
#: fingers beyond these get 0.1 less each, never below FINGER_RATING_FLOOR
FINGER_RATINGS: tuple[float, ...] = (0.8, 0.7, 0.6)
#: lowest default sub-rating of a finger agent (above end's 0.2: end comes last)
FINGER_RATING_FLOOR = 0.3


def finger_ratings(finger_names: tuple[str, ...] | list[str]) -> dict[str, float]:
    """Default sub-ratings of the finger agents: 0.8, 0.7, 0.6 in the hand's finger order
    (finger1, finger2, finger3 for hand3x3), then 0.1 less per extra finger (floor 0.3)."""
    out = {}
    for i, name in enumerate(finger_names):
        rating = FINGER_RATINGS[i] if i < len(FINGER_RATINGS) else FINGER_RATINGS[-1] - 0.1 * (i - 2)
        out[name] = round(max(FINGER_RATING_FLOOR, rating), 6)
    return out


def default_hand() -> HandModel:
    """The hand3x3 model (``urdf/hand3x3.urdf``): the default context's hand."""
    return default_context().hand


def build_world(
    request: PlanRequest,
    hand: HandModel | None = None,
    params: WorldParameters | None = None,
    *,
    check: bool = True,
    context: HandContext | None = None,
) -> GraspWorld:
    """The world of one plan: hand at its start pose, the object, seeded randomness.

    ``hand`` and ``params`` (default: hand3x3, its own) are ignored when ``context`` is given;
    ``check`` runs :func:`~eos_svc.world.admission.check_plannable` first (its ValidationError).
    """
    context = context if context is not None else context_for(hand, params)
    if check:
        check_plannable(request, context=context)
    hand = context.hand
    # SeedSequence(seed).spawn(3)'s children: the search, the tactile sensor, the joint sensing
    search_seed, sensor_seed, sensing_seed = (
        np.random.SeedSequence(request.seed, spawn_key=(k,)) for k in range(3)
    )
    return GraspWorld(
        context=context,
        scene=Scene(hand, make_object(request.obj)),
        state=hand.state(hand.neutral()),
        sensor=TactileSensor(noise_std=request.tactile_noise, rng=sensor_seed),
        rng=np.random.default_rng(search_seed),
        estimator=CurvatureEstimator(),
        sensing=JointSensing.build(hand, request.encoder_noise, request.link_error, sensing_seed),
        table_height=None if request.table is None else request.table.height,
    )


def build_agents(
    world: HandDriver | GraspWorld,
    ratings: dict[str, float] | None = None,
    solver: str = "osqp",
    memory: GraspMemory | None = None,
    oracle: ObjectSpec | None = None,
) -> list[Agent]:
    """The paper's eight agents (a finger agent per finger) and ep2 in list order, ``recall`` before
    ``end`` with a memory; they get the hand driver only (a :class:`GraspWorld` is wrapped).
    ``oracle``: the object grasp_points plans on instead of the postulate (measurement only)."""
    if isinstance(world, GraspWorld):
        world = KinematicDriver(world)
    fingers = world.hand.finger_names
    landings = TargetLandings(world)  # the fingers' landings at the wrist's pose, shared
    r = {**finger_ratings(fingers), **DEFAULT_RATINGS, **(ratings or {})}
    recall: list[Agent] = [] if memory is None else [RecallAgent(world, memory)]
    # where a touch may push the object, a check of where it is before the grasp (agents.relocate)
    relocate: list[Agent] = (
        [] if world.object_fixed else [RelocateAgent(r.get("relocate", RELOCATE_RATING), world)]
    )
    return [
        *(FingerAgent(finger, r[finger], world, landings) for finger in fingers),
        WristAgent(r["wrist"], world),
        EP1Agent(r["ep1"], world, solver=solver),
        EP2Agent(r["ep2"], world),
        PostShapeAgent(r["post_shape"], world),
        *relocate,
        GraspPointsAgent(r["grasp_points"], world, oracle=oracle),
        *recall,
        EndAgent(r["end"], world),
    ]


def plan(
    request: PlanRequest | None = None,
    *,
    on_cycle: CycleCallback | None = None,
    cancel: CancelToken | None = None,
    hand: HandModel | None = None,
    params: WorldParameters | None = None,
    context: HandContext | None = None,
    keep_trace: bool = True,
    memory: GraspMemory | None = None,
    oracle_postulate: bool = False,
    check: bool = True,
    check_board: bool = False,
    world: str | None = None,
    driver: HandDriver | None = None,
    agents: Sequence[PluginSpec] = (),
    offered: Mapping[str, PluginSpec] | None = None,
) -> PlanResult:
    """Plan one grasp: search, information, grasping, under the EOS controller.

    Args:
        request: what to grasp and how (default: :class:`PlanRequest` defaults).
        on_cycle, cancel, keep_trace: a callback of every cycle record, a token another thread
            may set to stop the plan, keep every cycle record in the result.
        hand, params: the hand model (default: the one ``request.hand`` names, else hand3x3) and
            the world's constants (default: the hand's own).
        context: the hand's :class:`~eos_svc.world.hand_context.HandContext`, built once by a
            caller planning many times with its own hand (``hand`` is then ignored).
        memory: a grasp memory: adds the ``recall`` agent and records how the grasp went.
        oracle_postulate: grasp_points plans on the true object (measurement only).
        check: run :func:`~eos_svc.world.admission.check_plannable` first.
        check_board: debug mode: every agent reads and writes only the entries it declares,
            every value written checked against its type (:mod:`eos_svc.schema.board_entries`).
        world: ``"kinematic"`` or ``"drake"`` (:mod:`eos_svc.drivers.worlds`; default: the
            request's).
        driver: a hand driver of the caller's instead of a world built here.
        agents: plug-in agents added after the request's own, just before ``end``
            (:mod:`eos_svc.agents.plugins.loading`).
        offered: the plug-ins the request's names may pick; ``None``: any installed one.

    Raises:
        ValidationError: a plug-in that cannot be resolved (naming ``agents[i]``), or a request
            admission refuses. Every planning outcome is a status in the result.
    """
    t0 = time.perf_counter()
    request = request if request is not None else PlanRequest()
    if context is None and hand is None and request.hand not in (None, DEFAULT_HAND):
        hand = load_hand_named(request.hand)  # the registered hand the request names
    context = context if context is not None else context_for(hand, params)
    world = check_world(request.world if world is None else world)
    model = build_world(request, check=check, context=context)
    if driver is None:  # all the agents get: the world stays the planner's
        driver = make_driver(world, model, request)
    team = build_agents(driver, memory=memory, oracle=request.obj if oracle_postulate else None)
    wanted = [*requested_plugins(request.agents, offered), *agents]
    extra = plugin_agents(driver, wanted, team, STAGES) if wanted else []
    team[-1:-1] = extra  # plug-ins join just before end (ties go to the built-in agents)
    entry_check = None
    if check_board:  # the entries the planner writes before the first cycle (board_entries.OUTSIDE_WRITERS)
        check_entry(keys.FRICTION, request.friction)
        own = plugin_entries(extra)
        entry_check = functools.partial(check_entry, extra=own) if own else check_entry
    controller = Controller(
        team,
        STAGES,
        request.weights,
        max_cycles=request.max_cycles,
        deadline_s=request.deadline_s,
        keep_trace=keep_trace,
        callbacks=[on_cycle] if on_cycle is not None else [],
        check_access=check_board,
        entry_check=entry_check,
    )
    # records the hand's q per cycle (and in the Drake world the object's pose, for viewers)
    board = PoseBoard(driver, {keys.FRICTION: request.friction}, getattr(driver, "object_pose", None))
    run = controller.run(board, cancel=cancel)
    verdict = board.get(keys.OUTCOME)
    judged = verdict is not None  # the end agent's verdict is the one authority on "good"
    if verdict is None:  # nobody judged: report the final contacts and their quality only
        verdict = driver.judge_grip(request.friction)
    good = judged and bool(verdict["good"])
    if memory is not None:
        remember(memory, driver, board, run.cycles_per_stage.get("grasping", 0), good)
    report = getattr(driver, "report", lambda: None)()
    if report is not None and report.get("moved_past_relocation_limit"):  # the planner says so
        run = dataclasses.replace(run, reason=f"{run.reason} ({moved_words(report, board.get(keys.SHAPE))})")
    obj = model.obj
    truth: dict = {"shape": request.obj.shape, **request.obj.to_dict(), "diameter": obj.diameter}
    truth["d_over_h"] = obj.diameter / model.hand.hand_height
    if request.obj.shape == "sphere":
        truth["radius"] = request.obj.size["radius"]
    return PlanResult.from_run(
        run,
        request=request,
        shape=board.get(keys.SHAPE),
        curvature=board.get(keys.CURVATURE),
        ground_truth=truth,
        contacts=verdict["contacts"],
        good_grasp=good,
        force_closure=bool(verdict["quality"]["force_closure"]),
        epsilon=float(verdict["quality"]["epsilon"]),
        quality=verdict["quality"],
        diameter_angle_deg=verdict["diameter_angle_deg"],
        d_over_h=board.get(keys.D_OVER_H),
        ep1_runs=int(board.get(keys.EP1_RUNS, 0)),
        touches=len(board.get(keys.EP1_CONTACT, {})) + len(board.get(keys.EP2_TOUCHES, [])),
        probes=driver.probes + int(board.get(keys.EP1_RUNS, 0)),
        hand_height=model.hand.hand_height,
        q_final=tuple(float(x) for x in driver.joint_positions()),
        wall_time_s=time.perf_counter() - t0,
        world=report,
    )


def moved_words(report: dict, shape: dict | None) -> str:
    """What the plan did about an object the exploration moved more than 2 mm (the relocate
    agent's ``located`` verdict on the postulate)."""
    moved = f"the object moved {report['object_moved_mm']:.1f} mm while the hand explored it"
    located = (shape or {}).get("located")
    if located is None:
        return f"{moved}, more than the 2 mm the plan tolerates: the grasp aimed where it had been"
    relocations = int((shape or {}).get("relocations", 0))
    if located.get("verified", True):
        how = f"re-located by touch {relocations} time(s), then" if relocations else "its pose"
        return f"{moved}; {how} checked within 2 mm by touch before the grasp"
    if not relocations:
        return f"{moved}; a check found it off by more than 2 mm, with too few fresh touches to re-locate it"
    return f"{moved}; re-located before the grasp, but the last check still found it more than 2 mm off"


def remember(memory: GraspMemory, world: HandDriver, board: Board, grasp_cycles: int, success: bool) -> None:
    """Record a plan that reached grasping: one try for its key, and the grasp if it worked."""
    shape, dh = board.get(keys.SHAPE), board.get(keys.D_OVER_H)
    if shape is None or dh is None or shape.get("centre") is None or keys.TARGET not in board:
        return
    offset = tuple((world.wrist_position() - np.asarray(shape["centre"])).tolist())
    angles = {f: world.finger_angle(f) for f in world.hand.finger_names}
    memory.record(shape["class"], float(dh), success, offset, angles, grasp_cycles)


def ratio_sphere_request(
    d_over_h: float,
    seed: int,
    hand: HandModel | None = None,
    position: tuple[float, float, float] | None = None,
    **kwargs: object,
) -> PlanRequest:
    """A sphere of diameter ``d_over_h`` × hand height (at the default position unless given)."""
    hand = hand or default_hand()
    if not (d_over_h > 0.0 and math.isfinite(d_over_h)):
        raise ValidationError("d_over_h", f"must be a positive finite ratio, got {d_over_h!r}")
    radius = 0.5 * d_over_h * hand.hand_height
    spec = ObjectSpec("sphere", {"radius": radius}, position or ObjectSpec().position)
    return PlanRequest(obj=spec, seed=seed, **kwargs)  # type: ignore[arg-type]
