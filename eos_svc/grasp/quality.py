"""Grasp quality: force closure under Coulomb friction and the Ferrari–Canny ε metric.

Pure NumPy/SciPy: contacts (points on the object, its outward normals; the finger pushes along
``−n``) in, a :class:`GraspQuality` out. Cones linearised by ``m`` edges (exactly two in 2-D),
optional soft-finger patches, wrenches ``[f ; (p − c) × f / L]``; ε is the radius of the largest
origin-centred ball inside their convex hull, 0 without force closure (degenerate sets never
raise). Conventions and the closed forms the tests check: ``docs/planner.md`` (Grasp quality).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull, QhullError

from eos_svc.errors import ValidationError
from eos_svc.kinematics.geometry import tangent_basis

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
        """JSON-friendly form: the fields in order."""
        return asdict(self)


def _array(value: ArrayLike, name: str) -> np.ndarray:
    """``value`` as a float array; :class:`ValidationError` naming ``name`` unless finite numbers."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValidationError(name, "must be an array of numbers") from None
    if not np.all(np.isfinite(a)):
        raise ValidationError(name, "must be finite")
    return a


def primitive_wrenches(
    points: ArrayLike,
    normals: ArrayLike,
    centre: ArrayLike | None,
    mu: float,
    edges: int = DEFAULT_EDGES,
    torque_scale: float | None = None,
    patch_radius: float = 0.0,
) -> tuple[np.ndarray, float, int]:
    """The primitive contact wrenches (k·w, 6) — (k·w, 3) in 2-D —, the torque scale used and
    the wrenches per contact w (the cone's edges, plus two with a soft-finger patch), of (k, 3)
    or (k, 2) contact ``points`` (m) with outward ``normals`` (any length), torques about
    ``centre`` (None: the centroid) over ``torque_scale`` (default: the largest ``‖p_i − c‖``),
    Coulomb ``mu`` ≥ 0, ``edges`` ≥ 3 per 3-D cone and a ``patch_radius`` (m, 0: hard contacts).
    A malformed argument raises :class:`ValidationError` naming it."""
    p, n = _array(points, "points"), _array(normals, "normals")
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValidationError("points", f"must have shape (k, 3) or (k, 2), got {p.shape}")
    if n.shape != p.shape:
        raise ValidationError("normals", f"must have the shape of points {p.shape}, got {n.shape}")
    mu = float(_array(mu, "mu"))
    if mu < 0.0:
        raise ValidationError("mu", f"must be ≥ 0, got {mu!r}")
    if isinstance(edges, bool) or not isinstance(edges, (int, np.integer)) or edges < 3:
        raise ValidationError("edges", f"must be an integer ≥ 3, got {edges!r}")
    lengths = np.linalg.norm(n, axis=1)
    if np.any(lengths < 1e-12):
        raise ValidationError("normals", "every normal must be non-zero")
    n = n / lengths[:, None]
    k, dim = p.shape
    c = (np.mean(p, axis=0) if k else np.zeros(dim)) if centre is None else _array(centre, "centre")
    if c.shape != (dim,):
        raise ValidationError("centre", f"must have {dim} coordinates, got shape {c.shape}")
    r = p - c
    if torque_scale is None:
        far = float(np.max(np.linalg.norm(r, axis=1))) if k else 0.0
        scale = far if far > 1e-12 else 1.0
    else:
        scale = float(_array(torque_scale, "torque_scale"))
        if scale <= 0.0:
            raise ValidationError("torque_scale", f"must be > 0, got {scale!r}")
    m = 1 if mu == 0.0 else (2 if dim == 2 else int(edges))
    # the cone's edges about each normal: t1, t2 span its tangent plane (t2 = 0 in the plane)
    if dim == 3:
        bases = [tangent_basis(ni) for ni in n]
        t1 = np.array([b[0] for b in bases]).reshape(k, 3)
        t2 = np.array([b[1] for b in bases]).reshape(k, 3)
    else:
        t1, t2 = np.stack([-n[:, 1], n[:, 0]], axis=1), np.zeros_like(n)
    theta = 2.0 * np.pi * np.arange(m) / m
    cos, sin = np.cos(theta)[None, :, None], np.sin(theta)[None, :, None]
    forces = -n[:, None, :] + mu * (cos * t1[:, None, :] + sin * t2[:, None, :])  # (k, m, dim)
    arm = r[:, None, :]
    if dim == 3:  # arm × force, component by component (np.cross's axis handling costs more)
        (ax, ay, az), (fx, fy, fz) = (
            np.moveaxis(np.broadcast_to(arm, forces.shape), -1, 0),
            np.moveaxis(forces, -1, 0),
        )
        torques = np.stack([ay * fz - az * fy, az * fx - ax * fz, ax * fy - ay * fx], axis=-1)
    else:
        torques = (arm[..., 0] * forces[..., 1] - arm[..., 1] * forces[..., 0])[..., None]
    patch = float(_array(patch_radius, "patch_radius"))
    if patch < 0.0:
        raise ValidationError("patch_radius", f"must be ≥ 0 m, got {patch_radius!r}")
    if patch > 0.0 and dim == 3 and mu > 0.0:
        gamma = 2.0 / 3.0 * mu * patch
        push = -n[:, None, :]  # (k, 1, 3)
        spin = np.concatenate([push, -push], axis=1) * gamma  # ± γ (−n): torque about the normal
        forces = np.concatenate([forces, np.repeat(push, 2, axis=1)], axis=1)
        torques = np.concatenate([torques, np.cross(arm, push) + spin], axis=1)
        m += 2
    wrenches = np.concatenate([forces, torques / scale], axis=2).reshape(k * m, 6 if dim == 3 else 3)
    return wrenches, scale, m


def epsilon_of_wrenches(wrenches: ArrayLike) -> tuple[float, int]:
    """Ferrari–Canny ε of a primitive wrench set and the set's rank: ε = 0 when the origin is not
    strictly inside the convex hull (rank-deficient and empty sets too; never raises)."""
    w = np.asarray(wrenches, dtype=float)
    if w.ndim != 2 or len(w) == 0:
        return 0.0, 0
    dim = w.shape[1]
    rank = int(np.linalg.matrix_rank(w, tol=1e-9 * max(float(np.max(np.abs(w))), 1.0)))
    if rank < dim or len(w) <= dim:
        return 0.0, rank
    try:
        # "QJ": qhull joggles the input (by ~1e-11 relative) and triangulates the hull instead
        # of merging facets — half the time of the default in 6-D, ε within ~1e-10 of it
        hull = ConvexHull(w, qhull_options="QJ")
    except (QhullError, ValueError):
        return 0.0, rank
    # equations: unit outward normal a and offset b with a·x + b ≤ 0 inside; the origin's
    # distance to a facet plane is −b (positive when the origin is on the inner side).
    distance = float(np.min(-hull.equations[:, -1]))
    return (distance if distance > EPSILON_TOL else 0.0), rank


def grasp_quality(
    points: ArrayLike,
    normals: ArrayLike,
    centre: ArrayLike | None,
    mu: float,
    edges: int = DEFAULT_EDGES,
    torque_scale: float | None = None,
    patch_radius: float = 0.0,
) -> GraspQuality:
    """Force closure and ε of contacts (arguments as :func:`primitive_wrenches`)."""
    w, scale, m = primitive_wrenches(points, normals, centre, mu, edges, torque_scale, patch_radius)
    eps, rank = epsilon_of_wrenches(w)
    k, dim = np.shape(points)
    return GraspQuality(eps > 0.0, eps, float(mu), m, scale, int(k), rank, 6 if dim == 3 else 3)


def contacts_quality(
    contacts: Mapping[str, Mapping[str, Any]],
    centre: ArrayLike,
    torque_scale: float,
    mu: float,
    edges: int = DEFAULT_EDGES,
    patch_radius: float = 0.0,
) -> GraspQuality:
    """:func:`grasp_quality` of the *touching* fingertips of a plan's ``contacts`` dict
    (per finger: ``touching``, ``point`` and outward ``normal`` in the world frame)."""
    touching = [c for c in contacts.values() if c.get("touching")]
    points = np.array([c["point"] for c in touching], dtype=float).reshape(-1, 3)
    normals = np.array([c["normal"] for c in touching], dtype=float).reshape(-1, 3)
    return grasp_quality(points, normals, centre, mu, edges, torque_scale, patch_radius)
