"""Grasp validation in Drake: real simulations of planned grasps (hand3x3, point contact, SAP)."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.planner import default_hand
from eos_svc.cli import main
from eos_svc.errors import EosError, ValidationError
from eos_svc.kinematics.hand import HAND3X3_URDF, HandDescription
from eos_svc.validation import DIRECTIONS, grasp_setup, validate_grasp
from eos_svc.validation.simulation import GraspSimulation


@pytest.fixture(scope="module")
def good_plan():
    """The default plan: a 3 cm sphere the end agent judges a good grasp."""
    result = plan(PlanRequest(seed=1))
    assert result.status == "success" and result.good_grasp
    return result


def shifted(result, dx: float) -> dict:
    """The result's JSON form with the real object moved ``dx`` m along the approach (+x):
    the fingertips, where the plan left them, now touch the hand-facing hemisphere."""
    data = copy.deepcopy(result.to_dict())
    data["ground_truth"]["position"][0] += dx
    return data


def eos(capsys, *args: str) -> tuple[int, str, str]:
    """Run ``eos ARGS`` in this process: (exit status, stdout, stderr)."""
    try:
        code = main(list(args))
    except SystemExit as exc:
        code = int(exc.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_plan_validate_holds_the_good_sphere_grasp_in_all_six_directions(good_plan, capsys):
    """``eos plan --validate --json``: the default plan (the fixture's) with its Drake verdict."""
    code, out, err = eos(capsys, "plan", "--quiet", "--validate", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["q_final"] == list(good_plan.q_final)  # the same plan as the fixture
    check = data["validation"]
    assert check["held"] is True, check["reason"]
    assert check["directions"] == list(DIRECTIONS) == list(check["displacement_m"])
    assert all(d < 0.01 for d in check["displacement_m"].values())
    assert all(len(o["touching"]) >= 2 and not o["stopped_early"] for o in check["outcomes"])
    # the squeeze moves the object a little before any load, and all three fingers hold it
    assert 0.0 < check["settle_displacement_m"] < 0.01
    assert check["settle_touching"] == ["finger1", "finger2", "finger3"]
    assert check["seconds"] == 1.5 and check["mass_kg"] == 0.1 and check["friction"] == 0.5


def test_contacts_in_front_of_the_centre_drop_the_object(good_plan):
    # 15 mm forward: the fingertips sit on the hand-facing side; the squeeze pushes it out
    check = validate_grasp(shifted(good_plan, 0.015))
    assert not check.held
    assert "dropped along" in check.reason
    assert max(check.displacement_m.values()) >= 0.01


def test_friction_decides_a_load_across_the_pinch(good_plan):
    # the fingers pinch along z: a load along +x is resisted by friction alone
    grippy = validate_grasp(good_plan, directions=["+x"], seconds=0.8)
    data = good_plan.to_dict()
    data["friction"] = 0.02
    slippery = validate_grasp(data, directions=["+x"], seconds=0.8)
    assert grippy.held and not slippery.held
    assert slippery.displacement_m["+x"] > 10 * grippy.displacement_m["+x"]


def test_drake_and_pinocchio_agree_on_the_fingertips(good_plan):
    """The welded Drake hand puts every fingertip where the planner's Pinocchio model does."""
    setup = grasp_setup(good_plan, 15)
    sim = GraspSimulation(
        HAND3X3_URDF,
        HandDescription.hand3x3(),
        setup.q_final,
        setup.obj,
        friction=0.5,
    )
    state = default_hand().state(np.asarray(good_plan.q_final))
    for finger in ("finger1", "finger2", "finger3"):
        np.testing.assert_allclose(sim.body_position(f"{finger}_tip"), state.tip_position(finger), atol=1e-9)
    assert sim.effort_limit == pytest.approx(float(default_hand().model.effortLimit[-1]))


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d.update(q_final=None), "q_final"),
        (lambda d: d.update(q_final=d["q_final"][:5]), "q_final"),
        (lambda d: d["q_final"].__setitem__(3, "x"), "q_final[3]"),
        (lambda d: d.pop("ground_truth"), "ground_truth"),
        (lambda d: d["ground_truth"].update(radius=-0.01), "ground_truth.radius"),
        (lambda d: d["ground_truth"].update(shape="cone"), "ground_truth.shape"),
        (lambda d: d.update(friction=-1), "friction"),
        (lambda d: d.pop("friction"), "friction"),
    ],
)
def test_bad_results_name_the_field(good_plan, edit, field):
    data = copy.deepcopy(good_plan.to_dict())
    edit(data)
    with pytest.raises(ValidationError) as info:
        validate_grasp(data)
    assert info.value.field == field
    assert isinstance(info.value, EosError)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"directions": 7}, "directions"),
        ({"directions": ["+w"]}, "directions"),
        ({"mass": 0.0}, "mass"),
        ({"seconds": float("nan")}, "seconds"),
        ({"squeeze": 3.0}, "squeeze"),
    ],
)
def test_bad_arguments_name_the_argument(good_plan, kwargs, field):
    with pytest.raises(ValidationError) as info:
        validate_grasp(good_plan, **kwargs)
    assert info.value.field == field


def test_result_has_no_validation_unless_asked(good_plan):
    assert good_plan.validation is None
    assert good_plan.to_dict()["validation"] is None


def test_cli_validates_a_record_file(tmp_path, capsys):
    record = tmp_path / "run.jsonl"
    assert eos(capsys, "plan", "--quiet", "--record", str(record))[0] == 0
    code, out, err = eos(capsys, "validate", str(record), "--directions", "1", "--seconds", "0.5", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["validation"]["held"] is True and data["validation"]["directions"] == ["+x"]


def test_cli_exit_1_when_dropped_and_2_on_bad_files(tmp_path, good_plan, capsys):
    dropped = tmp_path / "forward.json"
    dropped.write_text(json.dumps(shifted(good_plan, 0.015)))
    code, out, err = eos(capsys, "validate", str(dropped), "--directions", "1", "--seconds", "0.5")
    assert code == 1, err
    assert "DROPPED" in out
    bad = copy.deepcopy(good_plan.to_dict())
    bad["ground_truth"]["radius"] = "big"
    cases = {
        "missing.json": (None, "FILE: cannot read"),
        "list.json": ("[1, 2]", "not a plan result object"),
        "garbage.jsonl": ("{nope", "neither a plan result"),
        "radius.json": (json.dumps(bad), "ground_truth.radius: must be a number"),
    }
    for name, (text, message) in cases.items():
        path = tmp_path / name
        if text is not None:
            path.write_text(text)
        code, out, err = eos(capsys, "validate", str(path))
        assert code == 2, (name, out, err)
        assert message in err and "Traceback" not in err
    code, _, err = eos(capsys, "plan", "--hand", "no_such_hand.toml", "--validate")
    assert code == 2 and "--hand: no_such_hand.toml: file: cannot read" in err


def test_another_hands_plan_is_validated_with_that_hand(capsys):
    # the Drake model is built from the hand's description (here the Allegro's composite URDF)
    code, out, _ = eos(capsys, "plan", "--hand", "allegro", "--validate", "--quiet")
    assert code == 0 and "validation (Drake): HELD" in out
    assert "touching index, middle, ring, thumb" in out


def test_another_hands_result_is_refused_saying_the_validation_is_for_hand3x3():
    # a real Allegro plan's JSON result: its q_final has the Allegro's joints, and the refusal
    # says why (the Drake model is hand3x3's), not only the count
    from eos_svc.agents import PlanRequest, plan
    from eos_svc.hands import load_hand_named

    data = plan(PlanRequest(), hand=load_hand_named("allegro")).to_dict()
    with pytest.raises(ValidationError) as info:
        validate_grasp(data)
    assert info.value.field == "q_final"
    assert "--hand NAME" in info.value.reason and "allegro" in info.value.reason
