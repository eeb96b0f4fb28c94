"""Admission (check_plannable): real coal distances and hand kinematics against closed forms."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from eos_svc.agents.planner import default_hand, plan
from eos_svc.errors import ValidationError
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world.admission import check_plannable, hand_span
from eos_svc.world.hand_context import context_for

PARAMS = context_for().params
#: the box the grasp centre sweeps (world, m) and the envelope radius
LO = np.add(PARAMS.search_box_lo, PARAMS.grasp_centre)
HI = np.add(PARAMS.search_box_hi, PARAMS.grasp_centre)
ENVELOPE = PARAMS.envelope_radius


def refusal(spec: ObjectSpec) -> ValidationError | None:
    try:
        check_plannable(PlanRequest(obj=spec))
    except ValidationError as exc:
        return exc
    return None


def sphere(radius: float, position: tuple[float, float, float]) -> ObjectSpec:
    return ObjectSpec("sphere", {"radius": radius}, position)


# behind the swept box (-x) is the hand itself: that side is the overlap test's
@pytest.mark.parametrize(("axis", "side"), [(0, 1), (1, -1), (1, 1), (2, -1), (2, 1)])
def test_reach_boundary_is_the_envelope_around_the_swept_box(axis, side):
    r = 0.02
    for margin, refused in ((-1e-4, False), (1e-4, True)):
        p = [0.5 * (LO[i] + HI[i]) for i in range(3)]
        edge = HI[axis] if side > 0 else LO[axis]
        p[axis] = edge + side * (ENVELOPE + r + margin)
        err = refusal(sphere(r, (p[0], p[1], p[2])))
        out_of_reach = err is not None and "out of reach" in err.reason
        # just inside the reach the stricter findability rule may still refuse it (the sweep
        # lattice's columns need not pass within the envelope there), never as out of reach
        assert out_of_reach == refused, (p, err)
        if refused:
            assert err is not None and err.field == f"object.position[{axis}]"
            assert "out of reach" in err.reason


def test_reach_near_a_corner_uses_the_true_distance():
    # 4 cm out in x and in y from an edge of the box: per axis within reach, in fact 5.66 cm away
    r = 0.005
    p = (HI[0] + 0.04 + r / math.sqrt(2), HI[1] + 0.04 + r / math.sqrt(2), 0.0)
    err = refusal(sphere(r, p))
    assert err is not None and err.field.startswith("object.position")
    p_in = (HI[0] + 0.03, HI[1] + 0.03, 0.0)  # 4.24 cm - r from the edge: reachable
    assert refusal(sphere(r, p_in)) is None


def test_a_big_object_is_reachable_by_its_surface_not_its_centre():
    # a box 16 cm deep (9 cm thin: it fits between the fingertips) whose centre is 12 cm past
    # the box: its face is 4 cm away, within the envelope
    spec = ObjectSpec("box", {"size": [0.16, 0.16, 0.09]}, (HI[0] + 0.12, 0.0, 0.0))
    assert refusal(spec) is None
    far = ObjectSpec("box", {"size": [0.16, 0.16, 0.09]}, (HI[0] + 0.14, 0.0, 0.0))
    err = refusal(far)
    assert err is not None and err.field == "object.position[0]"


@pytest.mark.parametrize("position", [(0.0, 0.0, 0.0), (0.02, 0.0, 0.0), (0.13, 0.015, 0.06)])
def test_overlap_with_the_hand_at_its_start_configuration(position):
    err = refusal(sphere(0.03, position))
    assert err is not None and err.field == "object.position"
    assert "overlaps the hand" in err.reason


def test_span_covers_the_fingers_opening():
    hand = default_hand()
    span = hand_span(hand)
    # closed form from the closing sweeps: the two farthest tips when all joints open together
    sweeps = context_for(hand).sweeps
    opened = max(
        float(np.linalg.norm(sweeps[a].points[0] - sweeps[b].points[0])) - 2 * hand.tip_radius(a)
        for a in sweeps
        for b in sweeps
        if a != b
    )
    assert opened <= span < opened + 0.05


@pytest.mark.parametrize(
    ("spec", "field"),
    [
        (ObjectSpec("ellipsoid", {"radii": [0.3, 0.2, 0.25]}, (0.4, 0, 0)), "object.radii"),
        (ObjectSpec("cylinder", {"radius": 0.2, "length": 0.3}, (0.4, 0, 0)), "object.length"),
        (ObjectSpec("cylinder", {"radius": 0.15, "length": 0.9}, (0.4, 0, 0)), "object.radius"),
        (ObjectSpec("capsule", {"radius": 0.15, "length": 0.1}, (0.4, 0, 0)), "object.radius"),
        (ObjectSpec("box", {"size": [0.5, 0.3, 0.6]}, (0.5, 0, 0)), "object.size"),
    ],
)
def test_too_large_in_every_direction_names_the_size_field(spec, field):
    err = refusal(spec)
    assert err is not None and err.field == field


def test_a_long_thin_object_is_not_too_large():
    # 60 cm long but 2 cm thick: graspable across
    spec = ObjectSpec("cylinder", {"radius": 0.01, "length": 0.6}, (0.25, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert refusal(spec) is None


def test_plan_refuses_before_any_cycle():
    seen: list[object] = []
    with pytest.raises(ValidationError) as info:
        plan(PlanRequest(obj=sphere(0.03, (0.21, 0.0, 0.3))), on_cycle=seen.append)
    assert info.value.field == "object.position[2]" and seen == []


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["--position", "9", "9", "9"], "--position"),
        (["--position", "0.21", "0", "0.3"], "--position"),
        (["--position", "0", "0", "0"], "--position"),
        (["--radius", "0.2", "--position", "0.4", "0", "0"], "--radius"),
    ],
)
def test_cli_plan_exits_2_naming_the_option(args, option, tmp_path):
    record = tmp_path / "run.jsonl"
    proc = subprocess.run(
        [sys.executable, "-m", "eos_svc.cli", "plan", *args, "--record", str(record)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith(f"eos: error: {option}:"), proc.stderr
    assert "Traceback" not in proc.stderr
    assert not record.exists()  # refused before anything was written


@pytest.mark.parametrize("position", [(0.03, 0.2, 0.0), (0.0, 0.2, 0.0), (0.03, 0.15, 0.15)])
def test_positions_the_search_cannot_promise_to_find_are_refused(position):
    # reachable and clear of the hand, but at the rear of the search box where the sweeps'
    # crossings could bump into it: the search does not guarantee finding it, so admission refuses
    request = PlanRequest(obj=ObjectSpec("sphere", {"radius": 0.02}, position))
    with pytest.raises(ValidationError) as err:
        check_plannable(request)
    assert err.value.field == "object.position" and "cannot be sure to find" in err.value.reason


def test_the_findable_shortcut_agrees_with_sampling_every_sweep_line():
    from eos_svc.grasp.postulate import make_object
    from eos_svc.grasp.sweeps import forward_reach
    from eos_svc.world.coverage import findable

    hand = default_hand()
    params = context_for(hand).params
    reach = forward_reach(hand, context_for(hand).sweeps)
    rng = np.random.default_rng(5)
    shapes = [
        ("sphere", {"radius": 0.02}),
        ("box", {"size": [0.04, 0.06, 0.03]}),
        ("cylinder", {"radius": 0.02, "length": 0.08}),
    ]
    verdicts = []
    for _ in range(40):
        shape, size = shapes[int(rng.integers(len(shapes)))]
        position = tuple(rng.uniform([0.0, -0.25, -0.25], [0.5, 0.25, 0.25]).tolist())
        obj = make_object(ObjectSpec(shape, size, position, tuple(rng.uniform(-1, 1, 3).tolist())))
        verdict = findable(obj, params, reach)
        assert verdict == findable(obj, params, reach, exhaustive=True)
        verdicts.append(verdict)
    assert any(verdicts) and not all(verdicts)  # both answers were exercised


def test_an_object_above_the_grasp_centre_box_is_refused_and_a_forced_plan_gives_up():
    # centred 5 cm above the box the grasp centre sweeps: within the envelope's reach, but the
    # upper fingers bump into it on every sweep before the grasp centre comes near
    request = PlanRequest(obj=ObjectSpec("sphere", {"radius": 0.026}, (0.35, -0.03, 0.205)), seed=3)
    with pytest.raises(ValidationError) as err:
        check_plannable(request)
    assert err.value.field == "object.position" and "cannot be sure to find" in err.value.reason
    result = plan(request, check=False, keep_trace=False)  # planned anyway: a bounded search
    assert result.status == "failed" and "not located" in result.reason
    assert result.cycles_per_stage["search"] <= 2 * 36 + 1
