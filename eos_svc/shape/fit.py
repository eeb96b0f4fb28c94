"""Least-squares fit of one object kind to the touches (scipy.optimize).

Parameters: the centre (3), the orientation (none for a sphere; a rotation vector about a
start orientation ``R0`` for a box or ellipsoid; an axis tilt ``R0·(α, β, 1)`` for a cylinder or
capsule), then the log half sizes. The residuals are the kind's signed distance and gradient at
the touches (:meth:`~eos_svc.objects.base.SurfaceObject.local_distance`), whitened by the noise
model (:class:`~eos_svc.shape.touches.Touches`), so the covariance is ``(JᵀJ)⁻¹`` (inflated by
χ²/dof above 1). Each kind is fitted from a few starts (:mod:`~eos_svc.shape.starts`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, partial

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares, leastsq

from eos_svc.objects import FITTED_KINDS as KINDS
from eos_svc.objects import SurfaceObject
from eos_svc.objects.base import norm
from eos_svc.shape import kernels
from eos_svc.shape.starts import ClassStarts
from eos_svc.shape.touches import Touches

#: parameters of each kind's orientation
_ORIENTATION_PARAMS = {"none": 0, "rotation": 3, "axis": 2}
#: number of parameters of each kind
N_PARAMS = {k: 3 + _ORIENTATION_PARAMS[c.orientation] + c.half_size_count for k, c in KINDS.items()}
#: indices of the log-size parameters of each kind
SIZE_INDEX = {k: tuple(range(N_PARAMS[k] - c.half_size_count, N_PARAMS[k])) for k, c in KINDS.items()}
#: χ²/dof under which a start's fit is accepted without trying the others
GOOD_FIT = 3.0
#: relative step of the forward-difference Jacobian
JACOBIAN_STEP = 1e-8
#: the least-squares solvers' tolerances: relative change of the cost and of θ, the gradient's cosine
TOLERANCES = {"ftol": 1e-8, "xtol": 1e-8, "gtol": 1e-8}
#: ridge added to JᵀJ before inverting it (whitened units)
RIDGE = 1e-6
#: range of the log half sizes a fit may take (ln m): 0.1 mm to 1 m
LOG_SIZE_RANGE = (math.log(1e-4), 0.0)
_X, _Y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise u × v of (K, 3) arrays (np.cross's axis handling costs more than the product)."""
    ux, uy, uz = u.T
    vx, vy, vz = v.T
    return np.stack([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx], axis=1)


def rotation_matrices(omega: np.ndarray) -> np.ndarray:
    """exp([ω]×) of (K, 3) rotation vectors, (K, 3, 3) (Rodrigues:
    ``I + sin θ [k]× + (1 − cos θ) [k]×²``, ``k = ω/θ``)."""
    theta = norm(omega)
    kx, ky, kz = (omega / np.maximum(theta, 1e-12)[:, None]).T
    zero = np.zeros_like(kx)
    K = np.stack([zero, -kz, ky, kz, zero, -kx, -ky, kx, zero], axis=1).reshape(-1, 3, 3)
    out: np.ndarray = (
        np.eye(3) + np.sin(theta)[:, None, None] * K + (1.0 - np.cos(theta))[:, None, None] * (K @ K)
    )
    return out


def frames_with_z(axes: np.ndarray) -> np.ndarray:
    """(K, 3, 3) right-handed rotations whose third columns are the (K, 3) axes (normalised),
    their first columns world x (world y near x) made orthogonal to them."""
    z = axes / norm(axes)[:, None]
    ref = np.where((np.abs(z[:, :1]) < 0.9), _X, _Y)
    x = ref - (ref * z).sum(axis=1)[:, None] * z
    x /= norm(x)[:, None]
    return np.stack([x, cross(z, x), z], axis=2)


def batch_geometry(
    kind: str, thetas: np.ndarray, r0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centres (K, 3) m, rotations (K, 3, 3), half sizes (K, s) m) of K parameter vectors
    (K, k) about the start orientation ``r0`` (3, 3), or each about its own (K, 3, 3)."""
    cls = KINDS[kind]
    K = len(thetas)
    lo, hi = LOG_SIZE_RANGE
    half = np.exp(np.minimum(np.maximum(thetas[:, SIZE_INDEX[kind][0] :], lo), hi))
    if cls.orientation == "none":
        rotations = np.broadcast_to(np.eye(3), (K, 3, 3))
    elif cls.orientation == "rotation":
        rotations = r0 @ rotation_matrices(thetas[:, 3:6])
    else:
        tilt = np.concatenate([thetas[:, 3:5], np.ones((K, 1))], axis=1)
        rotations = frames_with_z(tilt @ r0.T if r0.ndim == 2 else np.einsum("kij,kj->ki", r0, tilt))
    return thetas[:, :3], rotations, half


def whitened_residuals(thetas: np.ndarray, kind: str, r0: np.ndarray, touches: Touches) -> np.ndarray:
    """Whitened residuals (K, m) of K parameter vectors: per contact the tip centre's distance
    ``(sd(c) − r − gap₀)/σ_d`` and the normal ``(∇sd(c) − n)/σ_n``; per free sample the hinge
    ``min(sd(f) − r, 0)/σ_d``: by the compiled loop once loaded (:mod:`eos_svc.shape.kernels`),
    else by :func:`numpy_residuals`."""
    kernel = kernels.compiled_residuals()
    if kernel is None or kind not in kernels.KIND_CODES:
        return numpy_residuals(thetas, kind, r0, touches)
    return kernel_residuals(kernel, thetas, kind, r0, touches)


def kernel_residuals(
    kernel: Callable[..., np.ndarray], thetas: np.ndarray, kind: str, r0: np.ndarray, touches: Touches
) -> np.ndarray:
    """:func:`whitened_residuals` by the compiled loop ``kernel``
    (:func:`eos_svc.shape.compiled.residuals`)."""
    r0s = np.empty((len(thetas), 3, 3))
    r0s[:] = r0
    t, thetas = touches, np.ascontiguousarray(thetas, dtype=float)
    out: np.ndarray = kernel(
        kernels.KIND_CODES[kind], SIZE_INDEX[kind][0], thetas, r0s, LOG_SIZE_RANGE,
        t.points, t.count, t.radii, t.normals, t.free_radii, t.gap_offset, t.sigma_distance, t.sigma_normal,
    )  # fmt: skip
    return out


def numpy_residuals(thetas: np.ndarray, kind: str, r0: np.ndarray, touches: Touches) -> np.ndarray:
    """:func:`whitened_residuals` in numpy, with the kinds' own distances
    (:meth:`~eos_svc.objects.base.SurfaceObject.local_distance`): the plain version."""
    centres, rotations, half = batch_geometry(kind, thetas, r0)
    local = (touches.points[None] - centres[:, None]) @ rotations
    d, g = KINDS[kind].local_distance(local, half[:, None, :])
    g = g @ rotations.transpose(0, 2, 1)
    n, sigma = touches.count, touches.sigma_distance
    r_d = (d[:, :n] - touches.radii - touches.gap_offset) / sigma
    r_n = ((g[:, :n] - touches.normals) / touches.sigma_normal).reshape(len(thetas), -1)
    r_f = np.minimum(d[:, n:] - touches.free_radii, 0.0) / sigma
    return np.concatenate([r_d, r_n, r_f], axis=1)


def residual_count(touches: Touches) -> int:
    """m, the number of whitened residuals: a distance and three normal components per
    contact, a hinge per free sample."""
    return 4 * touches.count + len(touches.free)


class Problem:
    """One fit's residuals (one kind, start orientation and set of touches) and their forward
    difference Jacobian (the box's and cylinder's kinks defeat a central one), evaluated in one
    batch and remembered per point: a refit from the same start finds its first steps known."""

    def __init__(self, kind: str, r0: np.ndarray, touches: Touches) -> None:
        self.kind, self.r0, self.touches = kind, r0, touches
        self.known: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        k = N_PARAMS[kind]
        self.steps = np.eye(k + 1, k, -1)  # θ, then θ + h_i e_i: rows 0, e_1, …, e_k times h

    def evaluate(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(whitened residuals (m,), Jacobian (m, k)) at ``theta``."""
        key = theta.tobytes()
        known = self.known.get(key)
        if known is None:
            h = JACOBIAN_STEP * np.maximum(1.0, np.abs(theta))
            R = whitened_residuals(theta + self.steps * h, self.kind, self.r0, self.touches)
            known = self.known[key] = (R[0], ((R[1:] - R[0]) / h[:, None]).T)
        return known

    def residuals(self, theta: np.ndarray, *_: object) -> np.ndarray:
        """The residuals at ``theta`` (a copy: MINPACK works in the arrays it is given)."""
        return self.evaluate(theta)[0].copy()

    def jacobian(self, theta: np.ndarray, *_: object) -> np.ndarray:
        """The Jacobian at ``theta`` (a copy)."""
        return self.evaluate(theta)[1].copy()


def fitted_object(kind: str, theta: np.ndarray, r0: np.ndarray) -> SurfaceObject:
    """The object of ``kind`` that the parameters ``theta`` about the start orientation ``r0``
    describe."""
    centres, rotations, half = batch_geometry(kind, np.asarray(theta)[None], r0)
    return KINDS[kind].from_half_sizes(half[0], pin.SE3(rotations[0], centres[0]))


@dataclass(frozen=True)
class ClassFit:
    """The best fit of one kind: χ² (Σ of the squared whitened residuals at the optimum), its k
    parameters ``theta`` about the start orientation ``r0`` with their (k, k) covariance, and the
    index of the start it began from."""

    kind: str
    chi2: float
    n_params: int
    covariance: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    r0: np.ndarray = field(repr=False)
    start: int = 0

    @cached_property
    def geometry(self) -> SurfaceObject:
        """The fitted object (made when first asked for: a selection needs the chosen kind's)."""
        return fitted_object(self.kind, self.theta, self.r0)

    def size_sigmas(self) -> np.ndarray:
        """σ of the log sizes (≈ relative σ of each size)."""
        idx = list(SIZE_INDEX[self.kind])
        return np.sqrt(np.maximum(np.diag(self.covariance)[idx], 0.0))

    def centre_sigmas(self) -> np.ndarray:
        """σ of the centre coordinates (m)."""
        return np.sqrt(np.maximum(np.diag(self.covariance)[:3], 0.0))


def explains(chi2: float, touches: Touches, kind: str) -> bool:
    """Whether a fit of ``kind`` with this χ² explains the touches to within the noise
    (χ²/dof ≤ GOOD_FIT over all the whitened residuals): :func:`fit_class` then tries no
    other start."""
    return chi2 <= GOOD_FIT * max(residual_count(touches) - N_PARAMS[kind], 1)


def nearest_order(kind: str, starts: ClassStarts) -> list[int]:
    """Indices of ``kind``'s starts from the lowest χ² at the start itself (ties in order)."""
    candidates = starts.of(kind)
    if len(candidates) < 2:
        return list(range(len(candidates)))
    thetas = np.array([theta0 for theta0, _ in candidates])
    r0s = np.array([r0 for _, r0 in candidates])
    chi2 = np.sum(whitened_residuals(thetas, kind, r0s, starts.touches) ** 2, axis=1)
    return sorted(range(len(candidates)), key=lambda i: float(chi2[i]))


def _minimise(
    problem: Problem, theta0: np.ndarray, max_nfev: int, levenberg_marquardt: bool
) -> tuple[np.ndarray, np.ndarray]:
    """(θ, whitened residuals at θ) minimising their squares from ``theta0`` in at most
    ``max_nfev`` evaluations: MINPACK's Levenberg–Marquardt (``leastsq``, what
    ``least_squares(method="lm", x_scale="jac")`` runs) when ``levenberg_marquardt`` (at least
    as many residuals as parameters), else ``least_squares(method="trf")``."""
    f, jac = problem.residuals, problem.jacobian
    if levenberg_marquardt:
        # without full_output leastsq skips a covariance (it costs a short fit's time) but warns when
        # it stops at max_nfev, as a quick fit is meant to
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            theta, _ = leastsq(f, theta0, Dfun=jac, maxfev=max_nfev, **TOLERANCES)
        return theta, problem.evaluate(theta)[0]
    res = least_squares(f, theta0, jac=jac, method="trf", x_scale="jac", max_nfev=max_nfev, **TOLERANCES)
    return res.x, res.fun


def fit_class(
    kind: str,
    touches: Touches,
    max_nfev: int = 20,
    hopeless: float = math.inf,
    max_starts: int | None = None,
    nearest_first: bool = False,
    class_starts: ClassStarts | None = None,
    only: int | None = None,
) -> ClassFit:
    """The least-squares fit of ``kind``, the best of its starts (:func:`_minimise` from each) up
    to one that :func:`explains` the touches or ends above ``hopeless`` (χ²). ``max_starts``: at
    most that many; ``nearest_first``: from the nearest (:func:`nearest_order`); ``class_starts``:
    the touches' starts, shared by several kinds' fits; ``only``: that start alone."""
    if kind not in N_PARAMS:
        raise ValueError(f"unknown class {kind!r} (choose from {', '.join(N_PARAMS)})")
    k, m = N_PARAMS[kind], residual_count(touches)
    shared = ClassStarts(touches) if class_starts is None else class_starts
    candidates = shared.of(kind)
    order = nearest_order(kind, shared) if nearest_first else range(len(candidates))
    if only is not None:
        order = [only]
    best = None
    for index in list(order)[:max_starts]:
        theta0, r0 = candidates[index]
        problem = shared.problem(kind, index, partial(Problem, kind, r0, touches))
        theta, fun = _minimise(problem, theta0, max_nfev, levenberg_marquardt=m >= k)
        chi2 = float(fun @ fun)
        if best is None or chi2 < best[0]:
            best = (chi2, theta, problem, r0, index)
        if explains(chi2, touches, kind) or chi2 > hopeless:
            break
    assert best is not None
    chi2, theta, problem, r0, index = best
    J = problem.jacobian(theta)
    # a direction no residual constrains (e.g. a length at its bound) gets a variance of
    # 1/RIDGE, not pinv's 0
    cov = np.linalg.inv(J.T @ J + RIDGE * np.eye(k)) * max(1.0, chi2 / max(m - k, 1))
    return ClassFit(kind, chi2, k, cov, theta, r0, index)


def size_axis(fit: ClassFit, n: int) -> np.ndarray | None:
    """The world direction along which ``fit``'s ``n``-th size lies, between two opposite faces:
    a rotated kind's n-th axis, an axis-oriented kind's axis for its last size (the length);
    None for a radius (no face of its own)."""
    orientation = KINDS[fit.kind].orientation
    R = fit.geometry.rotation
    if orientation == "rotation":
        return np.asarray(R[:, n])
    if orientation == "axis" and n == len(SIZE_INDEX[fit.kind]) - 1:
        return np.asarray(R[:, 2])
    return None


def face_moved(fit: ClassFit, n: int, factor: float, side: float, axis: np.ndarray) -> np.ndarray:
    """``fit``'s parameters with its ``n``-th size times ``factor`` and the face toward
    −``side`` · ``axis`` kept where it is (the centre shifted by the change; a zero ``axis``:
    the size changes about the centre)."""
    t = fit.theta.copy()
    t[SIZE_INDEX[fit.kind][n]] += math.log(factor)
    t[:3] += side * (factor - 1.0) * fit.geometry.half_sizes[n] * axis
    return t


def extent_ratios(fit: ClassFit, touches: Touches, step: float = 0.10) -> np.ndarray:
    """Per size of ``fit``: the largest likelihood ratio ``exp(−Δχ²/2)`` of the same object with
    that size ``step`` larger or smaller while one of its two faces along that direction stays
    put (the centre shifted by the change), against the fit. ≈ 0 when the touches bound the
    size on both sides; ≈ 1 when one side is free — a far face no contact or free sample sees
    (the least-squares covariance, a local quadratic, misses that)."""
    kind = fit.kind
    variants, owners = [], []
    for n in range(len(SIZE_INDEX[kind])):
        axis = size_axis(fit, n)
        if axis is None:
            axis = np.zeros(3)  # a radius: both sides move together
        for factor in (1.0 + step, 1.0 - step):
            for side in (1.0, -1.0):
                variants.append(face_moved(fit, n, factor, side, axis))
                owners.append(n)
    Rv = whitened_residuals(np.array(variants), kind, fit.r0, touches)
    delta = np.maximum(np.sum(Rv * Rv, axis=1) - fit.chi2, 0.0)
    ratios = np.zeros(len(SIZE_INDEX[kind]))
    for n, d in zip(owners, delta, strict=True):
        ratios[n] = max(ratios[n], math.exp(-0.5 * float(d)))
    return ratios
