"""EP1 end to end on the hand: accuracy on analytic shapes, repetition, errors, the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from eos_svc.cli import main as eos_main
from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.ep1 import (
    EP1Error,
    ep1_scene,
    ground_truth_form,
    place_hand_for_ep1,
    repeat_ep1,
    run_ep1,
)
from eos_svc.kinematics.hand import KinematicsError


def _start(shape, size, finger="finger1"):
    sc = ep1_scene(shape, size, finger=finger)
    return sc, sc.hand.state(place_hand_for_ep1(sc, finger))


def _truth(sc, res):
    return np.linalg.eigvalsh(ground_truth_form(sc.object, res.contact_point, res.frame))[::-1]


def test_place_hand_touches_with_zero_gap():
    for shape, size in [("sphere", 0.02), ("plane", 1.0), ("cylinder", 0.03), ("ellipsoid", 0.05)]:
        sc, st = _start(shape, size)
        assert abs(sc.contact(st, "finger1").distance) < 1e-9


def test_place_hand_in_a_scratch_state_gives_the_same_configuration():
    """A scratch state (re-used, left anywhere) changes nothing of the placement; another hand's
    state is refused, naming the argument."""
    sc = ep1_scene("ellipsoid", 0.05)
    scratch = sc.hand.state()
    for point in (None, np.array([0.0, 0.0, 0.5]), np.array([0.02, -0.01, 0.5])):
        q = place_hand_for_ep1(sc, "finger1", point=point)
        np.testing.assert_array_equal(place_hand_for_ep1(sc, "finger1", point=point, scratch=scratch), q)
    other = ep1_scene("sphere", 0.03).hand.state()
    with pytest.raises(KinematicsError, match="scratch"):
        place_hand_for_ep1(sc, "finger1", scratch=other)


@pytest.mark.parametrize("R", [0.01, 0.08])
def test_noise_free_sphere_radius_within_half_percent(R):
    sc, st = _start("sphere", R)
    res = run_ep1(sc, st, "finger1", TactileSensor(0.0))
    e = res.estimate
    assert abs(e.mean_radius / R - 1) < 0.005
    for r in e.radii:
        assert abs(r / R - 1) < 0.005
    assert res.max_slip_speed < 1e-6 and res.max_gap < 1e-5
    assert res.steps == 800 and len(res.samples) == 8
    assert np.abs(res.q_final - place_hand_for_ep1(sc)).max() < 1e-3  # back where it started


def test_noise_free_plane_is_flat():
    sc, st = _start("plane", 1.0)
    e = run_ep1(sc, st, "finger1", TactileSensor(0.0)).estimate
    assert e.is_flat and e.radii == (math.inf, math.inf) and e.mean_radius == math.inf
    assert max(abs(k) for k in e.principal_curvatures) < 0.05


@pytest.mark.parametrize(("shape", "size"), [("cylinder", 0.02), ("ellipsoid", 0.04)])
def test_noise_free_curvatures_within_two_percent(shape, size):
    sc, st = _start(shape, size)
    res = run_ep1(sc, st, "finger1", TactileSensor(0.0))
    kt = _truth(sc, res)
    ke = np.array(res.estimate.principal_curvatures)
    assert np.max(np.abs(ke - kt)) / np.max(np.abs(kt)) < 0.02
    if shape == "cylinder":
        # the principal direction of 1/r is around the axis (world z is the axis: ⟂ to it)
        d1 = res.frame[:, :2] @ res.estimate.principal_directions[:, 0]
        assert abs(d1[2]) < 0.05


def test_other_finger_and_solver():
    sc, st = _start("sphere", 0.03, finger="finger3")
    res = run_ep1(sc, st, "finger3", TactileSensor(0.0), solver="daqp", directions=(0.0, 90.0))
    assert abs(res.estimate.mean_radius / 0.03 - 1) < 0.005
    assert len(res.samples) == 4


def test_noisy_repetition_accumulates_and_uncertainty_shrinks():
    sc, st = _start("sphere", 0.04)
    sensor = TactileSensor(2e-4, rng=11)
    est = CurvatureEstimator()
    r1 = run_ep1(sc, st, "finger1", sensor, estimator=est)
    r2 = run_ep1(sc, st, "finger1", sensor, estimator=est)
    assert est.n_samples == 16 and r2.estimate.n_samples == 16
    assert r2.estimate.sigma_mean_curvature < r1.estimate.sigma_mean_curvature
    assert 0.0 <= r2.estimate.rating <= 1.0
    # samples returned by a run can be added elsewhere: the planner's accumulation
    other = CurvatureEstimator()
    other.add_samples(r1.samples + r2.samples)
    np.testing.assert_allclose(other.estimate().form, r2.estimate.form)
    # the error is consistent with the stated uncertainty (3σ)
    H = r2.estimate.mean_curvature
    assert abs(H - 25.0) < 3 * r2.estimate.sigma_mean_curvature + 1e-9


def test_repeat_until_rating():
    sc, st = _start("sphere", 0.08)
    res, runs, steps = repeat_ep1(
        sc, st, "finger1", TactileSensor(2e-4, rng=2), target_rating=0.95, max_runs=10
    )
    assert res.estimate.rating >= 0.95 or runs == 10
    assert steps == 800 * runs
    assert abs(res.estimate.mean_radius / 0.08 - 1) < 0.15


def test_no_contact_and_bad_parameters():
    sc = ep1_scene("sphere", 0.04)
    st = sc.hand.state()  # neutral: 5 mm away
    with pytest.raises(EP1Error, match="place_hand_for_ep1"):
        run_ep1(sc, st, "finger1", TactileSensor(0.0))
    st = sc.hand.state(place_hand_for_ep1(sc))
    for kw, field in [
        ({"omega": -1.0}, "omega"),
        ({"dt": math.nan}, "dt"),
        ({"steps_per_direction": 2}, "steps_per_direction"),
        ({"directions": (0.0,)}, "directions"),
    ]:
        with pytest.raises(EP1Error, match=field):
            run_ep1(sc, st, "finger1", TactileSensor(0.0), **kw)
    with pytest.raises(EP1Error, match="shape"):
        ep1_scene("cube", 0.04)


def test_cli_text_and_json(capsys):
    assert eos_main(["ep1", "--shape", "sphere", "--radius", "0.02", "--noise", "0"]) == 0
    out = capsys.readouterr().out
    assert "estimate" in out and "ground truth" in out and "steps" in out
    assert eos_main(["ep1", "--shape", "cylinder", "--radius", "0.03", "--seed", "1", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["steps"] > 0 and d["ground_truth"]["radii"][1] is None
    assert d["estimate"]["sigma_curvatures"][0] > 0


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--radius", "-0.04"], "--radius"),
        (["--radius", "0"], "--radius"),
        (["--radius", "nan"], "--radius"),
        (["--shape", "cube"], "--shape"),
        (["--noise", "-1"], "--noise"),
        (["--seed", "x"], "--seed"),
        (["--finger", "finger7"], "--finger"),
        (["--solver", "nope"], "--solver"),
    ],
)
def test_cli_bad_arguments_exit_2(argv, option, capsys):
    try:
        code = eos_main(["ep1", *argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert option in err and "Traceback" not in err
