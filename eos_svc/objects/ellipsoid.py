"""The ellipsoid: ``{"shape": "ellipsoid", "radii": [a, b, c]}``, semi-axes along local x, y, z."""

from __future__ import annotations

import math
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from eos_svc.objects.base import Array, SurfaceObject, norm, positive3, unit, xyz_sum

_UP = np.array([0.0, 0.0, 1.0])
#: Newton iterations at most, and the relative step that ends them
ITERATIONS, STEP_TOLERANCE = 30, 1e-12


def closest_points(P: Array, a: Array) -> Array:
    """The closest points (..., N, 3) on the ellipsoids of semi-axes ``a`` (..., 1, 3) to the
    local points ``P`` (..., N, 3).

    The closest point is ``s_i = a_i² p_i / (t + a_i²)`` with ``t`` the root of
    ``F(t) = Σ (a_i p_i / (t + a_i²))² − 1`` on ``t > −min a_i²``. Written ``h(t) = 1`` with
    ``h = (F + 1)^(−1/2)`` — a power mean of exponent −2 of the affine ``t + a_i²``, increasing
    and concave — Newton's method from a point left of the root stays left of it and rises
    monotonically to it (in one step for a sphere). Every term of ``F`` is at most 1 at the
    root, so ``t ≥ a_i |p_i| − a_i²``; and ``t ≥ 0`` outside. An inside point whose ``F`` is
    negative already at the pole ``t = −min a_i²`` (on the shortest axis' plane, near the
    centre) has no root: its closest point lies at the pole, off that plane."""
    a2 = a * a
    inside = xyz_sum((P / a) ** 2) < 1.0
    pole = -a2.min(axis=-1) * (1.0 - 1e-12)
    low = a * np.abs(P) - a2  # each term's bound on t, the greatest of the three below
    t = np.maximum(np.maximum(np.maximum(low[..., 0], low[..., 1]), low[..., 2]), np.where(inside, pole, 0.0))
    ap2 = (a * P) ** 2
    for _ in range(ITERATIONS):
        inv = 1.0 / (t[..., None] + a2)
        terms = ap2 * inv * inv  # (a_i p_i / (t + a_i²))²
        total = xyz_sum(terms)  # F + 1 = h⁻²
        slope = xyz_sum(terms * inv)  # h' h⁻³
        step = total * (np.sqrt(total) - 1.0) / np.maximum(slope, 1e-300)  # (1 − h) / h'
        t_next = np.maximum(t + step, pole)
        # converged where t no longer moves (a point held at the pole moves no more either)
        settled = (np.abs(t_next - t) <= STEP_TOLERANCE * (1e-6 + np.abs(t_next))).all()
        t = t_next
        if settled:
            break
    S = a2 * P / (t[..., None] + a2)
    at_pole = inside & (t <= pole)
    if at_pole.any():
        S = np.where(at_pole[..., None], _pole_points(P, np.broadcast_to(a, P.shape)), S)
    out: Array = S / np.sqrt(xyz_sum((S / a) ** 2))[..., None]  # exactly on the surface
    return out


def _pole_points(P: Array, a: Array) -> Array:
    """The closest points of inside points with no root right of the pole ``t = −a_k²`` (k the
    shortest axis; near the centre, on or next to the plane ``p_k = 0``): ``s_i = a_i² p_i /
    (a_i² − a_k²)`` off that axis, ``s_k`` from the surface equation, on ``p_k``'s side (where a
    root is left right of the pole after all, the root's point)."""
    a2 = a * a
    k = np.argmin(a, axis=-1)[..., None]
    off = a2 - np.take_along_axis(a2, k, axis=-1)
    s_off = np.where(off > 0.0, a2 * P / np.where(off > 0.0, off, 1.0), 0.0)
    rest = 1.0 - xyz_sum(np.where(off > 0.0, (s_off / a) ** 2, 0.0))
    p_k = np.take_along_axis(P, k, axis=-1)[..., 0]
    a_k = np.take_along_axis(a, k, axis=-1)[..., 0]
    s_k = np.where(p_k < 0.0, -1.0, 1.0) * a_k * np.sqrt(np.maximum(rest, 0.0))
    return np.where(np.arange(3) == k, s_k[..., None], s_off)


class Ellipsoid(SurfaceObject):
    """Ellipsoid with semi-axes ``radii`` (a, b, c) m along the local x, y, z axes."""

    kind = "ellipsoid"
    size_fields = ("radii",)
    half_size_count = 3
    orientation = "rotation"

    def __init__(self, radii: ArrayLike, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radii = positive3("radii", radii)
        self._geom = coal.Ellipsoid(*self.radii)

    @property
    def half_sizes(self) -> Array:
        return self.radii.copy()

    @classmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> Ellipsoid:
        return cls(np.asarray(half, dtype=float), placement)

    def sizes(self) -> dict[str, Any]:
        return {"radii": self.radii.tolist()}

    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """The distance to the exact closest point (:func:`closest_points`), negative inside;
        the gradient along ``p − s`` (the normal at ``s`` on the surface)."""
        S = closest_points(P, half)
        v = P - S
        dist = norm(v)
        sign = np.where(xyz_sum((P / half) ** 2) < 1.0, -1.0, 1.0)
        g = sign[..., None] * v / np.maximum(dist, 1e-12)[..., None]
        on = dist <= 1e-12  # on the surface: the normal there (made only where needed)
        if on.any():
            normal = S / half**2
            g = np.where(on[..., None], unit(normal, norm(normal), _UP), g)
        return sign * dist, g

    @property
    def diameter(self) -> float:
        return float(2.0 * self.radii.max())

    def local_half_extent(self, direction: Array) -> float:
        """Exact: the ray meets x²/a² + y²/b² + z²/c² = 1."""
        return float(1.0 / np.linalg.norm(direction / self.radii))

    def local_bounds(self, R: Array) -> Array:
        out: Array = np.sqrt((R**2) @ (self.radii**2))
        return out

    def _normal_local(self, s: Array) -> Array:
        g = s / self.radii**2
        out: Array = g / np.linalg.norm(g)
        return out

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        # implicit F = Σ x_i²/a_i² − 1: II(u, v) = uᵀ ∇²F v / |∇F| for tangent u, v
        grad = 2.0 * s / self.radii**2
        out: Array = np.diag(2.0 / self.radii**2) / np.linalg.norm(grad)
        return out

    def drake_shape(self) -> Any:
        from pydrake.geometry import Ellipsoid as DrakeEllipsoid

        return DrakeEllipsoid(*self.radii)

    def closing_axes(self) -> list[tuple[str, Array]]:
        """Across its two shorter axes."""
        A, order = self.rotation, np.argsort(self.radii)
        words = ("shortest", "middle")
        return [(f"across its {w} axis", A[:, int(i)]) for w, i in zip(words, order[:2], strict=True)]

    @property
    def volume(self) -> float:
        return 4.0 / 3.0 * math.pi * float(np.prod(self.radii))

    def unit_inertia(self) -> Array:
        """``diag(b² + c², a² + c², a² + b²) / 5``."""
        a2, b2, c2 = self.radii**2
        return np.diag([b2 + c2, a2 + c2, a2 + b2]) / 5.0
