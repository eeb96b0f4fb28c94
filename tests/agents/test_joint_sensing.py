"""The simulated hand's joint sensing: encoder noise and link-length calibration error."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.planner import default_hand
from eos_svc.errors import ValidationError
from eos_svc.world.joint_sensing import JointSensing, position_sigma


def test_exact_by_default_draws_nothing():
    hand = default_hand()
    sensing = JointSensing.build(hand, 0.0, 0.0, np.random.SeedSequence(1))
    state = hand.state(hand.neutral())
    assert sensing.exact and sensing.rng is None and sensing.position_sigma == 0.0
    frame = sensing.tip_frame(state, "finger1")
    assert np.array_equal(frame.translation, state.data.oMf[hand.tip_frame_id("finger1")].translation)


def test_link_errors_shift_a_straight_finger_along_itself():
    # at q = 0 every finger of hand3x3 is straight along +x: links δ longer than the model
    # believes leave the reported tip Σδ short of the true one, along x
    hand = default_hand()
    sensing = JointSensing.build(hand, 0.0, 0.001, np.random.SeedSequence(7))
    state = hand.state(hand.neutral())
    for finger in hand.finger_names:
        true = state.data.oMf[hand.tip_frame_id(finger)].translation
        reported = sensing.tip_frame(state, finger).translation
        delta = float(np.sum(sensing.link_error[finger]))
        assert reported - true == pytest.approx([-delta, 0.0, 0.0], abs=1e-12)
    # drawn once: the same error at every reading
    again = sensing.tip_frame(state, "finger1").translation
    assert np.array_equal(again, sensing.tip_frame(state, "finger1").translation)


def test_encoder_noise_spreads_the_tip_as_its_jacobian_says():
    hand = default_hand()
    sigma = 1e-3
    sensing = JointSensing.build(hand, sigma, 0.0, np.random.SeedSequence(3))
    q = hand.neutral()
    idx = hand.finger_q_index("finger1")
    q[idx] = 0.4
    state = hand.state(q)
    true = state.data.oMf[hand.tip_frame_id("finger1")].translation.copy()
    errors = np.array([sensing.tip_frame(state, "finger1").translation - true for _ in range(4000)])
    # small angles: E‖e‖² = σ² ‖J‖_F² over the finger's joint columns (finite differences)
    J = np.zeros((3, len(idx)))
    for k, i in enumerate(idx):
        dq = q.copy()
        dq[i] += 1e-7
        J[:, k] = (hand.state(dq).data.oMf[hand.tip_frame_id("finger1")].translation - true) / 1e-7
    expected = sigma**2 * float(np.sum(J * J))
    assert float(np.mean(np.sum(errors**2, axis=1))) == pytest.approx(expected, rel=0.1)
    assert np.linalg.norm(errors.mean(axis=0)) < 0.1 * np.sqrt(expected)  # unbiased


def test_position_sigma_closed_form():
    # three links of 40 mm: the joints sit 120, 80 and 40 mm behind the tip centre at q = 0
    hand = default_hand()
    sigma = position_sigma(hand, 1e-3, 2e-4)
    assert sigma == pytest.approx(np.sqrt(3 * 2e-4**2 + (1e-3**2) * (0.12**2 + 0.08**2 + 0.04**2)), rel=1e-6)


@pytest.mark.parametrize(
    ("field", "value"), [("encoder_noise", -1e-3), ("link_error", 0.1), ("encoder_noise", "x")]
)
def test_request_options_are_checked(field, value):
    with pytest.raises(ValidationError) as info:
        PlanRequest(**{field: value})
    assert info.value.field == field


def test_request_options_round_trip_and_stay_out_of_the_default_form():
    assert "encoder_noise" not in PlanRequest().to_dict()
    request = PlanRequest(encoder_noise=5e-4, link_error=5e-4)
    assert PlanRequest.from_dict(request.to_dict()) == request


def test_a_plan_with_sensing_errors_still_grasps():
    spec = ObjectSpec("box", {"size": [0.07, 0.05, 0.06]}, (0.24, 0.01, 0.0), (0.2, 0.1, 0.5))
    exact = plan(PlanRequest(obj=spec, seed=4))
    noisy = plan(PlanRequest(obj=spec, seed=4, encoder_noise=5e-4, link_error=5e-4))
    assert exact.good_grasp and noisy.good_grasp
    # the contacts the postulate rests on moved: the reported kinematics differ
    assert noisy.shape["object"] != exact.shape["object"]
