"""The Drake world: the object rests on the table, a guarded finger touch reports Drake's contact,
the lift test lifts a grip, and a Drake plan succeeds only when the lift test held."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, build_world, plan
from eos_svc.drivers.drake_plant import DrakeHandPlant
from eos_svc.drivers.drake_world import DrakeDriver
from eos_svc.drivers.lift_test import GRAVITY, lift_test, squeeze_grip
from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.schema.request import ObjectSpec

REQUEST = PlanRequest(seed=1)


def drake_driver(request: PlanRequest = REQUEST) -> DrakeDriver:
    return DrakeDriver(build_world(request), request.obj, request.friction)


def test_the_object_rests_on_the_table_under_gravity() -> None:
    driver = drake_driver()
    plant = driver._plant
    plant.advance(0.5)
    assert driver.object_moved() < 2e-4  # it stays where it was put, on the table top
    table = [f for other, _, normal, f in plant.object_contacts() if other == 0]
    assert sum(table) == pytest.approx(plant.settings.mass * GRAVITY, rel=0.02)  # it carries the weight
    lowest = plant.object_pose().translation()[2] - 0.5 * make_object(REQUEST.obj).diameter
    assert abs(lowest - plant.table_top) < 5e-4  # sunk into the table's compliant layer by less than 0.5 mm


def test_a_requested_table_below_the_object_is_where_the_object_comes_to_rest() -> None:
    """The request's table (its top 20 mm under the ball) is the Drake world's: the ball falls
    onto it and the planner's support height is that table's top."""
    ball = REQUEST.obj
    top = ball.position[2] - ball.size["radius"] - 0.02
    request = PlanRequest.from_dict({**REQUEST.to_dict(), "table": {"height": top}})
    driver = drake_driver(request)
    plant = driver._plant
    assert plant.table_top == pytest.approx(top)
    assert driver.support_height == pytest.approx(top)
    lowest = plant.object_pose().translation()[2] - ball.size["radius"]
    assert abs(lowest - top) < 5e-4  # it fell 20 mm and rests on the requested table


def test_a_guarded_finger_touch_reports_a_surface_point_and_a_positive_force() -> None:
    kinematic = plan(REQUEST)  # a grip the fingers reach from 0.3 rad more open
    driver = drake_driver()
    q = np.array(kinematic.q_final)
    hand = driver.hand
    for finger in hand.finger_names:
        q[hand.finger_q_index(finger)] -= 0.3
    driver.move_joints(q)
    finger = hand.opposing_finger
    for _ in range(40):
        step = driver.close_finger_step(finger, 0.02)
        if step.event != "moved":
            break
    assert step.event == "touched" and step.touch is not None
    touch = step.touch
    assert touch.force > 0.0
    centre = driver._plant.object_pose().translation()
    radius = REQUEST.obj.size["radius"]
    assert abs(np.linalg.norm(touch.point - centre) - radius) < 1e-3  # on the sphere's surface
    assert float(np.dot(touch.normal, (touch.point - centre) / radius)) > 0.99  # outward


def test_the_lift_test_lifts_a_kinematic_grip_ten_centimetres_and_it_holds_under_the_weight() -> None:
    result = plan(REQUEST)
    hand = build_world(REQUEST).hand
    obj = make_object(REQUEST.obj)
    plant = DrakeHandPlant(hand, REQUEST.obj, obj, REQUEST.friction)
    plant.set_hand_q(np.array(result.q_final))
    plant.simulator.Initialize()
    target = squeeze_grip(plant, hand)
    lift = lift_test(plant, hand, hand.wrist_q_index[:3], 0.5 * obj.diameter, target)
    assert lift["rise_m"] > 0.09  # the object went up with the hand
    assert lift["lift_drift_m"] < 0.01
    forces = {k: v for k, v in lift["load_displacement_m"].items() if not k.startswith("torque")}
    assert len(forces) == 6 and max(forces.values()) < 0.01


def test_an_unknown_world_is_refused_naming_the_field() -> None:
    with pytest.raises(ValidationError) as err:
        plan(REQUEST, world="mujoco")
    assert err.value.field == "world"


@pytest.mark.slow
def test_a_drake_plan_succeeds_only_when_the_lift_test_held() -> None:
    result = plan(PlanRequest(seed=1, deadline_s=600), world="drake")
    assert result.world is not None and result.world["name"] == "drake"
    lift = result.world["lift"]
    assert (result.status == "success") == bool(lift is not None and lift["held"])
    assert result.world["simulated_s"] > 0 and result.world["object_moved_mm"] >= 0.0
    assert result.world["moved_past_relocation_limit"] == (result.world["object_moved_mm"] > 2.0)
    said = "while the hand explored it" in result.reason  # the planner says so
    assert said == result.world["moved_past_relocation_limit"]


def test_the_request_carries_its_world_and_the_kinematic_form_is_unchanged() -> None:
    assert PlanRequest.from_dict({"world": "drake"}).world == "drake"
    assert "world" not in PlanRequest().to_dict()  # the kinematic world's JSON form as before
    assert PlanRequest(world="drake").to_dict()["world"] == "drake"
    with pytest.raises(ValidationError) as err:
        PlanRequest.from_dict({"world": "mujoco"})
    assert err.value.field == "world"


def test_a_drake_plan_records_the_object_pose_and_the_view_moves_the_object() -> None:
    from pydrake.geometry import MeshcatAnimation

    from eos_svc.schema import keys
    from eos_svc.view.replay_html import _animate_object, plan_scene

    request = PlanRequest(seed=1, max_cycles=3, world="drake", deadline_s=600)
    result = plan(request)
    records = [r.to_dict() for r in result.trace]
    poses = [c["new"] for r in records for c in r["changes"] if c["key"] == keys.OBJECT_POSE]
    assert poses and all(len(p) == 7 for p in poses)
    assert abs(poses[-1][2] - request.obj.position[2]) < 1e-3  # still resting on the table
    scene = plan_scene(request, records, result.to_dict())
    assert scene.timeline.frames > 0
    assert _animate_object(MeshcatAnimation(scene.timeline.fps), scene.timeline, records) == len(poses)
    kinematic = plan(PlanRequest(seed=1, max_cycles=3))
    assert not any(c.key == keys.OBJECT_POSE for r in kinematic.trace for c in r.changes)


def test_a_drake_plan_replays_cycle_for_cycle(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from eos_svc.cli import main

    record = tmp_path / "drake.jsonl"
    base = ["plan", "--world", "drake", "--max-cycles", "7", "--quiet", "--record", str(record)]
    assert main(base) == 1  # 7 cycles cannot grasp: a cycle limit, exit 1
    assert main(["replay", "--quiet", str(record)]) == 0  # deterministic: the same cycles and result


def test_a_rolling_ball_stops_as_the_tables_rolling_resistance_says() -> None:
    """Rolling at v = 2 cm/s, the ball decelerates at a = c N h r / (7/5 m r²) (h = r: its
    centre's height) and stops after about v² / 2a; without the coefficient only the soft
    table's own damping slows it, and it goes farther."""
    from pydrake.multibody.math import SpatialVelocity

    from eos_svc.drivers.drake_plant import PlantSettings

    hand, obj, r = build_world(REQUEST).hand, make_object(REQUEST.obj), REQUEST.obj.size["radius"]
    travelled = {}
    for c in (0.01, 0.0):
        plant = DrakeHandPlant(hand, REQUEST.obj, obj, REQUEST.friction, PlantSettings(rolling_resistance=c))
        plant.set_hand_q(build_world(REQUEST).state.q)
        plant.simulator.Initialize()
        plant.advance(0.2)
        start = np.array(plant.object_pose().translation())
        v = 0.02  # along +y: rolling about -x
        twist = SpatialVelocity(np.array([-v / r, 0.0, 0.0]), np.array([0.0, v, 0.0]))
        plant.plant.SetFreeBodySpatialVelocity(plant.context, plant.body, twist)
        plant.advance(1.0)
        travelled[c] = float(np.linalg.norm(np.array(plant.object_pose().translation()) - start))
        if c > 0.0:  # about at rest (below 0.05 rad/s the resistance is viscous: a slow tail)
            speed = plant.plant.EvalBodySpatialVelocityInWorld(plant.context, plant.body).translational()
            assert float(np.linalg.norm(speed)) < 5e-4
    mass = plant.settings.mass
    a = 0.01 * mass * GRAVITY * r * r / (1.4 * mass * r * r)
    assert travelled[0.01] == pytest.approx(v * v / (2 * a), rel=0.3)  # about 2.9 mm, then at rest
    assert travelled[0.0] > travelled[0.01]


def test_a_light_touch_leaves_a_resting_box_where_it_was() -> None:
    from eos_svc.schema.request import ObjectSpec

    request = PlanRequest(obj=ObjectSpec("box", {"size": (0.05, 0.05, 0.05)}, (0.21, 0.02, -0.015)), seed=1)
    driver = drake_driver(request)
    finger = driver.probe_finger("front")
    start = np.array([0.21 - 0.025 - 0.02, 0.02, -0.015])
    for _ in range(3):
        outcome = driver.guarded_probe(
            finger, start, np.array([1.0, 0.0, 0.0]), 0.09, driver.probe.angles[finger]
        )
        assert outcome.event == "touched"
    assert driver.object_moved() < 1e-4  # three touches at 0.05 N: less than 0.1 mm


def test_only_a_world_whose_object_can_move_checks_where_it_is() -> None:
    """The relocate agent joins the Drake world's team, never the kinematic world's (whose plans
    stay those of the paper's experiments)."""
    from eos_svc.agents import build_agents

    assert "relocate" not in [a.name for a in build_agents(build_world(REQUEST))]
    assert "relocate" in [a.name for a in build_agents(drake_driver())]


@pytest.mark.slow
@pytest.mark.parametrize("push", [(0.012, 0.0, 0.0), (0.0, -0.012, 0.0)], ids=["along +x", "sideways -y"])
def test_an_object_pushed_during_the_exploration_is_relocated_and_grasped_where_it_went(
    monkeypatch: pytest.MonkeyPatch, push: tuple[float, float, float]
) -> None:
    """When the exploration is over, just before the first check, the ball is pushed 12 mm
    along +x, away from the hand, or sideways along −y (an outside push the planner is not told
    of; a push along +y put the ball, moved by teleport, into a finger where the last probe left
    the hand): the check touches find it off (sideways: the side check touch; the front and top
    ones, 12 mm beside the ball's middle, land within 2 mm of where they would on the postulated
    ball), the refit re-locates it, and the grasp planned on the re-located ball is about its
    true new place (within 2 mm) and lifts it."""
    from eos_svc.agents.relocate import RelocateAgent

    request = PlanRequest(seed=1, deadline_s=3600, world="drake")  # a loaded machine simulates slowly
    driver = drake_driver(request)
    pushed: list[list[float]] = []
    at_grasp: list[list[float]] = []
    check = RelocateAgent.act

    def pushed_then_checked(self: RelocateAgent, board: object, ctx: object) -> object:
        if not pushed:
            driver.displace_object(np.array(push))
            pushed.append(driver.object_pose()[:3])
        return check(self, board, ctx)  # type: ignore[arg-type]

    monkeypatch.setattr(RelocateAgent, "act", pushed_then_checked)

    def watch(record: object) -> None:
        if getattr(record, "chosen", None) == "grasp_points" and not at_grasp:
            at_grasp.append(driver.object_pose()[:3])

    result = plan(request, driver=driver, on_cycle=watch)
    assert pushed and at_grasp
    details = " ".join(c.detail for c in result.trace if c.chosen == "relocate")
    assert "re-located" in details  # the check noticed the push
    assert result.shape is not None and result.shape["located"]["moved"] is False  # the last check agreed
    # the surface the grasp was planned on (a primitive or the touches' hull) lies on the ball where
    # Drake has it when the grasp is chosen: its points, nearest to 26 far points around it
    planned = make_object(ObjectSpec.from_dict(result.shape["object"]))
    ball = make_object(ObjectSpec("sphere", dict(request.obj.size), tuple(at_grasp[0])))
    around = [np.array(u, dtype=float) for u in np.ndindex(3, 3, 3) if u != (1, 1, 1)]
    surface = np.array([planned.closest_surface_point(ball.centre + 0.2 * (u - 1.0)) for u in around])
    off = np.abs(ball.signed_distances(surface)[0])
    assert np.median(off) < 0.002 and np.max(off) < 0.006  # a hull of touches made as the ball crept
    assert result.status == "success" and result.world is not None and result.world["lift"]["held"]


def test_the_search_locates_a_box_that_toppled_off_its_requested_pose() -> None:
    """Draw 1:10, a box put on an edge: in Drake it topples 13 mm off the requested pose before
    the plan starts. Each sweep's legs run one by one in Drake (as one straight motion a sweep
    cut through the box, the guard stopped the hand inside it and every later sweep was
    blocked), so the search finds it where it lies."""
    from eos_svc.experiments.grasp_suite import random_draw

    drawn = random_draw(20, 1)[10]
    request = PlanRequest(obj=drawn.spec, seed=drawn.seed or 1, world="drake")
    driver = drake_driver(request)
    assert np.linalg.norm(driver._start - np.asarray(drawn.spec.position)) > 0.005  # it toppled
    for _ in range(30):
        driver.search_step()
        if driver.located():
            break
    assert driver.located()
    assert driver.object_moved() < 0.002  # found without pushing it away
