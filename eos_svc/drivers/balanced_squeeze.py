"""A balanced squeeze: fingertip forces along the contact normals whose sum is (nearly) zero.

Closing every finger joint by the same angle (:func:`~eos_svc.drivers.lift_test.squeeze_grip`)
pushes with whatever fingertip forces the fingers' geometry gives: on hand3x3 the two fingers on
one side pushed a resting ball into the table with 4.8 N (five times its weight) and the
opposing finger could not balance them. The table carried the difference until the lift took
it away; then the soft PD fingers found a new equilibrium with the object 7 mm lower in the
hand — 70 % of the lift test's 1 cm, before any load.

A grip controller squeezes with *internal* forces (forces in the null space of the grasp
matrix's force rows, Murray, Li & Sastry, "A Mathematical Introduction to Robotic
Manipulation", 1994, §5.3): here the fingertip normal forces ``F_f ≥ 0`` minimising
``‖Σ F_f n_f‖`` (non-negative least squares, each finger at least :data:`MIN_SHARE` of the
total; of balanced shares the most even: two fingers on one side push equally), each made
by the joint torques ``τ = J_fᵀ (−F_f n_f)`` (``J_f``: the tip centre's Jacobian; a force
along a spherical tip's normal passes through its centre), scaled so the most loaded joint
uses ``effort`` of its URDF effort limit, and commanded as PD targets ``q + τ / kp``. The
contact normals are the ones Drake reports.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from scipy.optimize import nnls

from eos_svc.drivers.lift_test import squeeze_grip

if TYPE_CHECKING:
    from eos_svc.drivers.drake_plant import DrakeHandPlant
    from eos_svc.kinematics import HandModel

#: the smallest share of the squeeze's total normal force one finger takes
MIN_SHARE = 0.15
#: the weight of the shares' evenness against their balance
EVEN = 0.05
#: the fraction of a joint's URDF effort limit the most loaded finger joint squeezes with (at 0.5,
#: the upright capsule's grip turned under the lift test's torque; at 0.9 it held)
EFFORT = 0.9
#: the light uniform squeeze (rad per finger joint) that puts every fingertip on the object
#: before the balanced one reads its contact normals
LIGHT = 0.02


def balanced_forces(normals: np.ndarray, min_share: float = MIN_SHARE) -> np.ndarray:
    """Normal force shares ``F`` (summing to 1, each ≥ ``min_share``) minimising ``‖Σ F_f n_f‖``
    for unit normals ``normals`` (k × 3), and among those (weight :data:`EVEN`) the spread of the
    shares."""
    n = np.asarray(normals, dtype=float)
    k = len(n)
    if k * min_share > 1.0:
        raise ValueError(f"min_share: {min_share} times {k} fingers exceeds the whole force")
    weight = 10.0  # the sum's row: shares add to 1 (nearly exactly)
    base = np.full(k, min_share)
    # among balanced shares the most even (fingers on one side share their push equally: a
    # grip that resists a twist about the line through the contacts with both)
    even = EVEN * (np.eye(k) - np.full((k, k), 1.0 / k))
    matrix = np.vstack([n.T, weight * np.ones((1, k)), even])
    rhs = np.concatenate([-(n.T @ base), [weight * (1.0 - k * min_share)], -(even @ base)])
    extra, _ = nnls(matrix, rhs)
    shares: np.ndarray = base + extra
    return shares / shares.sum()


def balanced_squeeze(
    plant: DrakeHandPlant, hand: HandModel, kp: float, effort: float = EFFORT
) -> np.ndarray | None:
    """The finger joints' PD targets (planner order, the wrist's kept) of a balanced squeeze of
    the current grip (module docstring), ``kp`` the finger joints' gain (N·m/rad); None when a
    fingertip does not touch the object (nothing to balance)."""
    q = plant.hand_q()
    normals = []
    for finger in hand.finger_names:
        found = plant.tip_force(plant.tip_bodies[finger])
        if found is None:
            return None
        normals.append(np.asarray(found[1], dtype=float))
    shares = balanced_forces(np.array(normals))
    model = hand.model
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    torque = np.zeros(model.nv)
    for finger, share, normal in zip(hand.finger_names, shares, normals, strict=True):
        J = pin.getFrameJacobian(model, data, hand.tip_frame_id(finger), pin.LOCAL_WORLD_ALIGNED)[:3]
        columns = hand.finger_v_index(finger)
        torque[columns] = J[:, columns].T @ (-share * normal)
    limits = np.asarray(hand.effort_limit, dtype=float)
    fingers = np.ones(model.nv, dtype=bool)
    fingers[np.asarray(hand.wrist_v_index)] = False
    use = np.max(np.abs(torque[fingers]) / limits[fingers])
    if use <= 0.0:
        return None
    torque *= effort / use
    target: np.ndarray = q + torque / kp  # 1-DoF joints: the q and v orders agree
    return target


def squeeze(plant: DrakeHandPlant, hand: HandModel, kp: float, settle_s: float = 0.3) -> np.ndarray | None:
    """Close lightly (:data:`LIGHT` rad per joint, 0.1 s), then the balanced squeeze, settled
    for ``settle_s`` s; its PD targets, or None (after the light squeeze only) when a fingertip
    does not touch."""
    squeeze_grip(plant, hand, LIGHT, 0.1)
    target = balanced_squeeze(plant, hand, kp)
    if target is None:
        return None
    plant.command(target)
    plant.advance(settle_s)
    return target
