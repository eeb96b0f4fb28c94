"""The sphere: ``{"shape": "sphere", "radius": r}``, centred at its position."""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from eos_svc.objects.base import Array, SurfaceObject, norm, positive, unit

_UP = np.array([0.0, 0.0, 1.0])


class Sphere(SurfaceObject):
    """Sphere of ``radius`` m."""

    kind = "sphere"
    size_fields = ("radius",)
    half_size_count = 1
    orientation = "none"

    def __init__(self, radius: float, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radius = positive("radius", radius)
        self._geom = coal.Sphere(self.radius)

    @property
    def half_sizes(self) -> Array:
        return np.array([self.radius])

    @classmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> Sphere:
        return cls(float(half[0]), placement)

    def sizes(self) -> dict[str, Any]:
        return {"radius": self.radius}

    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """``|p| − r``; the gradient ``p / |p|`` (+z at the centre)."""
        n = norm(P)
        return n - half[..., 0], unit(P, n, _UP)

    @property
    def diameter(self) -> float:
        return 2.0 * self.radius

    def local_half_extent(self, direction: Array) -> float:
        return self.radius

    def local_bounds(self, R: Array) -> Array:
        return np.full(3, self.radius)

    def _normal_local(self, s: Array) -> Array:
        out: Array = s / np.linalg.norm(s)
        return out

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        return np.eye(3) / self.radius

    def drake_shape(self) -> Any:
        from pydrake.geometry import Sphere as DrakeSphere

        return DrakeSphere(self.radius)

    def closing_axes(self) -> list[tuple[str, Array]]:
        """About a vertical and a horizontal diameter."""
        return [
            ("about a vertical diameter", _UP),
            ("about a horizontal diameter", np.array([0.0, 1.0, 0.0])),
        ]

    def approach_options(self, closing: Array) -> list[Array | None]:
        """None besides the hand's own: every direction is alike on a sphere."""
        return []

    @property
    def volume(self) -> float:
        return 4.0 / 3.0 * math.pi * self.radius**3

    def unit_inertia(self) -> Array:
        """``(2/5) r² I``."""
        out: Array = 0.4 * self.radius**2 * np.eye(3)
        return out
