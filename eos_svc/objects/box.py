"""The box: ``{"shape": "box", "size": [x, y, z]}`` (full side lengths), centred. Its faces
are flat (zero curvature); normals and curvatures on edges and corners raise
:class:`~eos_svc.objects.base.CurvatureUndefinedError`."""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from eos_svc.objects.base import (
    EDGE_TOLERANCE,
    TINY,
    Array,
    CurvatureUndefinedError,
    SurfaceObject,
    norm,
    positive3,
)


class Box(SurfaceObject):
    """Box with full side lengths ``size`` (x, y, z) m, centred."""

    kind = "box"
    size_fields = ("size",)
    half_size_count = 3
    orientation = "rotation"

    def __init__(self, size: ArrayLike, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.size = positive3("size", size)
        self._half = 0.5 * self.size
        self._geom = coal.Box(*self.size)

    @property
    def half_sizes(self) -> Array:
        return self._half.copy()

    @classmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> Box:
        return cls(2.0 * np.asarray(half, dtype=float), placement)

    def sizes(self) -> dict[str, Any]:
        return {"size": self.size.tolist()}

    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """With ``q = |p| − h``: outside ``‖max(q, 0)‖``, gradient along ``sign(p)·max(q, 0)``;
        inside ``max q`` (negative), gradient the normal of the nearest face (the first of equals)."""
        q = np.abs(P) - half
        qp = np.maximum(q, 0.0)
        out = norm(qp)
        d = out + np.minimum(q.max(axis=-1), 0.0)
        sign = np.where(P >= 0.0, 1.0, -1.0)
        g_out = sign * qp / np.maximum(out, TINY)[..., None]
        g_in = np.where(q.argmax(axis=-1)[..., None] == np.arange(3), sign, 0.0)
        return d, np.where((out > TINY)[..., None], g_out, g_in)

    @property
    def diameter(self) -> float:
        return float(np.linalg.norm(self.size))

    def local_half_extent(self, direction: Array) -> float:
        d = np.abs(direction)
        return float(np.min(self._half[d > 0] / d[d > 0]))

    def local_bounds(self, R: Array) -> Array:
        out: Array = np.abs(R) @ self._half
        return out

    def _normal_local(self, s: Array) -> Array:
        h = self._half
        tol = EDGE_TOLERANCE + 1e-12 * float(h.max())
        faces = np.flatnonzero(np.abs(np.abs(s) - h) <= tol)
        if len(faces) != 1:
            raise CurvatureUndefinedError(
                "p_world", "the point is on a box edge or corner; normal and curvature undefined"
            )
        n = np.zeros(3)
        n[faces[0]] = math.copysign(1.0, s[faces[0]])
        return n

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        return np.zeros((3, 3))

    def drake_shape(self) -> Any:
        from pydrake.geometry import Box as DrakeBox

        return DrakeBox(*self.size)

    def closing_axes(self) -> list[tuple[str, Array]]:
        """Across each pair of opposite faces."""
        A = self.rotation
        return [(f"across faces {name}", A[:, i]) for i, name in enumerate(("±x", "±y", "±z"))]

    @property
    def volume(self) -> float:
        return float(np.prod(self.size))

    def unit_inertia(self) -> Array:
        """``diag(y² + z², x² + z², x² + y²) / 12``."""
        x2, y2, z2 = self.size**2
        out: Array = np.diag([y2 + z2, x2 + z2, x2 + y2]) / 12.0
        return out
