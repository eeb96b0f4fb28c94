"""``validate_grasp``: does the planned grasp hold the object in a physics engine?

The recipe, its numbers and what is not modelled: ``docs/validation.md``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from eos_svc.errors import ValidationError
from eos_svc.kinematics.hand import HandModel
from eos_svc.validation.drake_hand import drake_urdf, model_joint_names
from eos_svc.validation.report import DirectionOutcome, GraspValidation
from eos_svc.validation.setup import grasp_setup, load_directions
from eos_svc.validation.simulation import (
    DEFAULT_CONTACT_STIFFNESS,
    DEFAULT_KD,
    DEFAULT_KP,
    DEFAULT_MASS,
    DEFAULT_SQUEEZE,
    DEFAULT_TIME_STEP,
    GraspSimulation,
    SimulationError,
)
from eos_svc.world.hand_context import default_context

if TYPE_CHECKING:
    from eos_svc.schema.result import PlanResult

#: standard gravity (m/s²): the load is the object's weight
GRAVITY = 9.81
#: the load is sampled this often (s) for the largest displacement
SAMPLE_S = 0.1
#: longest load and squeeze accepted (s of simulated time)
MAX_SECONDS = 60.0


def _positive(value: object, name: str, upper: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValidationError(name, f"must be a number, got {type(value).__name__}")
    v = float(value)
    if not (math.isfinite(v) and 0.0 < v <= upper):
        raise ValidationError(name, f"must be in (0, {upper}], got {value!r}")
    return v


def validate_grasp(
    result: PlanResult | Mapping[str, Any],
    *,
    directions: int | Sequence[str] = 6,
    seconds: float = 1.5,
    mass: float = DEFAULT_MASS,
    squeeze: float | None = None,
    kp: float | None = None,
    kd: float | None = None,
    settle_seconds: float = 0.3,
    hold_tolerance: float = 0.01,
    min_parts: int = 2,
    contact_stiffness: float = DEFAULT_CONTACT_STIFFNESS,
    time_step: float = DEFAULT_TIME_STEP,
    stop_distance: float = 0.05,
    hand: HandModel | None = None,
) -> GraspValidation:
    """Simulate a plan's final grasp in Drake and say whether it holds the object.

    Args:
        result: a :class:`~eos_svc.agents.PlanResult` or its JSON dict (``q_final``,
            ``ground_truth``, ``friction`` are read).
        directions: how many of +x, -x, +y, -y, +z, -z (in that order), or a list of them.
        seconds: load time per direction (s).
        mass: object mass (kg); the load is ``mass · 9.81`` N.
        squeeze: added to every planned finger joint as the PD target (rad, or m for a
            prismatic joint; closing); default: the hand's ``[drake] squeeze``, else
            :data:`DEFAULT_SQUEEZE`.
        kp, kd: PD gains of every finger joint (N·m/rad, N·m·s/rad; N/m, N·s/m for a
            prismatic one); torques are clipped at the URDF's effort limit; default: the
            hand's ``[drake]`` values, else :data:`DEFAULT_KP`, :data:`DEFAULT_KD`.
        settle_seconds: squeeze time before the loads (s).
        hold_tolerance: largest displacement that still counts as held (m).
        min_parts: fewest hand parts (palm or fingers) that must touch the object at the end.
        contact_stiffness: point-contact stiffness (N/m).
        time_step: discrete step of the plant (s).
        stop_distance: a direction stops early once the object is this far away (m).
        hand: the hand model the plan used (default hand3x3): its URDF (a described hand's
            composite text), its description and its joints in the model's order.

    Raises:
        ValidationError: naming the bad field of ``result`` or the bad argument.
        SimulationError: Drake failed while simulating (an :class:`~eos_svc.errors.EosError`).
    """
    t_start = time.perf_counter()
    hand = default_context().hand if hand is None else hand
    settings = dict(getattr(hand, "drake", {}))
    squeeze = settings.get("squeeze", DEFAULT_SQUEEZE) if squeeze is None else squeeze
    joint_names = model_joint_names(hand)
    setup = grasp_setup(result, len(joint_names))
    names = load_directions(directions)
    seconds = _positive(seconds, "seconds", MAX_SECONDS)
    mass = _positive(mass, "mass", 100.0)
    settle_seconds = _positive(settle_seconds, "settle_seconds", MAX_SECONDS)
    hold_tolerance = _positive(hold_tolerance, "hold_tolerance", 1.0)
    time_step = _positive(time_step, "time_step", 0.01)
    stop_distance = max(_positive(stop_distance, "stop_distance", 10.0), hold_tolerance)
    kp = _positive(settings.get("kp", DEFAULT_KP) if kp is None else kp, "kp", 1e4)
    kd = _positive(settings.get("kd", DEFAULT_KD) if kd is None else kd, "kd", 1e3)
    contact_stiffness = _positive(contact_stiffness, "contact_stiffness", 1e9)
    if isinstance(squeeze, bool) or not isinstance(squeeze, (int, float)) or not abs(squeeze) <= 0.5:
        raise ValidationError("squeeze", f"must be a number in [-0.5, 0.5] rad, got {squeeze!r}")
    if isinstance(min_parts, bool) or not isinstance(min_parts, int) or min_parts < 1:
        raise ValidationError("min_parts", f"must be an integer ≥ 1, got {min_parts!r}")

    with drake_urdf(hand) as (path, package_dirs):
        try:
            sim = GraspSimulation(
                path,
                hand.description,
                setup.q_final,
                setup.obj,
                friction=setup.friction,
                joint_names=joint_names,
                package_dirs=package_dirs,
                mass=mass,
                squeeze=float(squeeze),
                kp=kp,
                kd=kd,
                contact_stiffness=contact_stiffness,
                time_step=time_step,
                table_height=setup.table_height,
            )
            settled = sim.settle(settle_seconds)
            settle_touching = sim.touching()
            outcomes = []
            for name in names:
                axis = np.zeros(3)
                axis["xyz".index(name[1])] = 1.0 if name[0] == "+" else -1.0
                largest, final, early = sim.load(axis, mass * GRAVITY, seconds, SAMPLE_S, stop_distance)
                touching = sim.touching()
                held = largest < hold_tolerance and len(touching) >= min_parts
                outcomes.append(DirectionOutcome(name, largest, final, touching, held, early))
        except RuntimeError as exc:  # Drake's own failures (e.g. the contact solver not converging)
            raise SimulationError(f"Drake could not simulate the grasp: {exc}") from exc
    dropped = [o for o in outcomes if not o.held]
    if not dropped:
        reason = "held in every direction"
    else:
        first = dropped[0]
        why = (
            f"moved {first.displacement_m * 1000:.1f} mm"
            if first.displacement_m >= hold_tolerance
            else f"only {len(first.touching)} hand part(s) touch ({', '.join(first.touching) or 'none'})"
        )
        every = ", ".join(o.direction for o in dropped)
        reason = f"dropped along {first.direction}: {why} (dropped along {every})"
    return GraspValidation(
        held=not dropped,
        reason=reason,
        seconds=seconds,
        outcomes=tuple(outcomes),
        settle_seconds=settle_seconds,
        settle_displacement_m=float(np.linalg.norm(settled - sim.start)),
        settle_touching=settle_touching,
        mass_kg=mass,
        friction=setup.friction,
        squeeze_rad=float(squeeze),
        kp=kp,
        kd=kd,
        effort_limit=sim.effort_limit,
        hold_tolerance_m=hold_tolerance,
        min_parts=min_parts,
        time_step=time_step,
        wall_time_s=time.perf_counter() - t_start,
    )
