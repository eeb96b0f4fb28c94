"""Grasp quality: force closure under Coulomb friction and the Ferrari–Canny ε metric.

Pure NumPy/SciPy (no Pinocchio): contacts in, a :class:`GraspQuality` out.

Conventions
-----------
- Contacts are hard-finger point contacts (no torsional friction). Each contact ``i`` has a
  point ``p_i`` on the object and the object's *outward* unit surface normal ``n_i`` (object
  → fingertip, as :class:`~eos_svc.kinematics.Contact` reports it). The finger pushes along
  ``−n_i``.
- The Coulomb cone of half-angle ``atan μ`` is linearised by ``m`` edges (3-D contacts)::

      f_ij = −n_i + μ (cos θ_j t1_i + sin θ_j t2_i),   θ_j = 2π j / m,  j = 0 … m−1

  (a unit normal component; an inner approximation of the cone). In the plane (2-D points)
  the cone has exactly two edges ``−n_i ± μ t_i`` — no approximation. With μ = 0 each
  contact gives the one wrench along its normal.
- Primitive wrenches ``w_ij = [f_ij ; (p_i − c) × f_ij / L]`` with torques about the
  object's centre ``c`` divided by a characteristic length ``L`` (default: the largest
  contact distance from ``c``; the planner uses the object's half diameter, the radius of a
  sphere), so forces and scaled torques share units. In 3-D, wrenches are 6-vectors; in 2-D,
  ``(f_x, f_y, τ_z / L)``.
- **Force closure** ⇔ the origin is strictly inside the convex hull ``W`` of the primitive
  wrenches (equivalently: they positively span wrench space).
- **ε (Ferrari–Canny, "Q1")** = radius of the largest origin-centred ball inside ``W`` =
  min over hull facets of the origin's distance to the facet plane; 0 when the grasp is not
  in force closure. It is the smallest wrench (force units, torque/L) the grasp can resist in
  its worst direction when the contact normal forces sum to 1. ε is invariant to translating
  the whole grasp, scales with the torque convention, and grows with μ.
- Degenerate inputs (no contacts, coincident/collinear/coplanar contact sets, μ = 0 on a
  sphere…) give a wrench set of rank below the wrench-space dimension: no force closure,
  ε = 0, never an exception. Malformed inputs (wrong shapes, NaN, μ < 0, zero normals) raise
  :class:`~eos_svc.errors.ValidationError` (a ``ValueError``) naming the argument.

Closed forms checked by the tests: two antipodal contacts on a disc of radius ``r`` (2-D,
``L = r``) have ``ε = μ / √(2 + μ²)``; any frictionless grasp of a sphere, and any set of at
most six frictionless contacts in 3-D, is not in force closure; two antipodal hard contacts
in 3-D never are (the torque about the line through them is unresisted), three contacts at
120° on a sphere's equator are for every μ > 0.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull, QhullError

from eos_svc.errors import ValidationError
from eos_svc.kinematics.geometry import tangent_basis
from eos_svc.schema.request import DEFAULT_FRICTION, MAX_FRICTION

__all__ = [
    "DEFAULT_EDGES",
    "DEFAULT_FRICTION",
    "GraspQuality",
    "contacts_quality",
    "epsilon_of_wrenches",
    "grasp_quality",
    "primitive_wrenches",
]

#: default number of edges of a linearised 3-D friction cone
DEFAULT_EDGES = 8
#: ε below this counts as zero (origin on the hull boundary: no force closure)
EPSILON_TOL = 1e-9


@dataclass(frozen=True)
class GraspQuality:
    """Quality of a set of contacts.

    Attributes:
        force_closure: the contacts can resist any wrench (origin strictly inside the hull).
        epsilon: Ferrari–Canny ε (0 without force closure); force units per unit total
            normal force, torques divided by ``torque_scale``.
        friction: Coulomb coefficient μ used.
        edges: edges per linearised friction cone (2 in the plane, 1 per contact at μ = 0).
        torque_scale: characteristic length L dividing the torques (m).
        contacts: number of contacts.
        rank: rank of the primitive wrench set (6 in 3-D, 3 in 2-D needed for closure).
        dimension: wrench-space dimension (6 or 3).
    """

    force_closure: bool
    epsilon: float
    friction: float
    edges: int
    torque_scale: float
    contacts: int
    rank: int
    dimension: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form: the fields in order (all scalars; ``dataclasses.asdict``'s
        recursive copy cost ≈ 40 µs a plan for the same dict)."""
        return {name: getattr(self, name) for name in _QUALITY_FIELDS}


#: GraspQuality's field names, in order
_QUALITY_FIELDS = tuple(f.name for f in fields(GraspQuality))


def _array(value: ArrayLike, name: str) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValidationError(name, "must be an array of numbers") from None
    if not np.all(np.isfinite(a)):
        raise ValidationError(name, "must be finite")
    return a


def check_friction(mu: object, name: str = "friction") -> float:
    """Validate a Coulomb friction coefficient: a finite number in [0, MAX_FRICTION]."""
    if isinstance(mu, bool) or not isinstance(mu, (int, float, np.floating, np.integer)):
        raise ValidationError(name, f"must be a number, got {type(mu).__name__}")
    v = float(mu)
    if not (math.isfinite(v) and 0.0 <= v <= MAX_FRICTION):
        raise ValidationError(name, f"must be in [0, {MAX_FRICTION}], got {v!r}")
    return v


def primitive_wrenches(
    points: ArrayLike,
    normals: ArrayLike,
    centre: ArrayLike | None = None,
    mu: float = DEFAULT_FRICTION,
    edges: int = DEFAULT_EDGES,
    torque_scale: float | None = None,
) -> tuple[np.ndarray, float, int]:
    """The primitive contact wrenches (see the module docstring for the convention).

    Args:
        points: (k, 3) or (k, 2) contact points on the object (m).
        normals: same shape: outward surface normals (need not be unit length).
        centre: torque reference, the object's centre (default: the contacts' centroid).
        mu: Coulomb friction coefficient (≥ 0).
        edges: edges per linearised 3-D cone (≥ 3; ignored in 2-D).
        torque_scale: characteristic length L (default: the largest ``‖p_i − c‖``, or 1).

    Returns:
        (wrenches of shape (k·m, 6) or (k·m, 3), the torque scale used, edges per contact).

    Raises:
        ValueError: naming the malformed argument.
    """
    p = _array(points, "points")
    n = _array(normals, "normals")
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValidationError("points", f"must have shape (k, 3) or (k, 2), got {p.shape}")
    if n.shape != p.shape:
        raise ValidationError("normals", f"must have the shape of points {p.shape}, got {n.shape}")
    dim = p.shape[1]
    mu = check_friction(mu, "mu")
    if isinstance(edges, bool) or not isinstance(edges, (int, np.integer)) or edges < 3:
        raise ValidationError("edges", f"must be an integer ≥ 3, got {edges!r}")
    lengths = np.linalg.norm(n, axis=1)
    if np.any(lengths < 1e-12):
        raise ValidationError("normals", "every normal must be non-zero")
    n = n / lengths[:, None]
    centroid = np.mean(p, axis=0) if len(p) else np.zeros(dim)
    c = centroid if centre is None else _array(centre, "centre")
    if c.shape != (dim,):
        raise ValidationError("centre", f"must have {dim} coordinates, got shape {c.shape}")
    r = p - c
    if torque_scale is None:
        far = float(np.max(np.linalg.norm(r, axis=1))) if len(r) else 0.0
        scale = far if far > 1e-12 else 1.0
    else:
        scale = float(_array(torque_scale, "torque_scale"))
        if scale <= 0.0:
            raise ValidationError("torque_scale", f"must be > 0, got {scale!r}")
    m = 1 if mu == 0.0 else (2 if dim == 2 else int(edges))
    forces = np.empty((len(p), m, dim))
    if dim == 3:
        # the cone's edge directions, the same for every contact (computed once)
        theta = 2.0 * np.pi * np.arange(m) / m
        cos_t, sin_t = np.cos(theta)[:, None], np.sin(theta)[:, None]
        for i, ni in enumerate(n):
            if m == 1:
                forces[i, 0] = -ni
                continue
            t1, t2 = tangent_basis(ni)
            forces[i] = -ni + mu * (cos_t * t1 + sin_t * t2)
        torques = cross_rows(r, forces) / scale
    else:
        t = np.stack([-n[:, 1], n[:, 0]], axis=1)
        signs = np.array([1.0]) if m == 1 else np.array([1.0, -1.0])
        forces = -n[:, None, :] + mu * signs[None, :, None] * t[:, None, :]
        torques = (r[:, None, 0] * forces[..., 1] - r[:, None, 1] * forces[..., 0])[..., None] / scale
    wrenches = np.concatenate([forces, torques], axis=2).reshape(len(p) * m, 6 if dim == 3 else 3)
    return wrenches, scale, m


def cross_rows(r: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """``np.cross(r[:, None, :], forces)`` of (k, 3) lever arms and (k, m, 3) forces, bit for
    bit (numpy forms each component as the same two products and their difference), without
    its axis shuffling (a tenth of a millisecond per grasp)."""
    a = r[:, None, :]
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = forces[..., 0], forces[..., 1], forces[..., 2]
    out: np.ndarray = np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)
    return out


def epsilon_of_wrenches(wrenches: ArrayLike) -> tuple[float, int]:
    """Ferrari–Canny ε of a primitive wrench set, and the set's rank.

    0 when the origin is not strictly inside the convex hull (including rank-deficient and
    empty sets). Never raises on degenerate geometry.
    """
    w = np.asarray(wrenches, dtype=float)
    if w.ndim != 2 or len(w) == 0:
        return 0.0, 0
    dim = w.shape[1]
    size = float(np.max(np.abs(w)))
    # np.linalg.matrix_rank(w, tol) without its dispatch: singular values above tol
    tol = 1e-9 * max(size, 1.0)
    rank = int(np.count_nonzero(np.linalg.svd(w, compute_uv=False) > tol)) if size > 0 else 0
    if rank < dim or len(w) <= dim:
        return 0.0, rank
    try:
        hull = ConvexHull(w)
    except (QhullError, ValueError):
        return 0.0, rank
    # equations: unit outward normal a and offset b with a·x + b ≤ 0 inside; the origin's
    # distance to a facet plane is −b (positive when the origin is on the inner side).
    distance = float(np.min(-hull.equations[:, -1]))
    return (distance if distance > EPSILON_TOL else 0.0), rank


def grasp_quality(
    points: ArrayLike,
    normals: ArrayLike,
    centre: ArrayLike | None = None,
    mu: float = DEFAULT_FRICTION,
    edges: int = DEFAULT_EDGES,
    torque_scale: float | None = None,
) -> GraspQuality:
    """Force closure and ε of contacts (arguments as :func:`primitive_wrenches`)."""
    w, scale, m = primitive_wrenches(points, normals, centre, mu, edges, torque_scale)
    dim = 6 if np.shape(points)[1] == 3 else 3
    eps, rank = epsilon_of_wrenches(w)
    return GraspQuality(
        force_closure=eps > 0.0,
        epsilon=eps,
        friction=float(mu),
        edges=m,
        torque_scale=scale,
        contacts=int(np.shape(points)[0]),
        rank=rank,
        dimension=dim,
    )


def contacts_quality(
    contacts: Mapping[str, Mapping[str, Any]],
    centre: ArrayLike,
    torque_scale: float,
    mu: float = DEFAULT_FRICTION,
    edges: int = DEFAULT_EDGES,
) -> GraspQuality:
    """:func:`grasp_quality` of the *touching* fingertips of a plan's ``contacts`` dict
    (per finger: ``touching``, ``point`` and outward ``normal`` in the world frame).

    Memoised on its (hashable) inputs: the end agent and the plan result judge the same
    contacts, and a 6-D hull costs milliseconds.
    """
    touching = tuple(
        (tuple(float(v) for v in c["point"]), tuple(float(v) for v in c["normal"]))
        for c in contacts.values()
        if c.get("touching")
    )
    centre_key = tuple(float(v) for v in np.asarray(centre, dtype=float).ravel())
    return _contacts_quality(touching, centre_key, float(torque_scale), float(mu), int(edges))


@functools.lru_cache(maxsize=64)
def _contacts_quality(
    touching: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...],
    centre: tuple[float, ...],
    torque_scale: float,
    mu: float,
    edges: int,
) -> GraspQuality:
    points = np.array([p for p, _ in touching], dtype=float).reshape(-1, 3)
    normals = np.array([n for _, n in touching], dtype=float).reshape(-1, 3)
    return grasp_quality(points, normals, centre, mu, edges, torque_scale)
