"""The Drake world's lift test: does the grip hold the object off the table under load?

After the grip (every fingertip touching), in the Drake world (:mod:`eos_svc.drivers.drake_plant`):

1. squeeze: every finger joint's PD target ``squeeze`` rad further closed (0.1 rad: 0.5 N·m at
   the Drake world's finger gain, half hand3x3's effort limit), settle;
2. lift: the wrist up ``height`` m (a straight ramp), hold;
3. load: from the lifted state, one at a time, the object's weight acting along ±x, ±y, ±z (an
   external force that cancels gravity and adds ``m g`` along the direction) and a torque
   ``m g r`` (r: half the object's diameter) about +x, +y, +z, each for ``load_s`` seconds.

Held = the object rose with the hand (at least half of ``height``) and its position relative
to the palm moved less than ``limit`` (1 cm) during the lift and under every load. (DexGraspBench
uses forces only; this adds the torques.)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from eos_svc.drivers.drake_plant import DrakeHandPlant
from eos_svc.kinematics import HandModel

GRAVITY = 9.81
#: the loads: (label, unit force direction or None, unit torque axis or None)
LOADS: tuple[tuple[str, tuple[float, float, float] | None, tuple[float, float, float] | None], ...] = (
    ("+x", (1.0, 0.0, 0.0), None),
    ("-x", (-1.0, 0.0, 0.0), None),
    ("+y", (0.0, 1.0, 0.0), None),
    ("-y", (0.0, -1.0, 0.0), None),
    ("+z", (0.0, 0.0, 1.0), None),
    ("-z", (0.0, 0.0, -1.0), None),
    ("torque x", None, (1.0, 0.0, 0.0)),
    ("torque y", None, (0.0, 1.0, 0.0)),
    ("torque z", None, (0.0, 0.0, 1.0)),
)


#: how much further every finger joint is closed for the grip the lift test starts from, rad
SQUEEZE = 0.1


def _in_palm(plant: DrakeHandPlant, palm: str) -> np.ndarray:
    """The object's centre in the palm frame, m."""
    X_WP = plant.body_pose(palm)
    return np.asarray(X_WP.inverse().multiply(plant.object_pose().translation()))


def squeeze_grip(
    plant: DrakeHandPlant, hand: HandModel, squeeze: float = SQUEEZE, settle_s: float = 0.3
) -> np.ndarray:
    """Step 1: every finger joint's target ``squeeze`` rad further closed than where it is,
    settled for ``settle_s`` s (the grip the lift starts from); returns the joint targets."""
    q = plant.hand_q()
    fingers = np.ones(len(q), dtype=bool)
    fingers[np.asarray(hand.wrist_q_index)] = False
    target: np.ndarray = q + squeeze * fingers
    plant.set_object_wrench(np.zeros(3), np.zeros(3))
    plant.command(target)
    plant.advance(settle_s)
    return target


def lift_test(
    plant: DrakeHandPlant,
    hand: HandModel,
    wrist_xyz_q: Any,
    radius: float,
    target: np.ndarray,
    *,
    height: float = 0.1,
    lift_s: float = 1.0,
    settle_s: float = 0.3,
    load_s: float = 0.3,
    limit: float = 0.01,
    chunk: float = 0.01,
) -> dict[str, Any]:
    """Steps 2 and 3 of the lift test (see the module docstring) from the squeezed grip
    (``target``: :func:`squeeze_grip`'s joint targets); returns ``held`` and the figures (m):
    rise, drift during the lift, displacement per load."""
    palm = hand.model.frames[hand.palm_frame_id].name
    mass = plant.settings.mass
    q = plant.hand_q()
    before = _in_palm(plant, palm)
    z0 = float(plant.object_pose().translation()[2])
    lifted = target.copy()
    lift = np.zeros(len(q))
    lift[wrist_xyz_q[2]] = height
    steps = max(1, round(lift_s / chunk))
    t0 = plant.time()
    drift = 0.0
    for k in range(1, steps + 1):
        plant.command_moving(target + lift * (k / steps), lift / lift_s if k < steps else np.zeros(len(q)))
        plant.advance_to(t0 + lift_s * k / steps)
        drift = max(drift, float(np.linalg.norm(_in_palm(plant, palm) - before)))
    lifted = target + lift
    plant.command(lifted)
    plant.advance(settle_s)
    held_at = _in_palm(plant, palm)
    drift = max(drift, float(np.linalg.norm(held_at - before)))
    rise = float(plant.object_pose().translation()[2]) - z0
    saved = plant.save()
    weight = mass * GRAVITY
    displacements: dict[str, float] = {}
    for label, direction, axis in LOADS:
        plant.restore(saved)
        plant.command(lifted)
        up = np.array([0.0, 0.0, 1.0])  # cancels gravity: the net load is the weight along direction
        force = np.zeros(3) if direction is None else weight * (np.asarray(direction) + up)
        torque = np.zeros(3) if axis is None else weight * radius * np.asarray(axis)
        plant.set_object_wrench(force, torque)
        worst = 0.0
        start = plant.time()
        for k in range(1, max(1, round(load_s / chunk)) + 1):
            plant.advance_to(start + k * chunk)
            worst = max(worst, float(np.linalg.norm(_in_palm(plant, palm) - held_at)))
            if worst >= limit:
                break
        displacements[label] = round(worst, 6)
    plant.restore(saved)
    plant.set_object_wrench(np.zeros(3), np.zeros(3))
    failed = [label for label, d in displacements.items() if d >= limit]
    held = rise >= 0.5 * height and drift < limit and not failed
    why = "held" if held else (
        f"the object did not rise with the hand (rose {rise * 1000:.1f} mm)" if rise < 0.5 * height
        else f"slipped {drift * 1000:.1f} mm in the hand while lifted" if drift >= limit
        else f"moved >= {limit * 1000:.0f} mm in the hand under {', '.join(failed)}"
    )  # fmt: skip
    return {
        "held": bool(held),
        "why": why,
        "rise_m": round(rise, 6),
        "lift_drift_m": round(drift, 6),
        "load_displacement_m": displacements,
        "limit_m": limit,
    }
