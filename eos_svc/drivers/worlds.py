"""The worlds a plan can run in, by name: ``kinematic`` (the default) and ``drake``."""

from __future__ import annotations

from typing import TYPE_CHECKING

from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.errors import ValidationError
from eos_svc.schema.request import WORLDS

if TYPE_CHECKING:
    from eos_svc.schema.request import PlanRequest
    from eos_svc.world.world import GraspWorld


def check_world(name: object) -> str:
    """``name`` if it names a world, else a :class:`ValidationError` naming the field ``world``."""
    if name not in WORLDS:
        raise ValidationError("world", f"must be one of {', '.join(WORLDS)}, got {name!r}")
    return str(name)


def make_driver(name: str, world: GraspWorld, request: PlanRequest) -> KinematicDriver:
    """The driver of the world ``name`` for a plan of ``request`` (``world``: the kinematic
    model with the request's object; the Drake world starts its simulation from it)."""
    if check_world(name) == "drake":
        from eos_svc.drivers.drake_world import DrakeDriver  # Drake loads only when asked

        return DrakeDriver(world, request.obj, request.friction)
    return KinematicDriver(world)
