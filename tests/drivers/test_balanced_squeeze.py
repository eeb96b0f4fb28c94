"""The balanced squeeze: its force shares against closed forms, and in Drake a grip squeezed
with them leaves the table carrying only the object's weight and the lift barely moves the
object in the hand, where the uniform squeeze pushed it into the table and it sagged."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, build_world, plan
from eos_svc.drivers.balanced_squeeze import balanced_forces, squeeze
from eos_svc.drivers.drake_world import DrakeDriver
from eos_svc.drivers.lift_test import GRAVITY, lift_test, squeeze_grip


def test_shares_balance_three_normals_at_120_degrees_equally() -> None:
    normals = np.array([[math.cos(a), math.sin(a), 0.0] for a in (0.0, 2 * math.pi / 3, 4 * math.pi / 3)])
    np.testing.assert_allclose(balanced_forces(normals), [1 / 3] * 3, atol=1e-3)


def test_two_fingers_on_one_side_share_what_the_opposing_one_pushes() -> None:
    normals = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    np.testing.assert_allclose(balanced_forces(normals), [0.25, 0.25, 0.5], atol=1e-3)  # evenness: 0.03 %


def test_unbalanceable_normals_keep_every_finger_at_its_smallest_share() -> None:
    normals = np.array([[0.0, 0.0, 1.0]] * 3)  # all on one side: nothing balances
    shares = balanced_forces(normals, min_share=0.2)
    assert shares.sum() == pytest.approx(1.0) and np.all(shares >= 0.2 - 1e-9)
    with pytest.raises(ValueError, match="min_share"):
        balanced_forces(normals, min_share=0.4)


def _grip(balanced: bool) -> tuple[float, dict]:
    """The default ball gripped at the kinematic plan's grip and squeezed: the table's force on
    it (N) and the lift test."""
    request = PlanRequest(seed=1)
    q = np.asarray(plan(request).q_final)
    driver = DrakeDriver(build_world(request), request.obj, request.friction)
    plant, world = driver._plant, driver._world
    plant.set_hand_q(q)
    kp = plant.settings.finger_kp
    target = squeeze(plant, world.hand, kp) if balanced else squeeze_grip(plant, world.hand)
    assert target is not None
    table = sum(f for other, _, _, f in plant.object_contacts() if other == 0)
    return table, lift_test(plant, world.hand, world.wrist_xyz_q, 0.5 * float(world.obj.diameter), target)


def test_in_drake_a_balanced_squeeze_leaves_the_weight_on_the_table_and_the_lift_does_not_sag() -> None:
    weight = 0.1 * GRAVITY
    table, lift = _grip(balanced=True)
    assert table < 1.5 * weight  # the fingers' forces nearly cancel: the table carries about the weight
    assert lift["held"] and lift["lift_drift_m"] < 0.003
    table, lift = _grip(balanced=False)
    assert table > 3 * weight  # the uniform squeeze pushes the ball into the table
    assert lift["lift_drift_m"] > 0.005  # and it sags in the hand when the table is gone
