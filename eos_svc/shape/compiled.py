"""The shape fit's whitened residuals as one compiled kernel (numba), for K parameter vectors.

:func:`residuals_and_geometry` computes what the numpy reference
(:func:`eos_svc.shape.fit._residuals_and_geometry_numpy`) computes — the geometry of each
parameter vector (:func:`~eos_svc.shape.fit.batch_geometry`), the signed distance and gradient
of its primitive (:mod:`eos_svc.shape.primitives`) at the contacts and the free samples, the
whitened residuals — as scalar loops, operation for operation in the reference's order, so
that the bits agree; :func:`difference_evaluation` does the same for a point of the fit and
its k forward-difference neighbours, with the Jacobian's quotients, in one call. numpy's
per-call overhead on these small arrays (a few hundred numbers, some sixty calls) is what the
reference spends its time on; here one call does it all.

Four things the reference does implicitly are spelled out:

* **Matrix products.** numpy hands ``@`` to OpenBLAS, whose double-precision kernels on this
  machine's x86-64 (Haswell and later: fused multiply-add) sum a length-3 product as
  ``fma(a₂, b₂, fma(a₁, b₁, a₀·b₀))`` for a matrix of two rows or more; a single row times a
  transposed matrix (``gemv``) as ``fma(a₂, b₂, fma(a₀, b₀, a₁·b₁))``; a single row times a
  matrix as ``(a₀b₀ + a₁b₁) + a₂b₂`` (numpy's own loop). ``np.einsum("kij,kj->ki")`` sums
  ``(a₀b₀ + a₂b₂) + a₁b₁``. :func:`blas_products_agree` checks the first of these on the BLAS
  at hand; another BLAS rounds these products otherwise (a few ulps: the kernel is then as
  accurate as the reference, not its bits).
* **The ellipsoid's Newton iteration** stops per *group* of rows — the whole call, or each of
  the reference's ``groups`` — when the group's largest relative step is below 1e-12 (at most
  30 iterations), as :func:`~eos_svc.shape.primitives.ellipsoid_planes` does; the other
  classes' rows are independent, so for them ``groups`` only selects which matrix product
  the cylinder's and capsule's axes come from (a group of one row: ``gemv``).
* **numpy's ``maximum``/``minimum``** return their first argument on ties (and NaN): so do
  :func:`_maximum` and :func:`_minimum`.
* **exp, sin and cos** are the C library's on both sides: the kernels' ``math`` functions
  (numba without Intel's SVML) and, in the reference, :func:`~eos_svc.shape.fit.libm_exp` and
  :func:`~eos_svc.shape.fit.libm_sin_cos` (numpy's own, dispatched by CPU, may round otherwise).

The kernels use numpy's error model (a division by zero gives ±inf or NaN, as in the
reference, not Python's exception). Every kernel is compiled on first use and cached on disk
(``cache=True``, in ``__pycache__``); :func:`warm_up` compiles or loads them all, and only then
does the fit use them (:mod:`eos_svc.shape.kernels`: until then it runs its numpy reference).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from eos_svc.shape import kernels

#: the classes' codes in the kernel, and each one's first log-size parameter and size count
KIND_CODE = {"sphere": 0, "ellipsoid": 1, "box": 2, "cylinder": 3, "capsule": 4}
_SIZE_FIRST = np.array([3, 6, 6, 5, 5])
_SIZE_COUNT = np.array([1, 3, 3, 2, 2])
#: axis matrix product modes (see the module docstring): gemm, gemv of a transposed, einsum
_GEMM, _GEMV_T, _EINSUM = 0, 1, 2
_TINY = 1e-15
#: the ellipsoid's Newton iterations at most, and its relative step bound
_ITERATIONS = 30
_STEP_BOUND = 1e-12
#: groups=None: the whole call is one group
_ONE_GROUP = np.zeros(1, dtype=np.int64)
#: the touches as the kernels take them: (points (N, 3), count, radii (count,), sensed normals
#: (count, 3), free radii (N − count,), gap offset, σ distance, σ normal) — the fit's
#: :attr:`eos_svc.shape.fit.FitData.kernel_touches`
KernelTouches = tuple[np.ndarray, int, np.ndarray, np.ndarray, np.ndarray, float, float, float]


@intrinsic
def _fma_intrinsic(typingctx: Any, a: Any, b: Any, c: Any) -> tuple[Any, Callable[..., Any]]:
    """``a·b + c`` rounded once (LLVM's ``llvm.fma.f64``: the hardware's fused multiply-add)."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.fma.f64")
        return builder.call(fn, args)

    return signature, codegen


#: the intrinsic as compiled code calls it, ``_fma(a, b, c)`` (the typing context is numba's)
_fma = cast(Callable[[float, float, float], float], _fma_intrinsic)


@numba.njit(cache=True, error_model="numpy", inline="always")
def _maximum(a: float, b: float) -> float:
    """``np.maximum(a, b)``: ``a`` when ``a ≥ b`` or ``a`` is NaN, else ``b``."""
    return a if (a >= b or a != a) else b


@numba.njit(cache=True, error_model="numpy", inline="always")
def _minimum(a: float, b: float) -> float:
    """``np.minimum(a, b)``: ``a`` when ``a ≤ b`` or ``a`` is NaN, else ``b``."""
    return a if (a <= b or a != a) else b


@numba.njit(cache=True, error_model="numpy", inline="always")
def _dot3(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> float:
    """A length-3 product as OpenBLAS's gemm sums it: ``fma(a₂, b₂, fma(a₁, b₁, a₀·b₀))``."""
    return _fma(a2, b2, _fma(a1, b1, a0 * b0))


@numba.njit(cache=True, error_model="numpy")
def _axis_about(mode: int, t3: float, t4: float, r0: np.ndarray, out: np.ndarray) -> None:
    """``r0 · (t3, t4, 1)`` into ``out`` (3,), summed as the reference's product ``mode``."""
    for i in range(3):
        a, b, c = r0[i, 0], r0[i, 1], r0[i, 2]
        if mode == _GEMM:
            out[i] = _fma(1.0, c, _fma(t4, b, t3 * a))
        elif mode == _GEMV_T:
            out[i] = _fma(1.0, c, _fma(t3, a, t4 * b))
        else:
            out[i] = (t3 * a + 1.0 * c) + t4 * b


@numba.njit(cache=True, error_model="numpy")
def _geometry(
    kind: int,
    thetas: np.ndarray,
    r0s: np.ndarray,
    per_row: bool,
    grouped: bool,
    groups: np.ndarray,
    log_lo: float,
    log_hi: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`~eos_svc.shape.fit.batch_geometry`: (centres (K, 3), rotations (K, 3, 3), sizes
    (K, s)) of the parameter vectors ``thetas`` (K, k) about ``r0s`` ((1 or K), 3, 3)."""
    K = thetas.shape[0]
    first, count = _SIZE_FIRST[kind], _SIZE_COUNT[kind]
    centres = np.empty((K, 3))
    sizes = np.empty((K, count))
    rotations = np.zeros((K, 3, 3))
    # the group (first row, size) of every row, for the axes' matrix products
    group_first = np.zeros(K, dtype=np.int64)
    group_size = np.full(K, K, dtype=np.int64)
    if grouped:
        for g in range(len(groups)):
            lo = groups[g]
            hi = groups[g + 1] if g + 1 < len(groups) else K
            for row in range(lo, hi):
                group_first[row] = lo
                group_size[row] = hi - lo
    Kx = np.empty((3, 3))
    rod = np.empty((3, 3))
    axis = np.empty(3)
    for row in range(K):
        for j in range(3):
            centres[row, j] = thetas[row, j]
        for j in range(count):
            sizes[row, j] = math.exp(_minimum(_maximum(thetas[row, first + j], log_lo), log_hi))
        if kind == 0:
            for j in range(3):
                rotations[row, j, j] = 1.0
        elif kind == 1 or kind == 2:
            # Rodrigues, as fit._batch_rotation_vectors: I + sin θ [k]× + (1 − cos θ) [k]×²
            w0, w1, w2 = thetas[row, 3], thetas[row, 4], thetas[row, 5]
            theta = math.sqrt((w0 * w0 + w1 * w1) + w2 * w2)
            scale = _maximum(theta, 1e-12)
            k0, k1, k2 = w0 / scale, w1 / scale, w2 / scale
            Kx[0, 0], Kx[0, 1], Kx[0, 2] = 0.0, k2 * -1.0, k1 * 1.0
            Kx[1, 0], Kx[1, 1], Kx[1, 2] = k2 * 1.0, 0.0, k0 * -1.0
            Kx[2, 0], Kx[2, 1], Kx[2, 2] = k1 * -1.0, k0 * 1.0, 0.0
            s, c = math.sin(theta), math.cos(theta)
            for i in range(3):
                for j in range(3):
                    kk = _dot3(Kx[i, 0], Kx[i, 1], Kx[i, 2], Kx[0, j], Kx[1, j], Kx[2, j])
                    rod[i, j] = ((1.0 if i == j else 0.0) + s * Kx[i, j]) + (1.0 - c) * kk
            r0 = r0s[row] if per_row else r0s[0]
            for i in range(3):
                for j in range(3):
                    rotations[row, i, j] = _dot3(
                        r0[i, 0], r0[i, 1], r0[i, 2], rod[0, j], rod[1, j], rod[2, j]
                    )
        else:
            # the tilted axis r0 · (α, β, 1), then fit._batch_frames_with_z
            if per_row and grouped:
                mode, r0 = (_GEMV_T if group_size[row] == 1 else _GEMM), r0s[group_first[row]]
            elif per_row:
                mode, r0 = _EINSUM, r0s[row]
            else:
                mode, r0 = (_GEMV_T if group_size[row] == 1 else _GEMM), r0s[0]
            _axis_about(mode, thetas[row, 3], thetas[row, 4], r0, axis)
            length = math.sqrt((axis[0] * axis[0] + axis[1] * axis[1]) + axis[2] * axis[2])
            z0, z1, z2 = axis[0] / length, axis[1] / length, axis[2] / length
            a0, a1, a2 = (1.0, 0.0, 0.0) if abs(z0) < 0.9 else (0.0, 1.0, 0.0)
            dot = (a0 * z0 + a1 * z1) + a2 * z2
            x0, x1, x2 = a0 - dot * z0, a1 - dot * z1, a2 - dot * z2
            nx = math.sqrt((x0 * x0 + x1 * x1) + x2 * x2)
            x0, x1, x2 = x0 / nx, x1 / nx, x2 / nx
            y0, y1, y2 = z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0
            rotations[row, 0, 0], rotations[row, 1, 0], rotations[row, 2, 0] = x0, x1, x2
            rotations[row, 0, 1], rotations[row, 1, 1], rotations[row, 2, 1] = y0, y1, y2
            rotations[row, 0, 2], rotations[row, 1, 2], rotations[row, 2, 2] = z0, z1, z2
    return centres, rotations, sizes


@numba.njit(cache=True, error_model="numpy")
def _local_points(
    kind: int, points: np.ndarray, centres: np.ndarray, rotations: np.ndarray
) -> np.ndarray:
    """``(points − centre) @ rotation`` (K, N, 3) as numpy's product computes it (gemm for
    two points or more, numpy's own loop for one; the sphere's identity: the offsets)."""
    K, N = centres.shape[0], points.shape[0]
    local = np.empty((K, N, 3))
    for row in range(K):
        R = rotations[row]
        for i in range(N):
            o0 = points[i, 0] - centres[row, 0]
            o1 = points[i, 1] - centres[row, 1]
            o2 = points[i, 2] - centres[row, 2]
            for j in range(3):
                if kind == 0:
                    local[row, i, j] = o0 if j == 0 else (o1 if j == 1 else o2)
                elif N == 1:
                    local[row, i, j] = (o0 * R[0, j] + o1 * R[1, j]) + o2 * R[2, j]
                else:
                    local[row, i, j] = _dot3(o0, o1, o2, R[0, j], R[1, j], R[2, j])
    return local


@numba.njit(cache=True, error_model="numpy")
def _ellipsoid(
    local: np.ndarray, sizes: np.ndarray, groups: np.ndarray, d: np.ndarray, g: np.ndarray
) -> None:
    """:func:`~eos_svc.shape.primitives.ellipsoid_planes` on every row's points: the exact
    closest point by Newton's method from the same lower bound, each group of rows (``groups``:
    first rows) iterated until its largest relative step is below 1e-12 (≤ 30 iterations);
    the distance into ``d`` (K, N), the local gradient into ``g`` (K, N, 3)."""
    K, N = local.shape[0], local.shape[1]
    t = np.empty((K, N))
    inside = np.empty((K, N), dtype=np.bool_)
    for row in range(K):
        a0, a1, a2 = sizes[row, 0], sizes[row, 1], sizes[row, 2]
        for i in range(N):
            p0, p1, p2 = local[row, i, 0], local[row, i, 1], local[row, i, 2]
            u0, u1, u2 = p0 / a0, p1 / a1, p2 / a2
            inside[row, i] = (u0 * u0 + u1 * u1) + u2 * u2 < 1.0
            amin = _minimum(_minimum(a0, a1), a2)
            floor = -(amin * amin) * (1.0 - 1e-12) if inside[row, i] else 0.0
            low0, low1, low2 = a0 * abs(p0) - a0 * a0, a1 * abs(p1) - a1 * a1, a2 * abs(p2) - a2 * a2
            t[row, i] = _maximum(_maximum(_maximum(low0, low1), low2), floor)
    for gi in range(len(groups)):
        lo = groups[gi]
        hi = groups[gi + 1] if gi + 1 < len(groups) else K
        for _ in range(_ITERATIONS):
            largest = 0.0
            for row in range(lo, hi):
                a0, a1, a2 = sizes[row, 0], sizes[row, 1], sizes[row, 2]
                b0, b1, b2 = a0 * a0, a1 * a1, a2 * a2
                for i in range(N):
                    q0, q1, q2 = a0 * local[row, i, 0], a1 * local[row, i, 1], a2 * local[row, i, 2]
                    tt = t[row, i]
                    inv0, inv1, inv2 = 1.0 / (tt + b0), 1.0 / (tt + b1), 1.0 / (tt + b2)
                    uu0, uu1, uu2 = q0 * q0 * inv0 * inv0, q1 * q1 * inv1 * inv1, q2 * q2 * inv2 * inv2
                    total = (uu0 + uu1) + uu2
                    slope = (uu0 * inv0 + uu1 * inv1) + uu2 * inv2
                    step = total * (math.sqrt(total) - 1.0) / _maximum(slope, 1e-300)
                    tt = tt + step
                    t[row, i] = tt
                    largest = _maximum(largest, abs(step) / (1e-6 + abs(tt)))
            if largest < _STEP_BOUND:
                break
    for row in range(K):
        a0, a1, a2 = sizes[row, 0], sizes[row, 1], sizes[row, 2]
        b0, b1, b2 = a0 * a0, a1 * a1, a2 * a2
        for i in range(N):
            p0, p1, p2 = local[row, i, 0], local[row, i, 1], local[row, i, 2]
            tt = t[row, i]
            s0, s1, s2 = b0 * p0 / (tt + b0), b1 * p1 / (tt + b1), b2 * p2 / (tt + b2)
            v0, v1, v2 = p0 - s0, p1 - s1, p2 - s2
            dist = math.sqrt((v0 * v0 + v1 * v1) + v2 * v2)
            sign = -1.0 if inside[row, i] else 1.0
            if dist > 1e-12:
                scale = _maximum(dist, 1e-12)
                g[row, i, 0] = sign * v0 / scale
                g[row, i, 1] = sign * v1 / scale
                g[row, i, 2] = sign * v2 / scale
            else:  # on the surface: the normal there
                n0, n1, n2 = s0 / b0, s1 / b1, s2 / b2
                nn = math.sqrt((n0 * n0 + n1 * n1) + n2 * n2)
                if nn > 1e-12:
                    scale = _maximum(nn, 1e-12)
                    g[row, i, 0], g[row, i, 1], g[row, i, 2] = n0 / scale, n1 / scale, n2 / scale
                else:
                    g[row, i, 0], g[row, i, 1], g[row, i, 2] = 0.0, 0.0, 1.0
            d[row, i] = sign * dist


@numba.njit(cache=True, error_model="numpy")
def _point_distance(kind: int, p0: float, p1: float, p2: float, size: np.ndarray, g: np.ndarray) -> float:
    """The signed distance (m) of the local point ``p`` to the sphere, box, cylinder or
    capsule of ``size``, its local gradient into ``g`` (3,): the elementwise operations of
    :func:`~eos_svc.shape.primitives.sphere`, ``box_planes``, ``cylinder_planes`` and
    ``capsule_planes`` on one point."""
    if kind == 0:  # sphere
        n = math.sqrt((p0 * p0 + p1 * p1) + p2 * p2)
        if n > 1e-12:
            scale = _maximum(n, 1e-12)
            g[0], g[1], g[2] = p0 / scale, p1 / scale, p2 / scale
        else:
            g[0], g[1], g[2] = 0.0, 0.0, 1.0
        return n - size[0]
    if kind == 2:  # box
        q0, q1, q2 = abs(p0) - size[0], abs(p1) - size[1], abs(p2) - size[2]
        e0, e1, e2 = _maximum(q0, 0.0), _maximum(q1, 0.0), _maximum(q2, 0.0)
        out = math.sqrt((e0 * e0 + e1 * e1) + e2 * e2)
        d = out + _minimum(_maximum(_maximum(q0, q1), q2), 0.0)
        sg0 = 1.0 if p0 >= 0.0 else -1.0
        sg1 = 1.0 if p1 >= 0.0 else -1.0
        sg2 = 1.0 if p2 >= 0.0 else -1.0
        if out > _TINY:
            scale = _maximum(out, _TINY)
            g[0], g[1], g[2] = sg0 * e0 / scale, sg1 * e1 / scale, sg2 * e2 / scale
        else:  # inside: the sign of the axis nearest its face (the first of equals)
            nearest = 0
            if q1 > q0:
                nearest = 1
            if q2 > (q0 if nearest == 0 else q1):
                nearest = 2
            g[0] = sg0 if nearest == 0 else 0.0
            g[1] = sg1 if nearest == 1 else 0.0
            g[2] = sg2 if nearest == 2 else 0.0
        return d
    radius, half_length = size[0], size[1]
    if kind == 3:  # cylinder
        rho = math.hypot(p0, p1)
        if rho > _TINY:
            scale = _maximum(rho, _TINY)
            rx, ry = p0 / scale, p1 / scale
        else:
            rx, ry = 1.0, 0.0
        dr = rho - radius
        dz = abs(p2) - half_length
        axial = 1.0 if p2 >= 0.0 else -1.0
        a, b = _maximum(dr, 0.0), _maximum(dz, 0.0)
        out = math.hypot(a, b)
        d = out + _minimum(_maximum(dr, dz), 0.0)
        if out > _TINY:
            scale = _maximum(out, _TINY)
            g[0] = (a * rx + b * 0.0) / scale
            g[1] = (a * ry + b * 0.0) / scale
            g[2] = (a * 0.0 + b * axial) / scale
        elif dr > dz:
            g[0], g[1], g[2] = rx, ry, 0.0
        else:
            g[0], g[1], g[2] = 0.0, 0.0, axial
        return d
    # capsule
    v2 = p2 - _minimum(_maximum(p2, -half_length), half_length)
    n = math.sqrt((p0 * p0 + p1 * p1) + v2 * v2)
    if n > 1e-12:
        scale = _maximum(n, 1e-12)
        g[0], g[1], g[2] = p0 / scale, p1 / scale, v2 / scale
    else:
        g[0], g[1], g[2] = 1.0, 0.0, 0.0
    return n - radius


@numba.njit(cache=True, error_model="numpy")
def _kernel(
    kind: int,
    thetas: np.ndarray,
    r0s: np.ndarray,
    per_row: bool,
    grouped: bool,
    groups: np.ndarray,
    log_lo: float,
    log_hi: float,
    points: np.ndarray,
    count: int,
    radii: np.ndarray,
    normals: np.ndarray,
    free_radii: np.ndarray,
    gap_offset: float,
    sigma_distance: float,
    sigma_normal: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(whitened residuals (K, m), centres, rotations, sizes): see :func:`residuals_and_geometry`."""
    centres, rotations, sizes = _geometry(kind, thetas, r0s, per_row, grouped, groups, log_lo, log_hi)
    local = _local_points(kind, points, centres, rotations)
    K, N = local.shape[0], local.shape[1]
    d = np.empty((K, N))
    g = np.empty((K, N, 3))
    if kind == 1:
        _ellipsoid(local, sizes, groups, d, g)
    else:
        for row in range(K):
            for i in range(N):
                p = local[row, i]
                d[row, i] = _point_distance(kind, p[0], p[1], p[2], sizes[row], g[row, i])
    n = count
    R = np.empty((K, 4 * n + (N - n)))
    for row in range(K):
        rot = rotations[row]
        for i in range(n):
            R[row, i] = ((d[row, i] - radii[i]) - gap_offset) / sigma_distance
            g0, g1, g2 = g[row, i, 0], g[row, i, 1], g[row, i, 2]
            for j in range(3):
                # the world gradient g @ rotationᵀ, as numpy's product computes it
                if kind == 0:
                    w = g0 if j == 0 else (g1 if j == 1 else g2)
                elif N == 1:
                    w = _fma(g2, rot[j, 2], _fma(g0, rot[j, 0], g1 * rot[j, 1]))
                else:
                    w = _dot3(g0, g1, g2, rot[j, 0], rot[j, 1], rot[j, 2])
                R[row, n + 3 * i + j] = (w - normals[i, j]) / sigma_normal
        for i in range(n, N):
            R[row, 3 * n + i] = _minimum(d[row, i] - free_radii[i - n], 0.0) / sigma_distance
    return R, centres, rotations, sizes


def residuals_and_geometry(
    kind: str,
    thetas: np.ndarray,
    r0: np.ndarray,
    groups: np.ndarray | None,
    log_size_range: tuple[float, float],
    touches: KernelTouches,
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(whitened residuals (K, m), (centres (K, 3), rotations (K, 3, 3), sizes (K, s))) of K
    parameter vectors ``thetas`` (K, k) of ``kind``, each about ``r0`` (3, 3) or its own row
    of ``r0`` (K, 3, 3), at the touches (:data:`KernelTouches`: N world points (N, 3) (m), the
    first ``count`` of them contact tip centres with radii and sensed normals, the rest free
    samples with their radii; the noise model's constants). The
    residuals' layout is the reference's: ``count`` distances, 3·count normal components,
    N − count free-space hinges. ``groups``: first rows of groups of rows evaluated as if in
    separate calls (see the module docstring)."""
    per_row = r0.ndim == 3
    r0s = np.ascontiguousarray(r0 if per_row else r0[None], dtype=np.float64)
    grouped = groups is not None
    R, centres, rotations, sizes = _kernel(
        KIND_CODE[kind],
        np.ascontiguousarray(thetas, dtype=np.float64),
        r0s,
        per_row,
        grouped,
        _ONE_GROUP if groups is None else np.ascontiguousarray(groups, dtype=np.int64),
        float(log_size_range[0]),
        float(log_size_range[1]),
        *touches,
    )
    return R, (centres, rotations, sizes)


@numba.njit(cache=True, error_model="numpy")
def _difference_kernel(
    kind: int,
    theta: np.ndarray,
    r0s: np.ndarray,
    per_row: bool,
    step: float,
    log_lo: float,
    log_hi: float,
    points: np.ndarray,
    count: int,
    radii: np.ndarray,
    normals: np.ndarray,
    free_radii: np.ndarray,
    gap_offset: float,
    sigma_distance: float,
    sigma_normal: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(residuals at θ (m,), difference quotients (k, m), centres, rotations, sizes of the
    k + 2 rows): see :func:`difference_evaluation`."""
    k = theta.shape[0]
    h = np.empty(k)
    thetas = np.empty((k + 2, k))
    for row in range(k + 2):
        for j in range(k):
            thetas[row, j] = theta[j]
    for j in range(k):
        h[j] = step * _maximum(1.0, abs(theta[j]))
        thetas[j, j] += h[j]
    groups = np.array([0, k + 1], dtype=np.int64)
    grouped = groups.shape[0] > 0  # True, as a plain bool: _kernel's one compiled signature
    R, centres, rotations, sizes = _kernel(
        kind, thetas, r0s, per_row, grouped, groups, log_lo, log_hi, points, count, radii, normals,
        free_radii, gap_offset, sigma_distance, sigma_normal,
    )
    m = R.shape[1]
    quotients = np.empty((k, m))
    for j in range(k):
        for i in range(m):
            quotients[j, i] = (R[j, i] - R[k, i]) / h[j]
    return R[k + 1].copy(), quotients, centres, rotations, sizes


def difference_evaluation(
    kind: str,
    theta: np.ndarray,
    r0: np.ndarray,
    step: float,
    log_size_range: tuple[float, float],
    touches: KernelTouches,
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(whitened residuals at ``theta`` (m,), forward-difference Jacobian (m, k), the geometry
    (centres, rotations, sizes) of the k + 2 rows evaluated) in one call: the k + 1 difference
    points ``θ + h_j e_j`` (``h_j = step · max(1, |θ_j|)``) and θ as one group of rows, θ again
    as a group of its own (whose residuals and geometry are θ's, as a call on it alone
    computes them), then the quotients ``(r(θ + h_j e_j) − r(θ)) / h_j``; the other arguments
    as :func:`residuals_and_geometry`'s."""
    per_row = r0.ndim == 3
    r, quotients, centres, rotations, sizes = _difference_kernel(
        KIND_CODE[kind],
        np.ascontiguousarray(theta, dtype=np.float64),
        np.ascontiguousarray(r0 if per_row else r0[None], dtype=np.float64),
        per_row,
        float(step),
        float(log_size_range[0]),
        float(log_size_range[1]),
        *touches,
    )
    return r, quotients.T, (centres, rotations, sizes)


def blas_products_agree() -> bool:
    """Whether numpy's matrix product of a few rows here is the kernel's
    ``fma(a₂, b₂, fma(a₁, b₁, a₀·b₀))`` (OpenBLAS on an FMA machine): then the kernel's bits
    are the reference's; with another BLAS they agree to a few ulps."""
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(64, 3)), rng.normal(size=(3, 3))
    return bool(np.array_equal(a @ b, _products(a, b)))


@numba.njit(cache=True, error_model="numpy")
def _products(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` (M, 3) @ (3, 3) summed as :func:`_dot3`."""
    out = np.empty((a.shape[0], 3))
    for i in range(a.shape[0]):
        for j in range(3):
            out[i, j] = _dot3(a[i, 0], a[i, 1], a[i, 2], b[0, j], b[1, j], b[2, j])
    return out


def warm_up() -> None:
    """Compile (first run) or load from the on-disk cache every kernel, on tiny inputs of the
    types the fit passes: a service calls it at start so that its first request does not
    pay the compilation (seconds)."""
    points = np.array([[0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.2]])
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    radii, free_radii = np.full(2, 0.01), np.full(1, 0.01)
    touches: KernelTouches = (points, 2, radii, normals, free_radii, 0.0, 0.001, 0.1)
    for kind, k in (("sphere", 4), ("ellipsoid", 9), ("box", 9), ("cylinder", 7), ("capsule", 7)):
        thetas = np.full((2, k), -3.0)
        for r0 in (np.eye(3), np.repeat(np.eye(3)[None], 2, axis=0)):
            for groups in (None, np.array([0, 1])):
                residuals_and_geometry(kind, thetas, r0, groups, (math.log(1e-4), 0.0), touches)
            difference_evaluation(
                kind, thetas[0], r0[0] if r0.ndim == 3 else r0, 1e-8, (math.log(1e-4), 0.0), touches
            )
    _products(points, np.eye(3))
    kernels.mark_ready()
