"""The cylinder: ``{"shape": "cylinder", "radius": r, "length": l}``, its axis along local z,
centred, with flat caps (coal's and Drake's convention: ``length`` is the full length)."""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np

from eos_svc.objects.axial import AxialObject
from eos_svc.objects.base import (
    EDGE_TOLERANCE,
    TINY,
    Array,
    CurvatureUndefinedError,
    across_axis_units,
)

_X = np.array([1.0, 0.0, 0.0])


class Cylinder(AxialObject):
    """Cylinder of ``radius`` m and ``length`` m along local z, centred (flat caps)."""

    kind = "cylinder"
    coal_shape = coal.Cylinder

    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """With ``dr = ρ − r`` and ``dz = |z| − h``: outside ``‖(max(dr, 0), max(dz, 0))‖``,
        inside ``max(dr, dz)``; the gradient from the radial and axial directions."""
        radius, half_length = half[..., 0], half[..., 1]
        rho = np.hypot(P[..., 0], P[..., 1])
        across = P.copy()
        across[..., 2] = 0.0
        radial = np.where((rho > TINY)[..., None], across / np.maximum(rho, TINY)[..., None], _X)
        axial = np.zeros(P.shape)
        axial[..., 2] = np.where(P[..., 2] >= 0.0, 1.0, -1.0)
        dr, dz = rho - radius, np.abs(P[..., 2]) - half_length
        a, b = np.maximum(dr, 0.0), np.maximum(dz, 0.0)
        out = np.hypot(a, b)
        d = out + np.minimum(np.maximum(dr, dz), 0.0)
        g_out = (a[..., None] * radial + b[..., None] * axial) / np.maximum(out, TINY)[..., None]
        g_in = np.where((dr > dz)[..., None], radial, axial)
        return d, np.where((out > TINY)[..., None], g_out, g_in)

    @property
    def diameter(self) -> float:
        return math.hypot(2.0 * self.radius, self.length)

    def local_half_extent(self, direction: Array) -> float:
        across, along = math.hypot(direction[0], direction[1]), abs(direction[2])
        return min(
            self.radius / across if across > 0 else math.inf,
            0.5 * self.length / along if along > 0 else math.inf,
        )

    def local_bounds(self, R: Array) -> Array:
        axial = np.abs(R[:, 2])
        out: Array = axial * 0.5 * self.length + self.radius * np.sqrt(np.maximum(1.0 - axial**2, 0.0))
        return out

    def _on_side(self, s: Array) -> bool:
        R, hz = self.radius, 0.5 * self.length
        tol = EDGE_TOLERANCE + 1e-12 * max(R, hz)
        on_side = abs(math.hypot(s[0], s[1]) - R) <= tol
        if on_side and abs(abs(s[2]) - hz) <= tol:
            raise CurvatureUndefinedError(
                "p_world", "the point is on a cylinder rim; normal and curvature are undefined"
            )
        return on_side

    def _normal_local(self, s: Array) -> Array:
        if self._on_side(s):
            rho = math.hypot(s[0], s[1])
            return np.array([s[0] / rho, s[1] / rho, 0.0])
        return np.array([0.0, 0.0, math.copysign(1.0, s[2])])

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        if not self._on_side(s):
            return np.zeros((3, 3))
        t = np.array([-n[1], n[0], 0.0])
        out: Array = np.outer(t, t) / self.radius
        return out

    def drake_shape(self) -> Any:
        from pydrake.geometry import Cylinder as DrakeCylinder

        return DrakeCylinder(self.radius, self.length)

    def closing_axes(self) -> list[tuple[str, Array]]:
        """Across the axis (its normals, the vertical's and the hand's y's parts across it), and
        along it when the object is no longer than wide (on the end faces)."""
        axis = self.rotation[:, 2]
        axes = [("across the axis", g) for g in across_axis_units(self.rotation)]
        if self.length <= 2.0 * self.radius:
            axes.append(("along the axis", axis))
        return axes

    @property
    def volume(self) -> float:
        return math.pi * self.radius**2 * self.length

    def unit_inertia(self) -> Array:
        """``diag((3r² + l²)/12, (3r² + l²)/12, r²/2)``."""
        r2, l2 = self.radius**2, self.length**2
        across = (3.0 * r2 + l2) / 12.0
        return np.diag([across, across, 0.5 * r2])
