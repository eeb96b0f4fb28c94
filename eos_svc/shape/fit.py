"""Least-squares fit of one primitive class to the touches (scipy.optimize.least_squares).

Parameters per class (sizes as logarithms, so they stay positive and their σ is relative):

=========  ==================================================  ==
class      parameters                                          k
=========  ==================================================  ==
sphere     centre (3), log radius                               4
ellipsoid  centre (3), rotation (3), log semi-axes (3)          9
box        centre (3), rotation (3), log half sides (3)         9
cylinder   centre (3), axis tilt (2), log radius, log half len  7
capsule    centre (3), axis tilt (2), log radius, log half len  7
=========  ==================================================  ==

Rotations are local charts about a start orientation ``R0``: ``R = R0·exp([ω]×)`` for the
box and the ellipsoid; for the cylinder and the capsule the axis is ``R0·(α, β, 1)/‖·‖``.
Each class is fitted from a few starts (orientations from the world axes and from the
normals' scatter) and the lowest χ² kept. The residuals are whitened by the touches' noise
model (:class:`~eos_svc.shape.touches.Touches`), so χ² is a log-likelihood and the fit's
covariance is ``(JᵀJ)⁻¹`` (inflated by χ²/dof when that exceeds 1).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import least_squares, leastsq

from eos_svc.shape import kernels, primitives
from eos_svc.shape.touches import Touches

if TYPE_CHECKING:  # numba loads with the compiled module: only its type here
    from eos_svc.shape.compiled import KernelTouches

#: number of parameters of each class
N_PARAMS = {"sphere": 4, "ellipsoid": 9, "box": 9, "cylinder": 7, "capsule": 7}
#: indices of the log-size parameters of each class
SIZE_INDEX = {"sphere": (3,), "ellipsoid": (6, 7, 8), "box": (6, 7, 8), "cylinder": (5, 6), "capsule": (5, 6)}
#: smallest half size a start may take (m)
MIN_HALF = 0.004
#: χ²/dof under which a start's fit is accepted without trying the others
GOOD_FIT = 3.0
#: relative step of the finite-difference Jacobian
JACOBIAN_STEP = 1e-8
#: ridge added to JᵀJ before inverting it (whitened units)
RIDGE = 1e-6
#: range of the log half sizes a fit may take (ln m): 0.1 mm to 1 m
LOG_SIZE_RANGE = (math.log(1e-4), 0.0)


def rotation_vector(omega: np.ndarray) -> np.ndarray:
    """exp([ω]×): the rotation matrix of rotation vector ``omega`` (Rodrigues)."""
    theta = float(np.linalg.norm(omega))
    if theta < 1e-12:
        return np.eye(3)
    k = omega / theta
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    out: np.ndarray = np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * (K @ K)
    return out


def frame_with_z(axis: np.ndarray) -> np.ndarray:
    """A right-handed rotation whose third column is ``axis`` (unit)."""
    z = axis / np.linalg.norm(axis)
    a = _X_AXIS if abs(z[0]) < 0.9 else _Y_AXIS
    x = a - (a @ z) * z
    x /= np.linalg.norm(x)
    return _columns(x, _cross(z[None], x[None])[0], z)


def _columns(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The 3×3 matrix of columns x, y, z: ``np.column_stack``'s result without its wrapper."""
    out = np.empty((3, 3))
    out[:, 0], out[:, 1], out[:, 2] = x, y, z
    return out


def _median(values: np.ndarray) -> float:
    """``np.median`` of a 1-D array (the middle value, or the mean of the two middle values:
    the same number) from a full sort — np.median's partitioning wrappers cost ~30× more on
    a few dozen values."""
    ordered = np.sort(values)
    half = len(ordered) // 2
    return float(ordered[half]) if len(ordered) % 2 else float((ordered[half - 1] + ordered[half]) / 2.0)


@dataclass(frozen=True)
class Geometry:
    """A class instance: centre (m, world), rotation (world ← local), half sizes (m)."""

    kind: str
    centre: np.ndarray
    rotation: np.ndarray
    sizes: tuple[float, ...]  # sphere (r,), ellipsoid (a, b, c), box (hx, hy, hz), cyl/capsule (r, h)

    def half_extents(self) -> np.ndarray:
        """Half extents of the instance's bounds along the world x, y, z axes (m)."""
        R, s = self.rotation, self.sizes
        if self.kind == "sphere":
            return np.full(3, s[0])
        if self.kind == "box":
            out: np.ndarray = np.abs(R) @ np.asarray(s)
            return out
        if self.kind == "ellipsoid":
            return np.sqrt((R**2) @ (np.asarray(s) ** 2))
        axial = np.abs(R[:, 2])
        if self.kind == "cylinder":
            return axial * s[1] + s[0] * np.sqrt(np.maximum(1.0 - axial**2, 0.0))
        return axial * s[1] + s[0]

    def signed_distance(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(signed distance (N,), outward gradient (N, 3), world) at world ``points``."""
        d, g = batch_signed_distance(
            self.kind,
            np.asarray(points, dtype=float).reshape(1, -1, 3),
            self.centre[None],
            self.rotation[None],
            np.asarray(self.sizes, dtype=float)[None],
        )
        return d[0], g[0]


def batch_signed_distance(
    kind: str,
    points: np.ndarray,
    centres: np.ndarray,
    rotations: np.ndarray,
    sizes: np.ndarray,
    groups: np.ndarray | None = None,
    point_planes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (K, N) and world gradient (K, N, 3) of K instances of ``kind``
    (centres (K, 3), rotations (K, 3, 3), sizes (K, s)) at world points (1 or K, N, 3).
    ``groups``: first indices of groups of instances evaluated as if in separate calls (of
    the distances, only the ellipsoid's iteration couples the instances of a call, see
    :func:`~eos_svc.shape.primitives.ellipsoid`). ``point_planes``: the points as contiguous
    coordinate planes (3, 1 or K, N), if at hand (:func:`offsets_from`)."""
    local = offsets_from(points, centres, point_planes) @ rotations
    if kind == "sphere":
        d, g = primitives.sphere(local, sizes[:, :1])
        return d, g @ rotations.transpose(0, 2, 1)
    # the other kernels on coordinate planes (3, K, N) (primitives.*_planes: the rows' bits)
    planes = local.transpose(2, 0, 1).copy()
    if kind == "ellipsoid":
        radii = sizes.T[:, :, None].repeat(local.shape[1], 2)
        d, g_planes = primitives.ellipsoid_planes(planes, radii, groups=groups)
    elif kind == "box":
        d, g_planes = primitives.box_planes(planes, sizes.T[:, :, None])
    elif kind == "cylinder":
        d, g_planes = primitives.cylinder_planes(planes, sizes[:, :1], sizes[:, 1:2])
    else:
        d, g_planes = primitives.capsule_planes(planes, sizes[:, :1], sizes[:, 1:2])
    return d, g_planes.transpose(1, 2, 0).copy() @ rotations.transpose(0, 2, 1)


def offsets_from(
    points: np.ndarray, centres: np.ndarray, point_planes: np.ndarray | None = None
) -> np.ndarray:
    """``points − centres[:, None, :]`` (K, N, 3), C-contiguous (m): from the points' contiguous
    coordinate planes (3, 1 or K, N) when given — the same subtractions (the same bits), but
    in contiguous loops instead of numpy's broadcast over a last axis of 3 (several times
    slower on these arrays) — then laid out as rows again for the matrix product."""
    if point_planes is None:
        out: np.ndarray = points - centres[:, None, :]
        return out
    return (point_planes - centres.T[:, :, None]).transpose(1, 2, 0).copy()


#: where the entries of a unit rotation axis k go in [k]×, flattened row by row, with their signs
_SKEW_AT, _SKEW_OF = np.array([1, 2, 3, 5, 6, 7]), np.array([2, 1, 2, 0, 1, 0])
_SKEW_SIGN = np.array([-1.0, 1.0, 1.0, -1.0, -1.0, 1.0])
_EYE = np.eye(3)


def libm_exp(a: np.ndarray) -> np.ndarray:
    """``exp`` of every element as the C library computes it (``math.exp``: the compiled
    kernels' exp). numpy dispatches its vectorised exp by CPU: on an AVX-512 machine (numpy
    2.4's X86_V4 path) it differs from the C library's in the last bit for ≈ 5 % of arguments,
    and this numpy reference must give the kernels' results bit for bit (a service's fits run
    it until the kernels are loaded)."""
    return _elementwise(math.exp, a.ravel().tolist(), a.shape)


def libm_sin_cos(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``sin`` and ``cos`` of every element as the C library computes them (``math.sin``,
    ``math.cos``: the compiled kernels'): numpy dispatches these by CPU too, so they may differ
    from the C library's as its exp does (:func:`libm_exp`)."""
    values = a.ravel().tolist()
    return _elementwise(math.sin, values, a.shape), _elementwise(math.cos, values, a.shape)


def _elementwise(
    function: Callable[[float], float], values: list[float], shape: tuple[int, ...]
) -> np.ndarray:
    """``function`` of every value (Python floats, in C order), as an array of ``shape``."""
    return np.array([function(v) for v in values]).reshape(shape)


def _batch_rotation_vectors(omega: np.ndarray) -> np.ndarray:
    """Rodrigues for (K, 3) rotation vectors → (K, 3, 3)."""
    theta = primitives.norm(omega)
    k = omega / np.maximum(theta, 1e-12)[:, None]
    flat = np.zeros((len(omega), 9))
    flat[:, _SKEW_AT] = k.take(_SKEW_OF, axis=1) * _SKEW_SIGN
    K = flat.reshape(-1, 3, 3)
    sin, cos = libm_sin_cos(theta)
    s, c = sin[:, None, None], cos[:, None, None]
    out: np.ndarray = _EYE + s * K + (1.0 - c) * (K @ K)
    return out


_X_AXIS, _Y_AXIS, _ZERO3 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.zeros(3)


def _batch_frames_with_z(axes: np.ndarray) -> np.ndarray:
    """(K, 3, 3) right-handed rotations whose third columns are the (K, 3) axes."""
    z = axes / primitives.norm(axes)[:, None]
    a = np.where((np.abs(z[:, 0]) < 0.9)[:, None], _X_AXIS, _Y_AXIS)
    x = a - primitives.sum3(a * z)[:, None] * z
    x /= primitives.norm(x)[:, None]
    out = np.empty((len(axes), 3, 3))
    out[:, :, 0], out[:, :, 1], out[:, :, 2] = x, _cross(z, x), z
    return out


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise u × v of (K, 3) arrays: ``np.cross``'s products, without its axis handling."""
    # take: fancy indexing's result at a third of its cost
    out: np.ndarray = u.take(_NEXT, 1) * v.take(_AFTER, 1) - u.take(_AFTER, 1) * v.take(_NEXT, 1)
    return out


_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])
#: the log-size parameters of each class, as a slice (:data:`SIZE_INDEX`)
_SIZE_SLICE = {kind: slice(index[0], index[-1] + 1) for kind, index in SIZE_INDEX.items()}


_IDENTITIES: dict[int, np.ndarray] = {}


def _identities(count: int) -> np.ndarray:
    """``count`` 3×3 identities (count, 3, 3), contiguous and read-only, made once per count
    (``np.broadcast_to``'s view costs more than the product with it; a product with an
    identity is exact whichever order BLAS sums it in: the same bits)."""
    if count not in _IDENTITIES:
        stack = np.repeat(_EYE[None], count, axis=0)
        stack.flags.writeable = False
        _IDENTITIES[count] = stack
    return _IDENTITIES[count]


def batch_geometry(
    kind: str, thetas: np.ndarray, r0: np.ndarray, groups: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centres, rotations, sizes) of K parameter vectors (K, k) about ``r0`` (3, 3), or each
    about its own (K, 3, 3). ``groups``: first indices of groups of parameter vectors
    evaluated as if in separate calls (a cylinder's or capsule's axes are one matrix product
    per call, whose rounding BLAS may choose by the number of rows; with an ``r0`` per row,
    every row of a group is about its first row's)."""
    centres = thetas[:, :3]
    # np.clip's arithmetic (the bound or the value itself) without its wrapper
    log_sizes = np.minimum(np.maximum(thetas[:, _SIZE_SLICE[kind]], LOG_SIZE_RANGE[0]), LOG_SIZE_RANGE[1])
    sizes = libm_exp(log_sizes)
    K = len(thetas)
    if kind == "sphere":
        rotations = _identities(K)
    elif kind in ("ellipsoid", "box"):
        rotations = r0 @ _batch_rotation_vectors(thetas[:, 3:6])
    else:
        tilt = np.ones((K, 3))
        tilt[:, :2] = thetas[:, 3:5]
        if r0.ndim == 3 and groups is not None:  # each group about its first row's r0
            ends = [*groups[1:], K]
            axes = np.concatenate([tilt[lo:hi] @ r0[lo].T for lo, hi in zip(groups, ends, strict=True)])
        elif r0.ndim == 3:
            axes = np.einsum("kij,kj->ki", r0, tilt)
        elif groups is None:
            axes = tilt @ r0.T
        else:
            ends = [*groups[1:], K]
            axes = np.concatenate([tilt[lo:hi] @ r0.T for lo, hi in zip(groups, ends, strict=True)])
        rotations = _batch_frames_with_z(axes)
    return centres, rotations, sizes


@dataclass(frozen=True)
class FitData:
    """What :func:`batch_residuals` needs of the touches, derived once per fit instead of per
    evaluation: the contacts and free samples as one array of points (m) — also as contiguous
    coordinate planes (3, 1, N) —, their radii (m), the sensed normals and the noise model's
    constants."""

    points: np.ndarray
    point_planes: np.ndarray
    count: int
    radii: np.ndarray
    normals: np.ndarray
    free_radii: np.ndarray
    gap_offset: float
    sigma_distance: float
    sigma_normal: float

    @cached_property
    def kernel_touches(self) -> KernelTouches:
        """These fields as the compiled kernels take them (:data:`eos_svc.shape.compiled.KernelTouches`:
        the points (N, 3), then the rest as plain ints, arrays and floats), built once per fit."""
        return (
            self.points[0],
            int(self.count),
            self.radii,
            self.normals,
            self.free_radii,
            float(self.gap_offset),
            float(self.sigma_distance),
            float(self.sigma_normal),
        )

    @classmethod
    def of(cls, touches: Touches) -> FitData:
        """The fit data of ``touches``."""
        # the contacts and the free samples in one evaluation of the class's distance
        points = np.concatenate([touches.centres, touches.free]) if len(touches.free) else touches.centres
        return cls(
            points[None],
            np.ascontiguousarray(points.T[:, None, :]),
            touches.count,
            touches.radii,
            touches.normals,
            touches.free_radii,
            touches.gap_offset,
            touches.sigma_distance,
            touches.sigma_normal,
        )


def batch_residuals(thetas: np.ndarray, kind: str, r0: np.ndarray, touches: Touches) -> np.ndarray:
    """Whitened residuals (K, m) of K parameter vectors (about one start orientation ``r0``
    or each about its own, see :func:`batch_geometry`): tip-centre distances, normals,
    free-space hinges."""
    return _whitened_residuals(thetas, kind, r0, FitData.of(touches))


def _whitened_residuals(
    thetas: np.ndarray, kind: str, r0: np.ndarray, data: FitData, groups: np.ndarray | None = None
) -> np.ndarray:
    """:func:`batch_residuals` from the touches' :class:`FitData`; ``groups`` (first rows of
    groups of ``thetas``) as in :func:`batch_signed_distance`."""
    return _residuals_and_geometry(thetas, kind, r0, data, groups)[0]


def _residuals_and_geometry(
    thetas: np.ndarray, kind: str, r0: np.ndarray, data: FitData, groups: np.ndarray | None = None
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(:func:`_whitened_residuals`, the :func:`batch_geometry` they were computed from): the
    compiled kernel (:func:`_residuals_and_geometry_compiled`) once it is ready in this
    process, the numpy reference (the same bits) until then (:mod:`eos_svc.shape.kernels`)."""
    if kernels.ready():
        return _residuals_and_geometry_compiled(thetas, kind, r0, data, groups)
    return _residuals_and_geometry_numpy(thetas, kind, r0, data, groups)


def _residuals_and_geometry_compiled(
    thetas: np.ndarray, kind: str, r0: np.ndarray, data: FitData, groups: np.ndarray | None = None
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """:func:`_residuals_and_geometry_numpy` as one call of the compiled kernel
    (:func:`eos_svc.shape.compiled.residuals_and_geometry`), the same operations in the same
    order on every number (the same bits; ``groups`` keeps its meaning: it couples only the
    ellipsoid's Newton stop and picks the axis products, every other row is independent)."""
    from eos_svc.shape import compiled  # numba on first use: importing the package stays light

    return compiled.residuals_and_geometry(kind, thetas, r0, groups, LOG_SIZE_RANGE, data.kernel_touches)


def _residuals_and_geometry_numpy(
    thetas: np.ndarray, kind: str, r0: np.ndarray, data: FitData, groups: np.ndarray | None = None
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The reference in numpy: :func:`batch_geometry`, :func:`batch_signed_distance` and the
    whitening, array by array (the compiled kernel is tested against it)."""
    geometry = batch_geometry(kind, thetas, r0, groups)
    n = data.count
    d, g = batch_signed_distance(kind, data.points, *geometry, groups, data.point_planes)
    K = len(thetas)
    r_d = (d[:, :n] - data.radii - data.gap_offset) / data.sigma_distance
    r_n = ((g[:, :n] - data.normals) / data.sigma_normal).reshape(K, -1)
    if not len(data.free_radii):
        return np.concatenate([r_d, r_n], axis=1), geometry
    r_f = np.minimum(d[:, n:] - data.free_radii, 0.0) / data.sigma_distance
    return np.concatenate([r_d, r_n, r_f], axis=1), geometry


def geometry_from(kind: str, theta: np.ndarray, r0: np.ndarray) -> Geometry:
    """The geometry of parameters ``theta`` about start orientation ``r0``."""
    return _geometry_row(kind, batch_geometry(kind, np.asarray(theta, dtype=float)[None], r0), 0)


def _geometry_row(kind: str, geometry: tuple[np.ndarray, np.ndarray, np.ndarray], row: int) -> Geometry:
    """Row ``row`` of :func:`batch_geometry`'s (centres, rotations, sizes) as a Geometry."""
    centres, rotations, sizes = geometry
    return Geometry(kind, centres[row].copy(), np.array(rotations[row]), tuple(float(v) for v in sizes[row]))


def residuals(theta: np.ndarray, kind: str, r0: np.ndarray, touches: Touches) -> np.ndarray:
    """Whitened residuals of one parameter vector (see :func:`batch_residuals`)."""
    out: np.ndarray = batch_residuals(np.asarray(theta, dtype=float)[None], kind, r0, touches)[0]
    return out


@dataclass(frozen=True)
class ClassFit:
    """The best fit of one class.

    Attributes:
        kind: the class.
        geometry: the fitted instance.
        chi2: Σ of the squared whitened residuals at the optimum.
        n_params: k.
        covariance: (k, k) covariance of the parameters.
        theta: the parameters; ``r0``: their start orientation.
        start: which of :func:`starts` the fit began from.
    """

    kind: str
    geometry: Geometry
    chi2: float
    n_params: int
    covariance: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    r0: np.ndarray = field(repr=False)
    start: int = 0

    def size_sigmas(self) -> np.ndarray:
        """σ of the log sizes (≈ relative σ of each size)."""
        idx = list(SIZE_INDEX[self.kind])
        return np.sqrt(np.maximum(np.diag(self.covariance)[idx], 0.0))

    def centre_sigmas(self) -> np.ndarray:
        """σ of the centre coordinates (m)."""
        return np.sqrt(np.maximum(np.diag(self.covariance)[:3], 0.0))


def extent_ratios(fit: ClassFit, touches: Touches, step: float = 0.10) -> np.ndarray:
    """Per size of ``fit``: the largest likelihood ratio ``exp(−Δχ²/2)`` of the same object with
    that size ``step`` larger or smaller while one of its two faces along that direction stays
    put (the centre shifted by the change), against the fit. ≈ 0 when the touches bound the
    size on both sides; ≈ 1 when one side is free — a far face no contact or free sample sees
    (the least-squares covariance, a local quadratic, misses that: the fit sits on the
    nearest contact, where the residuals do not change when the far face moves away)."""
    kind, theta, r0 = fit.kind, fit.theta, fit.r0
    g = fit.geometry
    variants = []
    owners = []
    for n, i in enumerate(SIZE_INDEX[kind]):
        half = g.sizes[n]
        if kind in ("box", "ellipsoid"):
            axis = g.rotation[:, n]
        elif kind in ("cylinder", "capsule") and n == 1:
            axis = g.rotation[:, 2]
        else:
            axis = np.zeros(3)  # a radius: both sides move together
        for factor in (1.0 + step, 1.0 - step):
            for side in (1.0, -1.0):
                t = theta.copy()
                t[i] = theta[i] + math.log(factor)
                t[:3] = theta[:3] + side * (factor - 1.0) * half * axis
                variants.append(t)
                owners.append(n)
    R = batch_residuals(np.array(variants), kind, r0, touches)
    delta = np.maximum(np.sum(R * R, axis=1) - fit.chi2, 0.0)
    ratios = np.zeros(len(SIZE_INDEX[kind]))
    for n, d in zip(owners, delta, strict=True):
        ratios[n] = max(ratios[n], math.exp(-0.5 * float(d)))
    return ratios


def _normal_scatter_axes(normals: np.ndarray) -> np.ndarray:
    """Eigenvectors (columns, ascending eigenvalue) of Σ n nᵀ, right-handed."""
    _, V = np.linalg.eigh(normals.T @ normals)
    if np.linalg.det(V) < 0:
        V[:, 0] = -V[:, 0]
    return V


def _normal_line_centre(points: np.ndarray, normals: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """The point nearest every inward normal line (a sphere's centre), regularised toward
    ``prior`` where the lines are parallel."""
    # Σ (I − n nᵀ) and Σ (I − n nᵀ) s over the contacts
    A = len(points) * np.eye(3) - normals.T @ normals
    b = points.sum(axis=0) - normals.T @ np.sum(normals * points, axis=1)
    lam = 1e-3 * len(points)
    out: np.ndarray = np.linalg.solve(A + lam * np.eye(3), b + lam * prior)
    return out


def _normal_clusters(
    normals: np.ndarray, angle: float = math.radians(15.0), most: int | None = None
) -> list[np.ndarray]:
    """Mean directions of the sensed normals grouped greedily within ``angle`` (the first
    normal left and every normal left within ``angle`` of it, and so on), largest first;
    ``most``: only that many of the largest."""
    cos = math.cos(angle)
    members = _cluster_members(normals, cos)
    members.sort(key=lambda m: -len(m))
    out = []
    for m in members[:most]:
        mean = normals[m].sum(axis=0)
        out.append(mean / np.linalg.norm(mean))
    return out


#: how far from a group's cosine bound every cosine must be for the Gram matrix to decide
#: membership as each normal's own product would (both round within a few 1e-16)
_CLUSTER_MARGIN = 1e-12


def _cluster_members(normals: np.ndarray, cos: float) -> list[list[int]]:
    """Indices of :func:`_normal_clusters`' groups, in the order they are formed: every
    cosine from one Gram matrix, unless one lies within :data:`_CLUSTER_MARGIN` of the bound
    (then each group's cosines as the plain loop computes them, group by group)."""
    dots = normals @ normals.T
    if np.any(np.abs(dots - cos) < _CLUSTER_MARGIN):
        left_array = np.arange(len(normals))
        plain: list[list[int]] = []
        while len(left_array):
            near_array = normals[left_array] @ normals[left_array[0]] >= cos
            plain.append(left_array[near_array].tolist())
            left_array = left_array[~near_array]
        return plain
    close = (dots >= cos).tolist()
    left = list(range(len(normals)))
    members: list[list[int]] = []
    while left:
        row = close[left[0]]
        members.append([j for j in left if row[j]])
        left = [j for j in left if not row[j]]
    return members


def _face_frames(normals: np.ndarray) -> list[np.ndarray]:
    """Box orientations from pairs of roughly orthogonal groups of normals (the largest
    groups first, at most three frames)."""
    clusters = _normal_clusters(normals, most=4)
    frames = []
    for i, x in enumerate(clusters):
        for c in clusters[i + 1 :]:
            if abs(c @ x) < 0.3:
                y = c - (c @ x) * x
                y /= np.linalg.norm(y)
                frames.append(_columns(x, y, _cross(x[None], y[None])[0]))
    return frames[:3]


def _distinct(axes: list[np.ndarray], angle: float = math.radians(15.0)) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for a in axes:
        a = a / np.linalg.norm(a)
        if all(abs(a @ b) < math.cos(angle) for b in out):
            out.append(a)
    return out


class ClassStarts:
    """Every class's start parameters from one set of touches (:func:`starts`), each class's
    computed once, on first use, and the pieces several classes share — the normals'
    scatter axes, the normal lines' nearest point, the cylinder's and the capsule's frames —
    once for all of them (:func:`~eos_svc.shape.selection.select_class` fits every class to
    the same touches)."""

    def __init__(self, touches: Touches) -> None:
        self.touches = touches
        S = touches.surface_points
        lo, hi = S.min(axis=0), S.max(axis=0)
        self.surface, self.mid = S, 0.5 * (lo + hi)
        self._of: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
        self._evaluations: dict[tuple[str, int], _Evaluations] = {}

    @cached_property
    def fit_data(self) -> FitData:
        """The touches' :class:`FitData`, shared by every fit."""
        return FitData.of(self.touches)

    def evaluations(self, kind: str, index: int) -> _Evaluations:
        """The :class:`_Evaluations` of ``kind`` about its start ``index``'s orientation, one
        per select: a fit of the class from that start again (a screening, a quick fit, the
        full fit: MINPACK from the same start takes the same first steps) finds the points
        already evaluated (the same bits: each point's residuals and Jacobian depend on it
        alone)."""
        key = (kind, index)
        if key not in self._evaluations:
            r0 = self.of(kind)[index][1]
            self._evaluations[key] = _Evaluations(kind, r0, self.touches, self.fit_data)
        return self._evaluations[key]

    def nearest_order(self, kind: str) -> list[int]:
        """:func:`_nearest_order` of ``kind``'s starts, from :meth:`evaluate_starts` (each
        start's residuals as its own fit evaluates them)."""
        candidates = self.of(kind)
        if len(candidates) < 2:
            return list(range(len(candidates)))
        self.evaluate_starts(kind)
        at_start = np.array([self.evaluations(kind, i).known[theta0.tobytes()][0] for i, (theta0, _) in
                             enumerate(candidates)])
        chi2 = np.sum(at_start**2, axis=1)
        return sorted(range(len(candidates)), key=lambda i: float(chi2[i]))

    def evaluate_starts(self, kind: str) -> None:
        """Every start of ``kind`` evaluated at its own parameters — residuals and difference
        Jacobian, as its :class:`_Evaluations` evaluates a point (one compiled call each:
        :func:`_difference_evaluation`) — so the fits from these starts find their first point
        known. :func:`_evaluate_starts_numpy` is the reference: all the starts in one batched
        numpy call, each start's rows as their own groups about their own orientation (the
        same bits), and what runs until the kernels are ready."""
        if not kernels.ready():
            _evaluate_starts_numpy(self, kind)
            return
        candidates = self.of(kind)
        for i, (theta0, r0) in enumerate(candidates):
            known = self.evaluations(kind, i).known
            key = theta0.tobytes()
            if key not in known:
                known[key] = _difference_evaluation(theta0, kind, r0, self.fit_data)

    def of(self, kind: str) -> list[tuple[np.ndarray, np.ndarray]]:
        """Start parameters and orientations ``(theta0, r0)`` of ``kind``."""
        if kind not in self._of:
            self._of[kind] = self._starts(kind)
        return list(self._of[kind])

    @cached_property
    def scatter_axes(self) -> np.ndarray:
        """:func:`_normal_scatter_axes` of the normals."""
        return _normal_scatter_axes(self.touches.normals)

    @cached_property
    def line_centre(self) -> np.ndarray:
        """:func:`_normal_line_centre` of the contacts, toward the middle of their bounds."""
        return _normal_line_centre(self.surface, self.touches.normals, self.mid)

    @cached_property
    def axial_frames(self) -> list[tuple[np.ndarray, float, float]]:
        """(frame, median radial distance of the contacts, largest axial one) (m) about each
        distinct candidate axis of a cylinder or a capsule, centred mid-bounds."""
        V = self.scatter_axes
        out = []
        for axis in _distinct([V[:, 0], *np.eye(3), V[:, 1], V[:, 2]]):
            r0 = frame_with_z(axis)
            local = (self.surface - self.mid) @ r0
            radial = _median(np.hypot(local[:, 0], local[:, 1]))
            out.append((r0, radial, float(np.max(np.abs(local[:, 2])))))
        return out

    def _starts(self, kind: str) -> list[tuple[np.ndarray, np.ndarray]]:
        S, mid, normals = self.surface, self.mid, self.touches.normals
        out: list[tuple[np.ndarray, np.ndarray]] = []
        if kind == "sphere":
            c = self.line_centre
            r = max(float(np.mean(np.linalg.norm(S - c, axis=1))), MIN_HALF)
            return [(np.array([*c, math.log(r)]), np.eye(3))]
        V = self.scatter_axes
        if kind in ("ellipsoid", "box"):
            frames = [*_face_frames(normals), np.eye(3), V] if kind == "box" else [V, np.eye(3)]
            for r0 in frames:
                c = mid if kind == "box" else self.line_centre
                half = np.maximum(np.max(np.abs((S - c) @ r0), axis=0), MIN_HALF)
                out.append((np.concatenate([c, _ZERO3, np.log(half)]), r0))
            return out
        for r0, median_radius, axial in self.axial_frames:
            radius = max(median_radius, MIN_HALF)
            half = max(axial - radius, MIN_HALF) if kind == "capsule" else max(axial, MIN_HALF)
            out.append((np.concatenate([mid, [0.0, 0.0, math.log(radius), math.log(half)]]), r0))
        return out


def _evaluate_starts_numpy(shared: ClassStarts, kind: str) -> None:
    """:meth:`ClassStarts.evaluate_starts` in one batched numpy call: every start's k + 1
    difference points and the start alone as groups of their own, each about its start's
    orientation (:func:`_residuals_and_geometry_numpy`)."""
    candidates = shared.of(kind)
    todo = [i for i, (theta0, _) in enumerate(candidates)
            if theta0.tobytes() not in shared.evaluations(kind, i).known]
    if not todo:
        return
    k = N_PARAMS[kind]
    rows = k + 2  # the k + 1 difference points (a group), the point alone (a group)
    blocks = [_difference_points(candidates[i][0], copies=2) for i in todo]
    thetas = np.concatenate([b[0] for b in blocks])
    r0s = np.repeat(np.array([candidates[i][1] for i in todo]), rows, axis=0)
    firsts = np.arange(len(todo)) * rows
    groups = np.stack([firsts, firsts + k + 1], axis=1).reshape(-1)
    R, geometry = _residuals_and_geometry_numpy(thetas, kind, r0s, shared.fit_data, groups)
    for j, (i, (_, h)) in enumerate(zip(todo, blocks, strict=True)):
        lo = j * rows
        block = (geometry[0][lo : lo + rows], geometry[1][lo : lo + rows], geometry[2][lo : lo + rows])
        shared.evaluations(kind, i).known[candidates[i][0].tobytes()] = (
            R[lo + k + 1], _difference_quotients(R[lo : lo + k + 1], h), block,
        )


def starts(kind: str, touches: Touches) -> list[tuple[np.ndarray, np.ndarray]]:
    """Start parameters and orientations ``(theta0, r0)`` of ``kind`` from the touches: the
    sphere's centre nearest the normal lines, the mean distance its radius; the ellipsoid
    about the normals' scatter axes and the world axes, centred there too; the box about
    frames of orthogonal groups of normals, the world axes and the scatter axes, centred
    mid-bounds; the cylinder and the capsule along each distinct scatter and world axis
    (:class:`ClassStarts`, which shares the pieces between classes)."""
    return ClassStarts(touches).of(kind)


def ranked_starts(kind: str, touches: Touches) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`starts` from the lowest χ² at the start itself (ties in their order): fitted in
    this order, the start nearest the touches is the one that explains them, shows the class
    hopeless, or screens it (:func:`~eos_svc.shape.selection.screen`)."""
    out = starts(kind, touches)
    return [out[i] for i in _nearest_order(kind, touches, out)]


def _nearest_order(kind: str, touches: Touches, candidates: list[tuple[np.ndarray, np.ndarray]]) -> list[int]:
    """Indices of ``candidates`` from the lowest χ² at the start itself (ties in their order)."""
    if len(candidates) < 2:
        return list(range(len(candidates)))
    thetas = np.array([theta0 for theta0, _ in candidates])
    r0s = np.array([r0 for _, r0 in candidates])
    chi2 = np.sum(batch_residuals(thetas, kind, r0s, touches) ** 2, axis=1)
    return sorted(range(len(candidates)), key=lambda i: float(chi2[i]))


def _difference_points(theta: np.ndarray, copies: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(the k + 1 parameter vectors of a forward-difference Jacobian at ``theta`` — each
    parameter stepped, then ``theta`` itself (``copies`` times) —, the steps h (k,))."""
    k = len(theta)
    h = JACOBIAN_STEP * np.maximum(1.0, np.abs(theta))
    thetas = np.repeat(theta[None], k + copies, axis=0)
    # the first k rows' diagonal as a strided view of the flat array: one in-place addition
    diagonal = thetas.reshape(-1)[: k * (k + 1) : k + 1]
    diagonal += h
    return thetas, h


def _difference_quotients(R: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The (m, k) Jacobian from the residuals (k + 1, m) at :func:`_difference_points`."""
    k = len(h)
    out: np.ndarray = ((R[:k] - R[k]) / h[:, None]).T
    return out


def _jacobian(theta: np.ndarray, kind: str, r0: np.ndarray, touches: Touches) -> np.ndarray:
    """Forward-difference Jacobian of :func:`residuals`, every column in one batched call
    (forward, as MINPACK's: the box and cylinder distances have kinks a central difference
    straddles)."""
    thetas, h = _difference_points(theta)
    return _difference_quotients(batch_residuals(thetas, kind, r0, touches), h)


#: (centres, rotations, sizes) of a batch of parameter vectors (:func:`batch_geometry`)
_BatchGeometry = tuple[np.ndarray, np.ndarray, np.ndarray]


def _difference_evaluation(
    theta: np.ndarray, kind: str, r0: np.ndarray, data: FitData
) -> tuple[np.ndarray, np.ndarray, _BatchGeometry]:
    """(residuals at ``theta``, their forward-difference Jacobian, the geometry of the k + 2
    rows evaluated — θ's own is the last): :func:`_difference_evaluation_compiled` once the
    kernels are ready in this process, :func:`_difference_evaluation_numpy` (the same bits)
    until then."""
    if kernels.ready():
        return _difference_evaluation_compiled(theta, kind, r0, data)
    return _difference_evaluation_numpy(theta, kind, r0, data)


def _difference_evaluation_compiled(
    theta: np.ndarray, kind: str, r0: np.ndarray, data: FitData
) -> tuple[np.ndarray, np.ndarray, _BatchGeometry]:
    """:func:`_difference_evaluation` in one call of the compiled kernel
    (:func:`eos_svc.shape.compiled.difference_evaluation`)."""
    from eos_svc.shape import compiled  # numba on first use: importing the package stays light

    return compiled.difference_evaluation(kind, theta, r0, JACOBIAN_STEP, LOG_SIZE_RANGE, data.kernel_touches)


def _difference_evaluation_numpy(
    theta: np.ndarray, kind: str, r0: np.ndarray, data: FitData
) -> tuple[np.ndarray, np.ndarray, _BatchGeometry]:
    """:func:`_difference_evaluation` from :func:`_difference_points` and
    :func:`_residuals_and_geometry_numpy`: the k + 1 difference points as one group, θ alone
    as another (see :class:`_Evaluations`)."""
    k = len(theta)
    thetas, h = _difference_points(theta, copies=2)
    R, geometry = _residuals_and_geometry_numpy(thetas, kind, r0, data, np.array([0, k + 1]))
    return R[k + 1], _difference_quotients(R[: k + 1], h), geometry


class _Evaluations:
    """The residuals (:func:`residuals`) and their Jacobian (:func:`_jacobian`) of one fit
    — one class, one start orientation, one set of touches — both from one batched call per
    parameter vector: MINPACK asks for the Jacobian at every point whose residuals it accepts,
    so evaluating the k + 1 difference points with the point itself costs one call instead of
    two (numpy's per-call overhead dominates these small arrays). The residuals and the
    Jacobian are, to the bit, those of :func:`residuals` and :func:`_jacobian` (the point is
    evaluated twice in the call: once with the difference points, once on its own, see
    :func:`batch_signed_distance`'s ``groups``); every evaluated point is remembered. One
    call of the compiled kernel evaluates a point (:func:`_difference_evaluation`)."""

    def __init__(self, kind: str, r0: np.ndarray, touches: Touches, data: FitData | None = None) -> None:
        self.kind, self.r0 = kind, r0
        self.data = FitData.of(touches) if data is None else data
        self.known: dict[bytes, tuple[np.ndarray, np.ndarray, _BatchGeometry]] = {}

    def _evaluate(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, _BatchGeometry]:
        theta = np.asarray(theta, dtype=float)
        key = theta.tobytes()
        if key not in self.known:
            self.known[key] = _difference_evaluation(theta, self.kind, self.r0, self.data)
        return self.known[key]

    def residuals(self, theta: np.ndarray, *args: object) -> np.ndarray:
        """The whitened residuals at ``theta`` (``args``: ignored, MINPACK's driver passes them):
        a copy, the remembered ones stay as evaluated (scipy's ``leastsq`` keeps the array of
        the first call as MINPACK's working residuals and overwrites it)."""
        out: np.ndarray = self._evaluate(theta)[0].copy()
        return out

    def jacobian(self, theta: np.ndarray, *args: object) -> np.ndarray:
        """The (m, k) forward-difference Jacobian at ``theta``: a copy, like :meth:`residuals`,
        so the remembered one stays as evaluated whatever the caller does with it."""
        out: np.ndarray = self._evaluate(theta)[1].copy()
        return out

    def geometry(self, theta: np.ndarray) -> Geometry:
        """:func:`geometry_from` ``theta`` (the same bits: computed as its own group)."""
        return _geometry_row(self.kind, self._evaluate(theta)[2], len(theta) + 1)


def residual_count(touches: Touches) -> int:
    """m, the number of whitened residuals (:func:`batch_residuals`): a distance and three
    normal components per contact, a hinge per free sample."""
    return 4 * touches.count + len(touches.free)


def explains(chi2: float, touches: Touches, kind: str) -> bool:
    """Whether a fit of ``kind`` with this χ² explains the touches to within the noise
    (χ²/dof ≤ GOOD_FIT over all the whitened residuals): :func:`fit_class` then tries no
    other start."""
    return chi2 <= GOOD_FIT * max(residual_count(touches) - N_PARAMS[kind], 1)


def levenberg_marquardt(
    theta0: np.ndarray,
    kind: str,
    r0: np.ndarray,
    touches: Touches,
    max_nfev: int,
    evaluations: _Evaluations | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(θ, whitened residuals at θ) after MINPACK's ``lmder`` from ``theta0`` — what
    ``least_squares(method="lm", x_scale="jac")`` runs (same tolerances, factor 100, the
    Jacobian's own scaling: the same iterates), called through ``scipy.optimize.leastsq``
    without ``least_squares``' per-evaluation wrappers and its Jacobian at the end (the fit
    needs that only for the best start). ``evaluations``: the fit's :class:`_Evaluations`
    (of ``kind``, ``r0``, ``touches``), to ask for the Jacobian at θ afterwards."""
    ev = _Evaluations(kind, r0, touches) if evaluations is None else evaluations
    m, k = residual_count(touches), len(theta0)
    assert m >= k, "MINPACK needs at least as many residuals as parameters (fit_class checks it)"
    pad_row = (m * k) % 2 == 0 and k % 2 == 1  # see _with_zero_row
    x, _, info, _, _ = leastsq(
        _with_zero_row(ev.residuals) if pad_row else ev.residuals,
        np.asarray(theta0, dtype=float),
        Dfun=_with_zero_row(ev.jacobian) if pad_row else ev.jacobian,
        full_output=True,
        ftol=1e-8,
        xtol=1e-8,
        gtol=1e-8,
        maxfev=max_nfev,
    )
    return x, info["fvec"][:m]


def _with_zero_row(function: Callable[..., np.ndarray]) -> Callable[..., np.ndarray]:
    """``function``'s residuals (m,) or Jacobian (m, k) with one more row of zeros.

    Works around scipy's C MINPACK (1.17 here): when ``qrfac`` recomputes the norm of the
    Jacobian's last column it reads one element past the (k, m) array scipy allocated
    (``tests/shape/test_minpack.py``). With m·k even those 8 bytes are slack in the array's
    malloc chunk — whatever an earlier allocation left there, so the pivot order and the
    iterates depended on the process's allocation history; with m·k odd they are the next
    chunk's size header, a subnormal number that changes no norm (and so for k odd one zero
    row makes m·k odd). A zero residual with a zero Jacobian row changes no other number
    MINPACK computes (every sum and norm over the rows adds ±0), so the iterates are those of
    a MINPACK that reads no further than its array. k even (the sphere's 4) stays exposed."""

    def padded(theta: np.ndarray, *args: object) -> np.ndarray:
        out = function(theta, *args)
        return np.concatenate([out, np.zeros((1, *out.shape[1:]))])

    return padded


def fit_class(
    kind: str,
    touches: Touches,
    max_nfev: int = 20,
    hopeless: float = math.inf,
    max_starts: int | None = None,
    nearest_first: bool = False,
    class_starts: ClassStarts | None = None,
) -> ClassFit:
    """The least-squares fit of ``kind`` (the best of its starts).

    ``hopeless``: a χ² above which the class cannot compete with a class already fitted
    (:func:`~eos_svc.shape.selection.select_class` passes a bound far above that class's
    χ²): once a start ends above it, the remaining starts are skipped (their posterior would
    be 0 whatever they reach). ``max_starts``: try at most that many starts (all by default).
    ``nearest_first``: try the starts from the nearest to the touches (:func:`ranked_starts`),
    not in :func:`starts`' order. ``class_starts``: the touches' :class:`ClassStarts` (shared
    by the fits of several classes to the same touches, with the points each start's fits
    evaluated), else computed here.

    The fit from the first start alone (``max_starts=1``) *is* the fit with the same
    ``max_nfev`` and any ``hopeless`` bound when its χ² is above that bound, when it
    :func:`explains` the touches, or when the class has one start (the sphere): every other
    start is skipped then."""
    if kind not in N_PARAMS:
        raise ValueError(f"unknown class {kind!r} (choose from {', '.join(N_PARAMS)})")
    k = N_PARAMS[kind]
    best = None
    m = residual_count(touches)
    shared = ClassStarts(touches) if class_starts is None else class_starts
    candidates = shared.of(kind)
    order = shared.nearest_order(kind) if nearest_first else range(len(candidates))
    for index in list(order)[:max_starts]:
        theta0, r0 = candidates[index]
        evaluations = shared.evaluations(kind, index)
        if m >= k:
            theta, fun = levenberg_marquardt(theta0, kind, r0, touches, max_nfev, evaluations)
        else:  # fewer residuals than parameters: MINPACK cannot, the trust region can
            res = least_squares(
                residuals,
                theta0,
                jac=_jacobian,
                args=(kind, r0, touches),
                method="trf",
                x_scale="jac",
                max_nfev=max_nfev,
                ftol=1e-8,
                xtol=1e-8,
                gtol=1e-8,
            )
            theta, fun = res.x, res.fun
        chi2 = float(fun @ fun)
        if best is None or chi2 < best[0]:
            best = (chi2, theta, r0, index, evaluations)
        if explains(chi2, touches, kind):
            break  # this start explains the touches to within the noise: no other start needed
        if chi2 > hopeless:
            break
    assert best is not None
    chi2, theta, r0, index, evaluations = best
    J = evaluations.jacobian(theta)  # usually known: MINPACK evaluated θ
    # a direction no residual constrains (e.g. a length at its bound) gets a variance of
    # 1/RIDGE, not pinv's 0
    cov = np.linalg.inv(J.T @ J + RIDGE * np.eye(k))
    dof = max(m - k, 1)
    cov = cov * max(1.0, chi2 / dof)
    return ClassFit(kind, evaluations.geometry(theta), chi2, k, cov, theta, r0, index)
