"""Objects to grasp: coal primitives at a pose with their analytic differential geometry.

Every object gives, at any surface point (world coordinates, m), the unit outward normal,
the principal curvatures (1/m, ≥ 0 for these convex shapes) and directions, and the second
fundamental form in any tangent basis — the ground truth for EP1's curvature estimate.

Local frames (coal's conventions): every shape is centred at its placement's origin;
cylinders and capsules have their axis along local z, ``length`` being the length of the
straight part (a capsule's total length is ``length + 2·radius``); ``Box(size)`` takes full
side lengths.

Where the curvature is not defined (box edges and corners, cylinder rims) a
:class:`CurvatureUndefinedError` is raised.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .geometry import tangent_basis
from .hand import KinematicsError

__all__ = [
    "Box",
    "Capsule",
    "CurvatureUndefinedError",
    "Cylinder",
    "Ellipsoid",
    "ObjectSizeError",
    "Sphere",
    "SurfaceObject",
]

#: Points within this distance (m) of a box edge / cylinder rim count as on it.
EDGE_TOLERANCE = 1e-9


class ObjectSizeError(KinematicsError):
    """A non-positive, non-finite or malformed object size."""


class CurvatureUndefinedError(KinematicsError):
    """The surface is not smooth at the point (edge, corner, rim)."""


def _positive(field: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise ObjectSizeError(field, f"must be a number, got {value!r}") from exc
    if not (math.isfinite(v) and v > 0.0):
        raise ObjectSizeError(field, f"must be finite and > 0 m, got {value!r}")
    return v


def _positive3(field: str, value: object) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ObjectSizeError(field, f"must be a 3-vector, got {value!r}") from exc
    if arr.shape != (3,):
        raise ObjectSizeError(field, f"must be a 3-vector, got shape {arr.shape}")
    for i, v in enumerate(arr):
        if not (math.isfinite(v) and v > 0.0):
            raise ObjectSizeError(f"{field}[{i}]", f"must be finite and > 0 m, got {v!r}")
    return arr


def _point(field: str, p: object) -> np.ndarray:
    arr = np.asarray(p, dtype=float)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise KinematicsError(field, f"must be a finite 3-vector, got {p!r}")
    return arr


class SurfaceObject(ABC):
    """A rigid convex object: a coal shape at ``placement`` (world ← object)."""

    kind: str = ""

    def __init__(self, placement: pin.SE3 | None = None) -> None:
        if placement is None:
            placement = pin.SE3.Identity()
        if not isinstance(placement, pin.SE3):
            raise KinematicsError("placement", f"must be a pinocchio.SE3, got {type(placement)}")
        self.placement: pin.SE3 = pin.SE3(placement)

    # -- to implement, everything in the object frame
    @property
    @abstractmethod
    def geometry(self) -> coal.ShapeBase:
        """The coal shape (object frame)."""

    @property
    @abstractmethod
    def diameter(self) -> float:
        """Characteristic size for d/h: the diameter of the smallest sphere about the object's
        centre that contains it (a sphere: 2R), m."""

    @abstractmethod
    def _project_local(self, p: np.ndarray) -> np.ndarray:
        """Closest surface point to p (object frame)."""

    @abstractmethod
    def _normal_local(self, s: np.ndarray) -> np.ndarray:
        """Unit outward normal at surface point s (object frame)."""

    @abstractmethod
    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        """3×3 symmetric S with II(u, v) = uᵀ S v for tangent u, v at s (object frame)."""

    @abstractmethod
    def _signed_distance_local(self, p: np.ndarray) -> float:
        """Signed distance from p to the surface (negative inside), object frame."""

    # -- world-frame API
    def to_local(self, p_world: np.ndarray) -> np.ndarray:
        """World point → object frame."""
        M = self.placement
        out: np.ndarray = M.rotation.T @ (np.asarray(p_world, dtype=float) - M.translation)
        return out

    def to_world(self, p_local: np.ndarray) -> np.ndarray:
        """Object-frame point → world."""
        M = self.placement
        out: np.ndarray = M.rotation @ p_local + M.translation
        return out

    def closest_surface_point(self, p_world: np.ndarray) -> np.ndarray:
        """The surface point closest to ``p_world`` (inside or outside), world, m."""
        return self.to_world(self._project_local(self.to_local(_point("p_world", p_world))))

    def signed_distance(self, p_world: np.ndarray) -> float:
        """Signed distance from ``p_world`` to the surface, m (negative inside)."""
        return self._signed_distance_local(self.to_local(_point("p_world", p_world)))

    def closest_point_and_distance(self, p_world: np.ndarray) -> tuple[np.ndarray, float]:
        """(closest surface point (world, m), signed distance (m, negative inside)) at once."""
        p = self.to_local(_point("p_world", p_world))
        s = self._project_local(p)
        return self.to_world(s), self._signed_distance_from(p, s)

    def _signed_distance_from(self, p: np.ndarray, s: np.ndarray) -> float:
        """Signed distance of local p given its closest surface point s."""
        return self._signed_distance_local(p)

    def surface_normal(self, p_world: np.ndarray) -> np.ndarray:
        """Unit outward normal (world) at the surface point closest to ``p_world``."""
        s = self._project_local(self.to_local(_point("p_world", p_world)))
        out: np.ndarray = self.placement.rotation @ self._normal_local(s)
        return out

    def _local_form(self, p_world: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = self._project_local(self.to_local(_point("p_world", p_world)))
        n = self._normal_local(s)
        return s, n, self._shape_matrix_local(s, n)

    def principal_curvatures(
        self, p_world: np.ndarray
    ) -> tuple[float, float, np.ndarray, np.ndarray]:
        """(k1, k2, d1, d2) at the surface point closest to ``p_world``: principal curvatures
        k1 ≥ k2 (1/m, positive where the surface bends away from its outward normal) and their
        unit directions in world axes."""
        _, n, S = self._local_form(p_world)
        e1, e2 = tangent_basis(n)
        E = np.stack([e1, e2], axis=1)  # 3×2
        II = E.T @ S @ E
        w, V = np.linalg.eigh(0.5 * (II + II.T))
        R = self.placement.rotation
        d1 = R @ (E @ V[:, 1])
        d2 = R @ (E @ V[:, 0])
        return float(w[1]), float(w[0]), d1, d2

    def curvature_form(self, p_world: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
        """2×2 symmetric second fundamental form II(e_i, e_j) in the tangent basis (e1, e2)
        (world vectors, projected onto the tangent plane), 1/m."""
        _, n, S = self._local_form(p_world)
        R = self.placement.rotation
        E = R.T @ np.stack([_point("e1", e1), _point("e2", e2)], axis=1)
        E = E - np.outer(n, n @ E)
        II = E.T @ S @ E
        out: np.ndarray = 0.5 * (II + II.T)
        return out

    def __repr__(self) -> str:
        t = self.placement.translation
        return f"{type(self).__name__}(diameter={self.diameter:.4g} m, at {np.round(t, 4)})"


class Sphere(SurfaceObject):
    """Sphere of ``radius`` m."""

    kind = "sphere"

    def __init__(self, radius: float, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radius = _positive("radius", radius)
        self._geom = coal.Sphere(self.radius)

    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return 2.0 * self.radius

    def _project_local(self, p: np.ndarray) -> np.ndarray:
        r = np.linalg.norm(p)
        if r < 1e-15:
            return np.array([0.0, 0.0, self.radius])
        out: np.ndarray = p * (self.radius / r)
        return out

    def _normal_local(self, s: np.ndarray) -> np.ndarray:
        out: np.ndarray = s / np.linalg.norm(s)
        return out

    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        return np.eye(3) / self.radius

    def _signed_distance_local(self, p: np.ndarray) -> float:
        return float(np.linalg.norm(p) - self.radius)


class Ellipsoid(SurfaceObject):
    """Ellipsoid with semi-axes ``radii`` (a, b, c) m along the local x, y, z axes."""

    kind = "ellipsoid"

    def __init__(self, radii: ArrayLike,
                 placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radii = _positive3("radii", radii)
        self._geom = coal.Ellipsoid(*self.radii)

    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return float(2.0 * self.radii.max())

    def _project_local(self, p: np.ndarray) -> np.ndarray:
        # Closest point x_i = a_i² p_i / (t + a_i²) with t the root of
        # F(t) = Σ (a_i p_i / (t + a_i²))² − 1 on t > −min a_i², where F decreases
        # monotonically: safeguarded Newton in plain floats (numpy on 3-vectors is slow).
        a = self.radii.tolist()
        x = p.tolist()
        a2 = [ai * ai for ai in a]
        if sum((xi / ai) ** 2 for xi, ai in zip(x, a, strict=True)) < 1e-24:
            i = int(np.argmin(self.radii))  # the centre: nearest is the end of the shortest axis
            out = np.zeros(3)
            out[i] = a[i]
            return out

        def f(t: float) -> tuple[float, float]:
            val, der = -1.0, 0.0
            for ai, a2i, xi in zip(a, a2, x, strict=True):
                den = t + a2i
                u = ai * xi / den
                val += u * u
                der -= 2.0 * u * u / den
            return val, der

        k_min = int(np.argmin(self.radii))
        lo = -a2[k_min]
        # Start left of the root (F > 0): Newton on a convex decreasing F then rises
        # monotonically to the root. Outside points: t = 0. Inside points: walk toward lo.
        t = 0.0
        if f(t)[0] <= 0.0:
            gap = -lo
            for _ in range(40):
                gap *= 0.25
                if gap < 1e-9 * -lo:  # root too close to the pole: treat as degenerate
                    gap = 0.0
                    break
                if f(lo + gap)[0] > 0.0:
                    break
            if gap == 0.0:  # no root in (lo, 0]: p on the shortest axis' plane (degenerate)
                xs = [
                    a2i * xi / (a2i - a2[k_min]) if a2i != a2[k_min] else 0.0
                    for a2i, xi in zip(a2, x, strict=True)
                ]
                rad = 1.0 - sum((xi / ai) ** 2 for xi, ai in zip(xs, a, strict=True))
                xs[k_min] = math.copysign(a[k_min] * math.sqrt(max(rad, 0.0)), x[k_min] or 1.0)
                return np.array(xs)
            t = lo + gap
        for _ in range(100):
            val, der = f(t)
            if val <= 1e-15 or der >= 0.0:
                break
            t -= val / der
        s = [a2i * xi / (t + a2i) for a2i, xi in zip(a2, x, strict=True)]
        k = math.sqrt(sum((si / ai) ** 2 for si, ai in zip(s, a, strict=True)))
        return np.array([si / k for si in s])  # exactly on the surface

    def _normal_local(self, s: np.ndarray) -> np.ndarray:
        g = s / self.radii**2
        out: np.ndarray = g / np.linalg.norm(g)
        return out

    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        # Implicit F = Σ x_i²/a_i² - 1: II(u, v) = uᵀ ∇²F v / |∇F| for tangent u, v.
        grad = 2.0 * s / self.radii**2
        out: np.ndarray = np.diag(2.0 / self.radii**2) / np.linalg.norm(grad)
        return out

    def _signed_distance_local(self, p: np.ndarray) -> float:
        return self._signed_distance_from(p, self._project_local(p))

    def _signed_distance_from(self, p: np.ndarray, s: np.ndarray) -> float:
        d = float(np.linalg.norm(p - s))
        return -d if np.sum((p / self.radii) ** 2) < 1.0 else d


class Cylinder(SurfaceObject):
    """Cylinder of ``radius`` m and ``length`` m along local z, centred (flat caps)."""

    kind = "cylinder"

    def __init__(self, radius: float, length: float, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radius = _positive("radius", radius)
        self.length = _positive("length", length)
        self._geom = coal.Cylinder(self.radius, self.length)

    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return math.hypot(2.0 * self.radius, self.length)

    def _project_local(self, p: np.ndarray) -> np.ndarray:
        R, hz = self.radius, 0.5 * self.length
        rho = math.hypot(p[0], p[1])
        ex, ey = (p[0] / rho, p[1] / rho) if rho > 1e-15 else (1.0, 0.0)
        if rho <= R and abs(p[2]) <= hz:  # inside: nearest of side or caps
            if R - rho < hz - abs(p[2]):
                return np.array([R * ex, R * ey, p[2]])
            return np.array([p[0], p[1], math.copysign(hz, p[2]) if p[2] != 0 else hz])
        rc = min(rho, R)
        return np.array([rc * ex, rc * ey, min(max(p[2], -hz), hz)])

    def _region(self, s: np.ndarray) -> str:
        R, hz = self.radius, 0.5 * self.length
        tol = EDGE_TOLERANCE + 1e-12 * max(R, hz)
        on_side = abs(math.hypot(s[0], s[1]) - R) <= tol
        on_cap = abs(abs(s[2]) - hz) <= tol
        if on_side and on_cap:
            raise CurvatureUndefinedError(
                "p_world", "the point is on a cylinder rim; normal and curvature are undefined"
            )
        return "side" if on_side else "cap"

    def _normal_local(self, s: np.ndarray) -> np.ndarray:
        if self._region(s) == "side":
            rho = math.hypot(s[0], s[1])
            return np.array([s[0] / rho, s[1] / rho, 0.0])
        return np.array([0.0, 0.0, math.copysign(1.0, s[2])])

    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        if self._region(s) == "cap":
            return np.zeros((3, 3))
        t = np.array([-n[1], n[0], 0.0])
        out: np.ndarray = np.outer(t, t) / self.radius
        return out

    def _signed_distance_local(self, p: np.ndarray) -> float:
        dr = math.hypot(p[0], p[1]) - self.radius
        dz = abs(p[2]) - 0.5 * self.length
        if dr <= 0 and dz <= 0:
            return max(dr, dz)
        return math.hypot(max(dr, 0.0), max(dz, 0.0))


class Capsule(SurfaceObject):
    """Capsule: a cylinder of ``radius`` m with straight part ``length`` m along local z,
    capped by hemispheres (total length ``length + 2·radius``)."""

    kind = "capsule"

    def __init__(self, radius: float, length: float, placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.radius = _positive("radius", radius)
        self.length = _positive("length", length)
        self._geom = coal.Capsule(self.radius, self.length)

    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return self.length + 2.0 * self.radius

    def _axis_point(self, p: np.ndarray) -> np.ndarray:
        hz = 0.5 * self.length
        return np.array([0.0, 0.0, min(max(p[2], -hz), hz)])

    def _project_local(self, p: np.ndarray) -> np.ndarray:
        c = self._axis_point(p)
        d = p - c
        r = float(np.linalg.norm(d))
        if r < 1e-15:
            d, r = np.array([1.0, 0.0, 0.0]), 1.0
        out: np.ndarray = c + d * (self.radius / r)
        return out

    def _normal_local(self, s: np.ndarray) -> np.ndarray:
        d = s - self._axis_point(s)
        out: np.ndarray = d / np.linalg.norm(d)
        return out

    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        if abs(s[2]) > 0.5 * self.length:  # hemispherical cap
            return np.eye(3) / self.radius
        t = np.array([-n[1], n[0], 0.0])
        out: np.ndarray = np.outer(t, t) / self.radius
        return out

    def _signed_distance_local(self, p: np.ndarray) -> float:
        return float(np.linalg.norm(p - self._axis_point(p)) - self.radius)


class Box(SurfaceObject):
    """Box with full side lengths ``size`` (x, y, z) m, centred. Faces are flat (zero
    curvature); normals and curvatures on edges and corners raise
    :class:`CurvatureUndefinedError`."""

    kind = "box"

    def __init__(self, size: ArrayLike,
                 placement: pin.SE3 | None = None) -> None:
        super().__init__(placement)
        self.size = _positive3("size", size)
        self._half = 0.5 * self.size
        self._geom = coal.Box(*self.size)

    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return float(np.linalg.norm(self.size))

    def _project_local(self, p: np.ndarray) -> np.ndarray:
        h = self._half
        if np.all(np.abs(p) <= h):  # inside: push to the nearest face
            i = int(np.argmin(h - np.abs(p)))
            s = p.copy()
            s[i] = math.copysign(h[i], p[i]) if p[i] != 0 else h[i]
            return s
        out: np.ndarray = np.clip(p, -h, h)
        return out

    def _normal_local(self, s: np.ndarray) -> np.ndarray:
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

    def _shape_matrix_local(self, s: np.ndarray, n: np.ndarray) -> np.ndarray:
        return np.zeros((3, 3))

    def _signed_distance_local(self, p: np.ndarray) -> float:
        q = np.abs(p) - self._half
        outside = np.linalg.norm(np.maximum(q, 0.0))
        return float(outside + min(q.max(), 0.0))
