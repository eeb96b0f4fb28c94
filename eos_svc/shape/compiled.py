"""The fit's whitened residuals as one compiled loop (numba): the optional accelerator of
:func:`eos_svc.shape.fit.whitened_residuals`, the same quantities point by point (the
ellipsoid's Newton iteration stops per point), equal to the numpy version to rounding
(``tests/shape/test_compiled.py``). Imported only by :func:`eos_svc.shape.kernels.load`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Newton iterations at most and the relative step that ends them (as :mod:`eos_svc.objects.ellipsoid`)
ITERATIONS, STEP_TOLERANCE = 30, 1e-12
TINY = 1e-15


@njit(cache=True)
def _rotation(code: int, theta: np.ndarray, r0: np.ndarray, R: np.ndarray) -> None:  # pragma: no cover
    """``R`` (3, 3) ← the world ← local rotation of parameters ``theta`` about ``r0`` (3, 3)
    (a sphere's: left as it is), in scalars (a 3×3 product through BLAS costs more)."""
    if code == 1 or code == 2:  # R0·exp([ω]×), exp([ω]×) = I + sin θ [k]× + (1 − cos θ) [k]×² (Rodrigues)
        w0, w1, w2 = theta[3], theta[4], theta[5]
        angle = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        s = max(angle, 1e-12)
        k0, k1, k2 = w0 / s, w1 / s, w2 / s
        a, b = math.sin(angle), 1.0 - math.cos(angle)
        E = (
            (1.0 - b * (k1 * k1 + k2 * k2), -a * k2 + b * k0 * k1, a * k1 + b * k0 * k2),
            (a * k2 + b * k0 * k1, 1.0 - b * (k0 * k0 + k2 * k2), -a * k0 + b * k1 * k2),
            (-a * k1 + b * k0 * k2, a * k0 + b * k1 * k2, 1.0 - b * (k0 * k0 + k1 * k1)),
        )
        for i in range(3):
            for j in range(3):
                R[i, j] = r0[i, 0] * E[0][j] + r0[i, 1] * E[1][j] + r0[i, 2] * E[2][j]
    elif code == 3 or code == 4:  # axis R0·(α, β, 1), normalised; x from world x (or y)
        a, b = theta[3], theta[4]
        z0 = r0[0, 0] * a + r0[0, 1] * b + r0[0, 2]
        z1 = r0[1, 0] * a + r0[1, 1] * b + r0[1, 2]
        z2 = r0[2, 0] * a + r0[2, 1] * b + r0[2, 2]
        n = math.sqrt(z0 * z0 + z1 * z1 + z2 * z2)
        z0, z1, z2 = z0 / n, z1 / n, z2 / n
        rx = 1.0 if abs(z0) < 0.9 else 0.0  # x from world x, or y when z is near x
        d = rx * z0 + (1.0 - rx) * z1
        x0, x1, x2 = rx - d * z0, (1.0 - rx) - d * z1, -d * z2
        n = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        x0, x1, x2 = x0 / n, x1 / n, x2 / n
        R[0, 0], R[1, 0], R[2, 0] = x0, x1, x2
        R[0, 1], R[1, 1], R[2, 1] = z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0
        R[0, 2], R[1, 2], R[2, 2] = z0, z1, z2


@njit(cache=True)
def _ellipsoid(
    p0: float, p1: float, p2: float, a0: float, a1: float, a2: float
) -> tuple[float, float, float, float]:  # pragma: no cover
    """(signed distance, gradient) of local point ``p`` to the ellipsoid of semi-axes ``a``
    (:func:`eos_svc.objects.ellipsoid.closest_points`, one point)."""
    s0, s1, s2 = a0 * a0, a1 * a1, a2 * a2
    inside = (p0 / a0) ** 2 + (p1 / a1) ** 2 + (p2 / a2) ** 2 < 1.0
    pole = -min(s0, s1, s2) * (1.0 - 1e-12)
    t = max(a0 * abs(p0) - s0, a1 * abs(p1) - s1, a2 * abs(p2) - s2, pole if inside else 0.0)
    u0, u1, u2 = (a0 * p0) ** 2, (a1 * p1) ** 2, (a2 * p2) ** 2
    for _ in range(ITERATIONS):
        i0, i1, i2 = 1.0 / (t + s0), 1.0 / (t + s1), 1.0 / (t + s2)
        v0, v1, v2 = u0 * i0 * i0, u1 * i1 * i1, u2 * i2 * i2
        total = v0 + v1 + v2
        slope = v0 * i0 + v1 * i1 + v2 * i2
        step = total * (math.sqrt(total) - 1.0) / max(slope, 1e-300)
        t = max(t + step, pole)
        if abs(step) <= STEP_TOLERANCE * (1e-6 + abs(t)):
            break
    c0, c1, c2 = s0 * p0 / (t + s0), s1 * p1 / (t + s1), s2 * p2 / (t + s2)
    if inside and t <= pole:  # no root right of the pole: the closest point off the short axis
        c0, c1, c2 = _pole_point(p0, p1, p2, a0, a1, a2)
    scale = math.sqrt((c0 / a0) ** 2 + (c1 / a1) ** 2 + (c2 / a2) ** 2)
    c0, c1, c2 = c0 / scale, c1 / scale, c2 / scale  # exactly on the surface
    w0, w1, w2 = p0 - c0, p1 - c1, p2 - c2
    dist = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    sign = -1.0 if inside else 1.0
    if dist > 1e-12:
        return sign * dist, sign * w0 / dist, sign * w1 / dist, sign * w2 / dist
    n0, n1, n2 = c0 / s0, c1 / s1, c2 / s2  # on the surface: the normal there
    length = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if length > 1e-12:
        return sign * dist, n0 / length, n1 / length, n2 / length
    return sign * dist, 0.0, 0.0, 1.0


@njit(cache=True)
def _pole_point(
    p0: float, p1: float, p2: float, a0: float, a1: float, a2: float
) -> tuple[float, float, float]:  # pragma: no cover
    """The closest point of an inside point with no root right of the pole, on the side of
    ``p`` along the shortest axis (:func:`eos_svc.objects.ellipsoid._pole_points`)."""
    p, a = (p0, p1, p2), (a0, a1, a2)
    k = 0 if a0 <= a1 and a0 <= a2 else (1 if a1 <= a2 else 2)
    out = [0.0, 0.0, 0.0]
    rest = 1.0
    for i in range(3):
        off = a[i] * a[i] - a[k] * a[k]
        if off > 0.0:
            out[i] = a[i] * a[i] * p[i] / off
            rest -= (out[i] / a[i]) ** 2
    out[k] = (-1.0 if p[k] < 0.0 else 1.0) * a[k] * math.sqrt(max(rest, 0.0))
    return out[0], out[1], out[2]


@njit(cache=True)
def _distance(
    code: int, p0: float, p1: float, p2: float, h: np.ndarray
) -> tuple[float, float, float, float]:  # pragma: no cover
    """(signed distance, gradient) of local point ``p`` to a kind of half sizes ``h``."""
    if code == 0 or code == 4:  # sphere: |p| − r; capsule: the same about the axis segment
        w2 = p2 - min(max(p2, -h[1]), h[1]) if code == 4 else p2
        n = math.sqrt(p0 * p0 + p1 * p1 + w2 * w2)
        if n > 1e-12:
            return n - h[0], p0 / n, p1 / n, w2 / n
        return (n - h[0], 0.0, 0.0, 1.0) if code == 0 else (n - h[0], 1.0, 0.0, 0.0)
    if code == 1:
        return _ellipsoid(p0, p1, p2, h[0], h[1], h[2])
    if code == 2:  # box
        q0, q1, q2 = abs(p0) - h[0], abs(p1) - h[1], abs(p2) - h[2]
        e0, e1, e2 = max(q0, 0.0), max(q1, 0.0), max(q2, 0.0)
        out = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        x, y, z = 1.0 if p0 >= 0.0 else -1.0, 1.0 if p1 >= 0.0 else -1.0, 1.0 if p2 >= 0.0 else -1.0
        inner = min(max(q0, q1, q2), 0.0)
        if out > TINY:
            return out + inner, x * e0 / out, y * e1 / out, z * e2 / out
        if q0 >= q1 and q0 >= q2:  # the nearest face, the first of equals
            return out + inner, x, 0.0, 0.0
        if q1 >= q2:
            return out + inner, 0.0, y, 0.0
        return out + inner, 0.0, 0.0, z
    # cylinder
    rho = math.hypot(p0, p1)
    rx, ry = (p0 / rho, p1 / rho) if rho > TINY else (1.0, 0.0)
    sz = 1.0 if p2 >= 0.0 else -1.0
    dr, dz = rho - h[0], abs(p2) - h[1]
    a, b = max(dr, 0.0), max(dz, 0.0)
    out = math.hypot(a, b)
    d = out + min(max(dr, dz), 0.0)
    if out > TINY:
        return d, a * rx / out, a * ry / out, b * sz / out
    if dr > dz:
        return d, rx, ry, 0.0
    return d, 0.0, 0.0, sz


@njit(cache=True)
def residuals(
    code: int,
    first: int,
    thetas: np.ndarray,
    r0s: np.ndarray,
    log_size_range: tuple[float, float],
    points: np.ndarray,
    count: int,
    radii: np.ndarray,
    normals: np.ndarray,
    free_radii: np.ndarray,
    gap_offset: float,
    sigma_distance: float,
    sigma_normal: float,
) -> np.ndarray:  # pragma: no cover
    """Whitened residuals (K, m) of K parameter vectors ``thetas`` (K, k) of the kind ``code``
    (:data:`eos_svc.shape.kernels.KIND_CODES`; its log sizes from index ``first``), each about
    its start orientation ``r0s`` (K, 3, 3), at the touches (``points``: the contacts' tip centres, then
    the free samples'; the rest as :class:`eos_svc.shape.touches.Touches`)."""
    K, N = thetas.shape[0], points.shape[0]
    out = np.empty((K, 4 * count + N - count))
    half = np.empty(3)
    R = np.eye(3)
    for row in range(K):
        theta = thetas[row]
        for j in range(thetas.shape[1] - first):
            half[j] = math.exp(min(max(theta[first + j], log_size_range[0]), log_size_range[1]))
        _rotation(code, theta, r0s[row], R)
        for n in range(N):
            x, y, z = points[n, 0] - theta[0], points[n, 1] - theta[1], points[n, 2] - theta[2]
            d, g0, g1, g2 = _distance(
                code,
                x * R[0, 0] + y * R[1, 0] + z * R[2, 0],
                x * R[0, 1] + y * R[1, 1] + z * R[2, 1],
                x * R[0, 2] + y * R[1, 2] + z * R[2, 2],
                half,
            )
            if n < count:
                out[row, n] = (d - radii[n] - gap_offset) / sigma_distance
                for i in range(3):
                    world = R[i, 0] * g0 + R[i, 1] * g1 + R[i, 2] * g2
                    out[row, count + 3 * n + i] = (world - normals[n, i]) / sigma_normal
            else:
                out[row, 3 * count + n] = min(d - free_radii[n - count], 0.0) / sigma_distance
    return out


def warm_up() -> None:
    """Compile (or load from numba's cache) :func:`residuals`: one call per kind."""
    from eos_svc.shape.fit import N_PARAMS, SIZE_INDEX, kernel_residuals
    from eos_svc.shape.kernels import KIND_CODES
    from eos_svc.shape.touches import Touches

    radii, free = np.full(3, 0.01), np.array([[0.0, 0.0, 0.2]])
    touches = Touches(np.eye(3) * 0.05, np.eye(3), radii, free, radii[:1])
    for kind in KIND_CODES:
        theta = np.zeros((1, N_PARAMS[kind]))
        theta[:, SIZE_INDEX[kind][0] :] = math.log(0.04)
        kernel_residuals(residuals, theta, kind, np.eye(3), touches)
