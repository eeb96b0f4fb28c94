"""A new hand needs only its description: a hand not shipped with eos_svc — a small URDF this
test writes, three fingers of two revolute joints whose positive angles *open* — described in a
TOML file, registered, planned with and validated in Drake. Nothing else is written for it."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.hands import HandRegistry
from eos_svc.validation import validate_grasp
from eos_svc.world.hand_context import HandContext
from tests.hands.claw import write_hand


def test_a_hand_from_its_description_alone_plans_and_holds(tmp_path):
    registry = HandRegistry()
    assert "claw" not in registry.names
    spec = registry.add_file(write_hand(tmp_path))
    assert registry.names.count("claw") == 1
    hand = registry.build("claw")
    assert hand.finger_names == ("claw1", "claw2", "claw3") and hand.nq == 6 + 6
    # the closing direction −1: the planner's +q closes, toward the hand axis
    state = hand.state()
    q, _ = state.close_finger("claw2", 0.5)
    before, after = state.tip_position("claw2"), hand.state(q).tip_position("claw2")
    assert np.hypot(*after[1:]) < np.hypot(*before[1:]) - 0.01
    context = HandContext.build(hand)
    request = PlanRequest(obj=ObjectSpec("sphere", {"radius": 0.025}, ObjectSpec().position), seed=1)
    result = plan(request, context=context, keep_trace=False)
    assert result.status == "success", result.reason
    assert result.good_grasp and set(result.contacts) == set(spec.finger_names)
    check = validate_grasp(result, hand=hand, directions=2, seconds=0.5)
    assert check.held, check.reason


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda t: t.replace("closing = [-1, -1]", "closing = [-1, 2]", 1), "fingers[0].closing[1]"),
        (lambda t: t.replace('opposing_finger = "claw1"', 'opposing_finger = "thumb"'), "opposing_finger"),
        (lambda t: t.replace('joints = ["f1_j1"', 'joints = ["nope"', 1), "fingers[0].joints[0]"),
        (lambda t: t.replace('root_link = "base"', 'root_link = "palm_link"'), "root_link"),
        (lambda t: t.replace("radius = 0.008", "radius = -1", 1), "fingers[0].tip.radius"),
        (lambda t: t.replace('urdf = { path = "claw.urdf" }', 'urdf = { path = "none.urdf" }'), "urdf.path"),
        (lambda t: t + "\n[world]\nhand_size = 3\n", "world.hand_size"),
        (lambda t: t.replace("floating = true", "floating = 1"), "wrist.floating"),
    ],
)
def test_a_bad_description_is_refused_naming_the_key(tmp_path, edit, field):
    from eos_svc.kinematics import HandDescriptionError

    path = write_hand(tmp_path)
    path.write_text(edit(path.read_text()))
    with pytest.raises(HandDescriptionError) as info:
        HandRegistry().build(path)
    assert info.value.field == field, info.value
