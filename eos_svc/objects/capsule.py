"""The capsule: ``{"shape": "capsule", "radius": r, "length": l}``, a cylinder of radius ``r``
with a straight part of ``length`` along local z, capped by hemispheres (total length
``l + 2r``, coal's and Drake's convention)."""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np

from eos_svc.objects.axial import AxialObject
from eos_svc.objects.base import Array, across_axis_units, norm, unit

_X = np.array([1.0, 0.0, 0.0])


class Capsule(AxialObject):
    """Capsule of ``radius`` m about a straight part of ``length`` m along local z."""

    kind = "capsule"
    coal_shape = coal.Capsule

    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """The distance to the axis segment minus the radius; the gradient away from the
        segment's nearest point (+x on the segment itself)."""
        v = P.copy()
        v[..., 2] -= np.clip(P[..., 2], -half[..., 1], half[..., 1])
        n = norm(v)
        return n - half[..., 0], unit(v, n, _X)

    @property
    def diameter(self) -> float:
        return self.length + 2.0 * self.radius

    def local_half_extent(self, direction: Array) -> float:
        r, h = self.radius, 0.5 * self.length
        across, along = math.hypot(direction[0], direction[1]), abs(direction[2])
        if across * h >= r * along:  # leaves through the side, where |z| ≤ h
            return r / across
        # through a cap: |t·d − (0, 0, h)| = r
        return h * along + math.sqrt(max((h * along) ** 2 - h * h + r * r, 0.0))

    def local_bounds(self, R: Array) -> Array:
        out: Array = np.abs(R[:, 2]) * 0.5 * self.length + self.radius
        return out

    def _axis_point(self, p: Array) -> Array:
        hz = 0.5 * self.length
        return np.array([0.0, 0.0, min(max(p[2], -hz), hz)])

    def _normal_local(self, s: Array) -> Array:
        d = s - self._axis_point(s)
        out: Array = d / np.linalg.norm(d)
        return out

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        if abs(s[2]) > 0.5 * self.length:  # hemispherical cap
            return np.eye(3) / self.radius
        t = np.array([-n[1], n[0], 0.0])
        out: Array = np.outer(t, t) / self.radius
        return out

    def drake_shape(self) -> Any:
        from pydrake.geometry import Capsule as DrakeCapsule

        return DrakeCapsule(self.radius, self.length)

    def closing_axes(self) -> list[tuple[str, Array]]:
        """Across the axis (its normals, the vertical's and the hand's y's parts across it); never
        along it: a capsule is always longer than wide."""
        return [("across the axis", g) for g in across_axis_units(self.rotation)]

    @property
    def volume(self) -> float:
        r = self.radius
        return math.pi * r * r * self.length + 4.0 / 3.0 * math.pi * r**3

    def unit_inertia(self) -> Array:
        """The cylinder's and the two hemispheres' (parallel axes: each hemisphere's centre of
        mass 3r/8 beyond the end of the straight part), in proportion to their volumes."""
        r, h = self.radius, self.length
        cylinder = math.pi * r * r * h / self.volume
        ends = 1.0 - cylinder
        axial = cylinder * r * r / 2.0 + ends * 0.4 * r * r
        across = cylinder * (3.0 * r * r + h * h) / 12.0 + ends * (
            0.4 * r * r + h * h / 4.0 + 3.0 * h * r / 8.0
        )
        return np.diag([across, across, axial])
