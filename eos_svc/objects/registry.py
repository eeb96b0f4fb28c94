"""The object kinds by name: what the rest of the code iterates instead of naming each kind."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from eos_svc.errors import ValidationError
from eos_svc.objects.base import SurfaceObject
from eos_svc.objects.box import Box
from eos_svc.objects.capsule import Capsule
from eos_svc.objects.cylinder import Cylinder
from eos_svc.objects.ellipsoid import Ellipsoid
from eos_svc.objects.mesh import Mesh
from eos_svc.objects.sphere import Sphere

#: every object kind by its JSON name; the fitted ones first, in the order the shape fit breaks ties
KINDS: dict[str, type[SurfaceObject]] = {
    cls.kind: cls for cls in (Sphere, Ellipsoid, Cylinder, Capsule, Box, Mesh)
}
#: the kinds the shape fit fits to touches (the primitives: ``fittable``)
FITTED_KINDS: dict[str, type[SurfaceObject]] = {name: cls for name, cls in KINDS.items() if cls.fittable}


def kind_of(name: str, field: str = "object.shape") -> type[SurfaceObject]:
    """The class of the kind ``name``, else a :class:`ValidationError` naming ``field``."""
    if name not in KINDS:
        raise ValidationError(field, f"unknown shape {name!r} (choose from {', '.join(KINDS)})")
    return KINDS[name]


def from_dict(data: Mapping[str, Any], prefix: str = "object") -> SurfaceObject:
    """The object of a JSON form ``{"shape": kind, <its size fields>, "position", "rpy"}``."""
    if not isinstance(data, Mapping):
        raise ValidationError(prefix, f"must be an object, got {type(data).__name__}")
    if "shape" not in data:
        raise ValidationError(f"{prefix}.shape", "is required")
    return kind_of(str(data["shape"]), f"{prefix}.shape").from_dict(data, prefix)


def make(
    shape: str, size: Mapping[str, Any], position: Sequence[float], rpy: Sequence[float] = (0.0, 0.0, 0.0)
) -> SurfaceObject:
    """The object of kind ``shape`` with size fields ``size`` at ``position`` (m), ``rpy`` (rad)."""
    placement = pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.asarray(position, dtype=float))
    return kind_of(shape)(**size, placement=placement)
