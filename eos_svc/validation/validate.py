"""``validate_grasp``: does the planned grasp hold the object in a physics engine? What it reads
from a plan result is checked at the edge, each problem a :class:`~eos_svc.errors.ValidationError`
naming the field (the recipe and its numbers: ``docs/validation.md``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from eos_svc.errors import ValidationError
from eos_svc.kinematics.hand import HandModel
from eos_svc.schema.request import MAX_FRICTION, MESH_FIELDS, SHAPE_SIZE_FIELDS, ObjectSpec, Table
from eos_svc.validation.drake_hand import drake_urdf, model_joint_names
from eos_svc.validation.report import DIRECTIONS, DirectionOutcome, GraspValidation
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


def _positive(value: object, name: str, upper: float = math.inf, zero: bool = False) -> float:
    """``value`` as a number in (0, ``upper``] (in [0, ``upper``] when ``zero`` is allowed)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValidationError(name, f"must be a number, got {type(value).__name__}")
    v = float(value)
    if not (math.isfinite(v) and (v >= 0.0 if zero else v > 0.0) and v <= upper):
        raise ValidationError(name, f"must be in {'[' if zero else '('}0, {upper}], got {value!r}")
    return v


@dataclass(frozen=True)
class GraspSetup:
    """The grasp to simulate.

    Attributes:
        q_final: every joint of the hand in the planner's order (hand3x3: wrist x, y, z (m),
            roll, pitch, yaw (rad), then each finger's joints from the palm out (rad)).
        obj: the real object, shape, size and pose.
        friction: Coulomb μ of the hand–object contacts.
        table_height: the table the object rests on (world z of its top, m), or None.
    """

    q_final: tuple[float, ...]
    obj: ObjectSpec
    friction: float
    table_height: float | None = None


def _field(result: Any, name: str) -> Any:
    found = name in result if isinstance(result, Mapping) else hasattr(result, name)
    if not found:
        raise ValidationError(name, "is missing from the plan result")
    return result[name] if isinstance(result, Mapping) else getattr(result, name)


def _q_final(value: Any, joints: int) -> tuple[float, ...]:
    if value is None:
        raise ValidationError(
            "q_final", "is null: the plan has no final hand configuration (the end agent never judged it)"
        )
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence):
        raise ValidationError("q_final", f"must be a list of {joints} numbers, got {type(value).__name__}")
    if len(value) != joints:
        raise ValidationError(
            "q_final",
            f"must have {joints} joint values (wrist then fingers), got {len(value)}: is this another "
            "hand's plan (e.g. --hand allegro)? Validate it with its hand (validate_grasp(..., hand=...), "
            "eos validate --hand NAME)",
        )
    out = []
    for i, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
            raise ValidationError(f"q_final[{i}]", f"must be a finite number, got {v!r}")
        out.append(float(v))
    return tuple(out)


def _object(value: Any) -> ObjectSpec:
    if not isinstance(value, Mapping):
        raise ValidationError("ground_truth", f"must be an object, got {type(value).__name__}")
    sizes = {k for fields in SHAPE_SIZE_FIELDS.values() for k in fields} | set(MESH_FIELDS)
    # ground_truth also carries derived fields (diameter, d_over_h): keep what a request has
    spec = {k: v for k, v in value.items() if k in sizes | {"shape", "position", "rpy"}}
    if "position" not in spec:
        raise ValidationError("ground_truth.position", "is required")
    try:
        return ObjectSpec.from_dict(spec, prefix="ground_truth")
    except ValidationError as exc:  # size checks name the request's "object.*" fields
        where = "ground_truth" + exc.field[len("object") :] if exc.field.startswith("object") else exc.field
        raise ValidationError(where, exc.reason) from None


def grasp_setup(result: Any, joints: int) -> GraspSetup:
    """The grasp of a plan result (object or JSON dict) with ``joints`` hand joints.

    Raises:
        ValidationError: naming the missing or malformed field (``q_final``,
            ``ground_truth.radius``, ``friction``, …).
    """
    if not isinstance(result, Mapping) and not hasattr(result, "q_final"):
        raise ValidationError(
            "result", f"must be a plan result or its JSON object, got {type(result).__name__}"
        )
    q = _q_final(_field(result, "q_final"), joints)
    obj = _object(_field(result, "ground_truth"))
    friction = _positive(_field(result, "friction"), "friction", MAX_FRICTION, zero=True)
    # the table of the plan's request (none, or a result without its request: no table)
    request = result.get("request") if isinstance(result, Mapping) else getattr(result, "request", None)
    table = request.get("table") if isinstance(request, Mapping) else None
    try:
        return GraspSetup(q, obj, friction, None if table is None else Table.from_dict(table).height)
    except ValidationError as exc:
        raise ValidationError(f"request.{exc.field}", exc.reason) from None


def load_directions(directions: int | Sequence[str]) -> tuple[str, ...]:
    """The load directions: the first ``n`` of :data:`DIRECTIONS` or named ones (``"+x"``, …).

    Raises:
        ValidationError: ``directions`` names an unknown or repeated direction, or is out of 1…6.
    """
    if isinstance(directions, int) and not isinstance(directions, bool):
        if not 1 <= directions <= len(DIRECTIONS):
            raise ValidationError("directions", f"must be in [1, {len(DIRECTIONS)}], got {directions}")
        return DIRECTIONS[:directions]
    if isinstance(directions, (str, bool)) or not isinstance(directions, Sequence) or not directions:
        raise ValidationError(
            "directions", "must be a count 1…6 or a non-empty list of +x, -x, +y, -y, +z, -z"
        )
    for i, d in enumerate(directions):
        if d not in DIRECTIONS or d in directions[:i]:
            why = "given twice" if d in DIRECTIONS else f"unknown (choose from {', '.join(DIRECTIONS)})"
            raise ValidationError("directions", f"direction {d!r}: {why}")
    return tuple(directions)


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
