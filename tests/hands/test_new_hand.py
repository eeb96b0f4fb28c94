"""A new hand needs only its description: a hand not shipped with eos_svc — a small URDF this
test writes, three fingers of two revolute joints whose positive angles *open* — described in a
TOML file, registered, planned with and validated in Drake. Nothing else is written for it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.hands import HandRegistry
from eos_svc.validation import validate_grasp
from eos_svc.world.hand_context import HandContext

#: the fingers' bases sit this far off the hand axis (m); links are 50 mm long
RHO = 0.04
LINK = 0.05


def finger_urdf(i: int, angle: float) -> str:
    """Finger ``i`` at ``angle`` about the base's x axis: two links along x, joints about their
    local z (tangential: a positive angle swings the tip away from the axis, so the closing
    direction is −1)."""
    y, z = RHO * math.cos(angle), RHO * math.sin(angle)
    limit = '<limit lower="-1.2" upper="0.4" effort="2" velocity="2"/>'
    link = (
        '<collision><origin xyz="{x} 0 0" rpy="0 1.5707963 0"/>'
        '<geometry><cylinder radius="0.006" length="0.04"/></geometry></collision>'
        '<inertial><mass value="0.02"/>'
        '<inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial>'
    )
    return f"""
  <joint name="f{i}_j1" type="revolute"><parent link="base"/><child link="f{i}_l1"/>
    <origin xyz="0.02 {y:.6f} {z:.6f}" rpy="{angle:.9f} 0 0"/><axis xyz="0 0 1"/>{limit}</joint>
  <link name="f{i}_l1">{link.format(x=LINK / 2)}</link>
  <joint name="f{i}_j2" type="revolute"><parent link="f{i}_l1"/><child link="f{i}_l2"/>
    <origin xyz="{LINK} 0 0"/><axis xyz="0 0 1"/>{limit}</joint>
  <link name="f{i}_l2">{link.format(x=0.02)}</link>"""


def write_hand(tmp_path):
    """The URDF and its description (the finger above the axis opposes the two below)."""
    fingers = "".join(finger_urdf(i, math.radians(a)) for i, a in ((1, 90.0), (2, 210.0), (3, 330.0)))
    (tmp_path / "claw.urdf").write_text(
        f"""<robot name="claw">
  <link name="base"><collision><origin xyz="0.005 0 0"/><geometry><box size="0.01 0.1 0.1"/></geometry>
  </collision><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>{fingers}
</robot>"""
    )
    finger_tables = "".join(
        f"""
[[fingers]]
name = "claw{i}"
joints = ["f{i}_j1", "f{i}_j2"]
closing = [-1, -1]
tip = {{ link = "f{i}_l2", xyz = [{LINK}, 0.0, 0.0], radius = 0.008 }}
"""
        for i in (1, 2, 3)
    )
    (tmp_path / "claw.toml").write_text(
        f"""name = "claw"
summary = "a test hand: three fingers of two joints"
urdf = {{ path = "claw.urdf" }}
root_link = "base"
opposing_finger = "claw1"

[wrist]
floating = true
{finger_tables}"""
    )
    return tmp_path / "claw.toml"


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
