"""What the cylinder and the capsule share: a ``radius`` and a ``length`` (m) along local z."""

from __future__ import annotations

from typing import Any, ClassVar

import coal
import numpy as np
import pinocchio as pin

from eos_svc.objects.base import Array, SurfaceObject, perpendicular_unit, positive


class AxialObject(SurfaceObject):
    """A kind of ``radius`` m about a ``length`` m along local z, centred; its coal shape is
    ``coal_shape(radius, length)``."""

    size_fields = ("radius", "length")
    half_size_count = 2
    orientation = "axis"
    #: coal's class of the shape, built from ``(radius, length)``
    coal_shape: ClassVar[type[coal.ShapeBase]]

    def __init__(self, radius: float, length: float, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radius = positive("radius", radius)
        self.length = positive("length", length)
        self._geom = self.coal_shape(self.radius, self.length)

    @property
    def half_sizes(self) -> Array:
        return np.array([self.radius, 0.5 * self.length])

    @classmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> AxialObject:
        return cls(float(half[0]), 2.0 * float(half[1]), placement)

    def sizes(self) -> dict[str, Any]:
        return {"radius": self.radius, "length": self.length}

    def approach_options(self, closing: Array) -> list[Array | None]:
        """The object's axes, and the direction across both the grip and the axis."""
        return [
            *super().approach_options(closing),
            perpendicular_unit(np.cross(closing, self.rotation[:, 2]), closing),
        ]
