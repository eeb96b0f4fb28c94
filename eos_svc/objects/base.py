"""The abstract object kind: a rigid convex primitive at a pose, and what every kind provides
(``docs/objects.md``). Local frames follow coal's (centred; cylinders and capsules along local z);
SI units; :meth:`SurfaceObject.local_distance` is the one distance implementation.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar

import coal
import numpy as np
import pinocchio as pin

from eos_svc.errors import ValidationError

Array = np.ndarray

#: Points within this distance (m) of a box edge / cylinder rim count as on it.
EDGE_TOLERANCE = 1e-9
#: a length below which a direction or distance counts as zero (m)
TINY = 1e-15


class ObjectSizeError(ValidationError):
    """A non-positive, non-finite or malformed object size (``field`` names it)."""


class CurvatureUndefinedError(ValidationError):
    """The surface is not smooth at the point (edge, corner, rim)."""


def positive(field: str, value: object) -> float:
    """``value`` as a finite length > 0 (m), else :class:`ObjectSizeError` naming ``field``."""
    if isinstance(value, bool):
        raise ObjectSizeError(field, f"must be a number, got {value!r}")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise ObjectSizeError(field, f"must be a number, got {value!r}") from exc
    if not (math.isfinite(v) and v > 0.0):
        raise ObjectSizeError(field, f"must be finite and > 0 m, got {value!r}")
    return v


def positive3(field: str, value: object) -> Array:
    """``value`` as three finite lengths > 0 (m), else :class:`ObjectSizeError` naming the entry."""
    if isinstance(value, (str, bytes)):
        raise ObjectSizeError(field, f"must be a 3-vector, got {value!r}")
    try:
        arr = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ObjectSizeError(field, f"must be a 3-vector, got {value!r}") from exc
    if arr.shape != (3,):
        raise ObjectSizeError(field, f"must be a 3-vector, got shape {arr.shape}")
    return np.array([positive(f"{field}[{i}]", v) for i, v in enumerate(arr.tolist())])


def vector3(field: str, value: object) -> Array:
    """``value`` as a finite 3-vector, else :class:`ValidationError` naming ``field``."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.empty(0)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ValidationError(field, f"must be a finite 3-vector, got {value!r}")
    return arr


def xyz_sum(v: Array) -> Array:
    """x + y + z over the last axis, as ``v.sum(axis=-1)`` (whose reduction over so short an
    axis costs ~6x the two additions on a sweep's points)."""
    out: Array = v[..., 0] + v[..., 1] + v[..., 2]
    return out


def norm(v: Array) -> Array:
    """Euclidean norm over the last axis, of length 3."""
    out: Array = np.sqrt(xyz_sum(v * v))
    return out


def unit(v: Array, n: Array, fallback: Array) -> Array:
    """``v / n`` over the last axis (``n``: the norms, (...,)), ``fallback`` where ``n`` ≈ 0."""
    n = n[..., None]
    out: Array = np.where(n > 1e-12, v / np.maximum(n, 1e-12), fallback)
    return out


def perpendicular_unit(v: Array, axis: Array) -> Array | None:
    """``v`` with its component along unit ``axis`` removed, normalised (None if ~parallel)."""
    w = v - (v @ axis) * axis
    n = float(np.linalg.norm(w))
    return None if n < 1e-6 else w / n


def distinct_units(vectors: list[Array | None], signed: bool) -> list[Array]:
    """The unit ``vectors`` (Nones skipped) without near-repeats (cosine ≥ 0.999; of either sign
    unless ``signed``), in order."""
    out: list[Array] = []
    for v in vectors:
        if v is not None and all((v @ u if signed else abs(v @ u)) < 0.999 for u in out):
            out.append(v)
    return out


def across_axis_units(rotation: Array) -> list[Array]:
    """Distinct closing directions across a solid of revolution's axis (its rotation's third
    column): its frame's x and y, and the parts across the axis of world z and y."""
    axis = rotation[:, 2]
    world_y, world_z = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    return distinct_units(
        [
            rotation[:, 0],
            rotation[:, 1],
            perpendicular_unit(world_z, axis),
            perpendicular_unit(world_y, axis),
        ],
        signed=False,
    )


class SurfaceObject(ABC):
    """A rigid convex object: a primitive shape at ``placement`` (world ← object)."""

    #: the kind's name in the JSON form (``"shape"``)
    kind: ClassVar[str] = ""
    #: the size fields of the JSON form, in order (also the constructor's arguments)
    size_fields: ClassVar[tuple[str, ...]] = ()
    #: how many half sizes the shape fit fits (:attr:`half_sizes`)
    half_size_count: ClassVar[int] = 0
    #: how the shape fit orients the kind: ``"none"`` (a sphere), ``"rotation"`` (a rotation
    #: vector about a start orientation) or ``"axis"`` (an axis tilted from a start axis)
    orientation: ClassVar[str] = "rotation"
    #: the shape fit fits this kind to touches (a primitive with half sizes); False: a mesh
    fittable: ClassVar[bool] = True
    #: a good grasp must also lie about the diameter (the paper's Fig. 2 angle test,
    #: :mod:`eos_svc.drivers.grip_verdict`); False: force closure about the centre of mass decides
    grasp_about_diameter: ClassVar[bool] = True

    _geom: coal.ShapeBase

    def __init__(self, placement: pin.SE3 | None = None) -> None:
        if placement is None:
            placement = pin.SE3.Identity()
        if not isinstance(placement, pin.SE3):
            raise ValidationError("placement", f"must be a pinocchio.SE3, got {type(placement)}")
        self.placement: pin.SE3 = pin.SE3(placement)

    # -- what each kind implements, in its own frame ------------------------------------
    @property
    @abstractmethod
    def half_sizes(self) -> Array:
        """The sizes as the shape fit takes them (m): radii and half lengths."""

    @classmethod
    @abstractmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> SurfaceObject:
        """The object of half sizes ``half`` (see :attr:`half_sizes`)."""

    @abstractmethod
    def sizes(self) -> dict[str, Any]:
        """The size fields of the JSON form (m): ``{field: float or [3 floats]}``."""

    @staticmethod
    @abstractmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        """Signed distance (..., N) and its gradient (..., N, 3) at local points ``P``
        (..., N, 3) of the instances with half sizes ``half`` (..., 1, s)."""

    @property
    def geometry(self) -> coal.ShapeBase:
        """The coal shape (object frame): the ``_geom`` each kind builds."""
        return self._geom

    @property
    @abstractmethod
    def diameter(self) -> float:
        """The diameter of the smallest sphere about the centre that contains the object (m)."""

    @abstractmethod
    def local_half_extent(self, direction: Array) -> float:
        """Distance from the centre to the surface along the unit local ``direction`` (m)."""

    @abstractmethod
    def local_bounds(self, R: Array) -> Array:
        """Half extents (m) along the world axes of the object turned by ``R`` (world ← local)."""

    @abstractmethod
    def _normal_local(self, s: Array) -> Array:
        """Unit outward normal at surface point ``s``."""

    @abstractmethod
    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        """3×3 symmetric S with II(u, v) = uᵀ S v for tangent u, v at ``s`` (1/m)."""

    @abstractmethod
    def drake_shape(self) -> Any:
        """The pydrake.geometry shape (Drake's validation and the MeshCat drawing)."""

    def triangles(self) -> Array | None:
        """The surface's triangles (F, 3, 3), object frame, m, when the kind is made of them
        (a mesh: the flat pictures draw them), else None (a primitive: drawn from its coal shape)."""
        return None

    def drake_collision_shapes(self) -> list[Any]:
        """The pydrake.geometry shapes Drake's contact engine takes, in the object frame
        (default: :meth:`drake_shape`; a mesh: its convex pieces)."""
        return [self.drake_shape()]

    @abstractmethod
    def closing_axes(self) -> list[tuple[str, Array]]:
        """The closing axes (unsigned, world) through the centre of mass for the kind, each
        with a word on it (see :mod:`eos_svc.grasp.frames`)."""

    def approach_options(self, closing: Array) -> list[Array | None]:
        """Approach directions (signed, world, ⟂ ``closing``) of the kind besides the hand's own
        (None where one is parallel to ``closing``): by default the object's axes."""
        A = self.rotation
        return [perpendicular_unit(sign * A[:, i], closing) for i in range(3) for sign in (1.0, -1.0)]

    @property
    @abstractmethod
    def volume(self) -> float:
        """Volume (m³)."""

    @abstractmethod
    def unit_inertia(self) -> Array:
        """Inertia about the centre (object frame) of a solid of unit mass (m², i.e. kg·m²/kg)."""

    # -- JSON form ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], prefix: str = "object") -> SurfaceObject:
        """The object of a JSON form ``{"shape": kind, <size fields>, "position", "rpy"}``
        (position m, rpy rad, both optional: the origin, upright). Errors name the field
        (``prefix.field``) and the reason."""
        allowed = {"shape", "position", "rpy", *cls.size_fields}
        for key in data:
            if key not in allowed:
                raise ValidationError(
                    f"{prefix}.{key}", f"not a field of a {cls.kind} (takes {', '.join(sorted(allowed))})"
                )
        sizes = {}
        for key in cls.size_fields:
            if key not in data:
                raise ValidationError(f"{prefix}.{key}", f"is required for a {cls.kind}")
            sizes[key] = data[key]
        position = vector3(f"{prefix}.position", data.get("position", (0.0, 0.0, 0.0)))
        rpy = vector3(f"{prefix}.rpy", data.get("rpy", (0.0, 0.0, 0.0)))
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rpy), position)
        try:
            return cls(**sizes, placement=placement)
        except ObjectSizeError as exc:
            raise ObjectSizeError(f"{prefix}.{exc.field}", exc.reason) from None

    def to_dict(self) -> dict[str, Any]:
        """The JSON form (:meth:`from_dict` reads it back)."""
        rpy = [0.0, 0.0, 0.0] if self.orientation == "none" else pin.rpy.matrixToRpy(self.rotation).tolist()
        return {"shape": self.kind, **self.sizes(), "position": self.centre.tolist(), "rpy": rpy}

    # -- frames ---------------------------------------------------------------------------
    @property
    def centre(self) -> Array:
        """The centre (world, m)."""
        return np.array(self.placement.translation)

    @property
    def rotation(self) -> Array:
        """world ← object rotation."""
        return np.array(self.placement.rotation)

    def to_local(self, p_world: Array) -> Array:
        """World point(s) (..., 3) → object frame."""
        M = self.placement
        out: Array = (np.asarray(p_world, dtype=float) - M.translation) @ M.rotation
        return out

    def to_world(self, p_local: Array) -> Array:
        """Object-frame point(s) (..., 3) → world."""
        M = self.placement
        out: Array = np.asarray(p_local) @ M.rotation.T + M.translation
        return out

    # -- distance -------------------------------------------------------------------------
    def local_distances(self, P: Array) -> tuple[Array, Array]:
        """Signed distance (N,) m and outward gradient (N, 3) at local points ``P`` (N, 3) of
        this object (default: :meth:`local_distance` at its half sizes)."""
        d, g = self.local_distance(P[None], self.half_sizes[None, None])
        return d[0], g[0]

    def signed_distances(self, points: Array) -> tuple[Array, Array]:
        """(signed distance (N,) m, outward gradient (N, 3) world) at world ``points`` (N, 3)."""
        d, g = self.local_distances(self.to_local(points))
        return d, g @ self.placement.rotation.T

    def _local_closest(self, p_world: Array) -> tuple[Array, Array, float]:
        """(local point, its closest surface point (local), signed distance) of a world point."""
        p = self.to_local(vector3("p_world", p_world))
        d, g = self.local_distances(p[None])
        return p, p - d[0] * g[0], float(d[0])

    def signed_distance(self, p_world: Array) -> float:
        """Signed distance from ``p_world`` to the surface, m (negative inside)."""
        return self._local_closest(p_world)[2]

    def closest_surface_point(self, p_world: Array) -> Array:
        """The surface point closest to ``p_world`` (inside or outside), world, m."""
        return self.to_world(self._local_closest(p_world)[1])

    def closest_point_and_distance(self, p_world: Array) -> tuple[Array, float]:
        """(closest surface point (world, m), signed distance (m, negative inside)) at once."""
        _, s, d = self._local_closest(p_world)
        return self.to_world(s), d

    def surface_normal(self, p_world: Array) -> Array:
        """Unit outward normal (world) at the surface point closest to ``p_world``."""
        out: Array = self.placement.rotation @ self._normal_local(self._local_closest(p_world)[1])
        return out

    # -- extents --------------------------------------------------------------------------
    def half_extent(self, direction: Array) -> float:
        """Distance from the centre to the surface along the unit world ``direction`` (m)."""
        return self.local_half_extent(self.placement.rotation.T @ np.asarray(direction, dtype=float))

    def half_extents(self) -> Array:
        """Half extents of the object's bounds along the world x, y, z axes (m)."""
        return self.local_bounds(self.rotation)

    def depth_below_centre(self) -> float:
        """How far the object reaches below its centre (world −z, m): its lowest point is at
        ``centre[2] − depth_below_centre()`` (a centred primitive: its vertical half extent)."""
        return float(self.half_extents()[2])

    # -- curvature ------------------------------------------------------------------------
    def _local_form(self, p_world: Array) -> tuple[Array, Array]:
        s = self._local_closest(p_world)[1]
        n = self._normal_local(s)
        return n, self._shape_matrix_local(s, n)

    def principal_curvatures(self, p_world: Array) -> tuple[float, float, Array, Array]:
        """(k1, k2, d1, d2) at the surface point closest to ``p_world``: principal curvatures
        k1 ≥ k2 (1/m, positive where the surface bends away from its outward normal) and their
        unit directions in world axes: the eigenpairs of the shape matrix on the tangent plane
        (the normal's own eigenvalue pushed below every other)."""
        n, S = self._local_form(p_world)
        P = np.eye(3) - np.outer(n, n)
        shift = 1.0 + float(np.abs(S).sum())
        w, V = np.linalg.eigh(P @ S @ P - shift * np.outer(n, n))
        R = self.placement.rotation
        return float(w[2]), float(w[1]), R @ V[:, 2], R @ V[:, 1]

    def curvature_form(self, p_world: Array, e1: Array, e2: Array) -> Array:
        """2×2 symmetric second fundamental form II(e_i, e_j) in the tangent basis (e1, e2)
        (world vectors, projected onto the tangent plane), 1/m."""
        n, S = self._local_form(p_world)
        R = self.placement.rotation
        E = R.T @ np.stack([vector3("e1", e1), vector3("e2", e2)], axis=1)
        E = E - np.outer(n, n @ E)
        II = E.T @ S @ E
        out: Array = 0.5 * (II + II.T)
        return out

    # -- mass -----------------------------------------------------------------------------
    def mass_properties(
        self, density: float | None = None, mass: float | None = None
    ) -> tuple[float, Array, Array]:
        """(mass kg, centre of mass (world, m), inertia about it (world axes, kg·m²)) of the
        solid of uniform ``density`` (kg/m³) or of total ``mass`` (kg): give one."""
        if (density is None) == (mass is None):
            raise ValidationError("mass_properties", "give exactly one of density or mass")
        m = positive("mass", mass) if mass is not None else positive("density", density) * self.volume
        R = self.rotation
        return m, self.centre, m * (R @ self.unit_inertia() @ R.T)

    def __repr__(self) -> str:
        t = self.placement.translation
        return f"{type(self).__name__}(diameter={self.diameter:.4g} m, at {np.round(t, 4)})"
