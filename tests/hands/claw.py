"""A hand not shipped with eos_svc, for the tests: a small URDF written here, three fingers of
two revolute joints whose positive angles *open*, and its description (TOML)."""

from __future__ import annotations

import math
from pathlib import Path

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


def write_hand(tmp_path: Path) -> Path:
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
