"""The verdict of a Drake grasp validation: held or not, and what was measured per load direction."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

#: the six load directions, in the order they are simulated (world axes)
DIRECTIONS: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")


@dataclass(frozen=True)
class DirectionOutcome:
    """What happened while the object's weight pulled along one direction.

    Attributes:
        direction: ``"+x"`` … ``"-z"`` (world axes).
        displacement_m: largest distance (m) of the object's centre from where the squeeze left it.
        final_displacement_m: that distance at the end of the load (or when it stopped early).
        touching: hand parts (``palm`` or a finger name) in contact with the object at the end.
        held: ``displacement_m`` < the hold tolerance and at least ``min_parts`` parts touch.
        stopped_early: the object got ``stop_distance`` away; the rest of the load was skipped.
    """

    direction: str
    displacement_m: float
    final_displacement_m: float
    touching: tuple[str, ...]
    held: bool
    stopped_early: bool = False

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (every field)."""
        return asdict(self) | {"touching": list(self.touching)}


@dataclass(frozen=True)
class GraspValidation:
    """The result of :func:`eos_svc.validation.validate_grasp`.

    Attributes:
        held: held in every direction simulated.
        reason: the first failing direction and why, or "held in every direction".
        seconds: load duration per direction (s).
        outcomes: one :class:`DirectionOutcome` per direction, in simulation order.
        settle_seconds: squeeze time before any load (s).
        settle_displacement_m: how far the squeeze alone moved the object's centre (m).
        settle_touching: hand parts touching the object after the squeeze.
        mass_kg: object mass (kg); the load is its weight, ``mass_kg · gravity`` (N).
        friction: Coulomb μ of every hand–object contact.
        squeeze_rad: added to the planned finger angles as the PD target (rad).
        kp: PD stiffness of each finger joint (N·m/rad); ``kd`` its damping (N·m·s/rad).
        effort_limit: largest torque of each finger joint (N·m, the URDF's).
        hold_tolerance_m: a larger displacement is a drop (m).
        min_parts: fewest hand parts that must still touch the object.
        time_step: the discrete plant's step (s).
        wall_time_s: seconds the validation took.
    """

    held: bool
    reason: str
    seconds: float
    outcomes: tuple[DirectionOutcome, ...]
    settle_seconds: float
    settle_displacement_m: float
    settle_touching: tuple[str, ...]
    mass_kg: float
    friction: float
    squeeze_rad: float
    kp: float
    kd: float
    effort_limit: float
    hold_tolerance_m: float
    min_parts: int
    time_step: float
    wall_time_s: float

    @property
    def directions(self) -> tuple[str, ...]:
        """The directions simulated, in order."""
        return tuple(o.direction for o in self.outcomes)

    @property
    def displacement_m(self) -> dict[str, float]:
        """Largest displacement (m) per direction."""
        return {o.direction: o.displacement_m for o in self.outcomes}

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form: ``held``, ``reason``, ``displacement_m`` per direction,
        ``directions``, then every other field (per-direction details under ``outcomes``)."""
        head = {"held": self.held, "reason": self.reason, "displacement_m": self.displacement_m}
        lists = {
            "outcomes": [o.to_dict() for o in self.outcomes],
            "settle_touching": list(self.settle_touching),
        }
        return head | {"directions": list(self.directions)} | asdict(self) | lists
