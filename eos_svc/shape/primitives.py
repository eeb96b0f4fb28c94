"""Signed distance and its gradient for each primitive class, in the class's own frame.

Every function takes local points ``P`` (..., N, 3) and the class's sizes broadcastable
against the leading axes (``(..., 1)`` scalars, ``(..., 1, 3)`` vectors: several parameter
sets at once, as the fit's finite-difference Jacobian needs), and returns ``(d, g)``: the
signed distance (..., N) in m (negative inside) and its gradient (..., N, 3) (unit: the
outward normal at the closest surface point). Conventions match
:mod:`eos_svc.kinematics.objects` (and coal): centred shapes, cylinder and capsule axes
along local z, a capsule's straight part of half length ``h``.
"""

from __future__ import annotations

import numpy as np

Array = np.ndarray
_TINY = 1e-15


def sum3(v: Array) -> Array:
    """Σ over a last axis of length 3, ``(v₀ + v₁) + v₂``: ``np.sum(v, axis=-1)``'s
    arithmetic (the same order, the same bits) as two additions of strided views — numpy's
    reduction over so short an axis costs several times more."""
    out: Array = v[..., 0] + v[..., 1] + v[..., 2]
    return out


def max3(v: Array) -> Array:
    """Largest entry over a last axis of length 3: ``np.max(v, axis=-1)`` (NaN propagated)."""
    out: Array = np.maximum(np.maximum(v[..., 0], v[..., 1]), v[..., 2])
    return out


def norm(v: Array) -> Array:
    """Euclidean norm over the last axis (of length 3): ``np.linalg.norm(v, axis=-1)``'s
    arithmetic without its argument handling (these arrays are small: the call dominates)."""
    out: Array = np.sqrt(sum3(v * v))
    return out


# a reduction as a ufunc method: np.max's arithmetic without its wrapper
_max = np.maximum.reduce
# the largest of each of several consecutive slices (their first indices): reduceat
_max_at = np.maximum.reduceat
#: the coordinate axes' indices, to compare with an argmax
_AXES = np.arange(3)
_X_UNIT = np.array([1.0, 0.0, 0.0])


def _unit_from(v: Array, n: Array, fallback: tuple[float, float, float]) -> Array:
    """``v / n`` (``n`` = :func:`norm` of ``v``, (...,)), or ``fallback`` where ``n`` ≈ 0."""
    n = n[..., None]
    out: Array = np.where(n > 1e-12, v / np.maximum(n, 1e-12), np.asarray(fallback))
    return out


def _unit(v: Array, fallback: tuple[float, float, float]) -> Array:
    return _unit_from(v, norm(v), fallback)


def sphere(P: Array, radius: Array) -> tuple[Array, Array]:
    """Sphere of ``radius``."""
    n = norm(P)
    return n - radius, _unit_from(P, n, (0.0, 0.0, 1.0))


def box(P: Array, half: Array) -> tuple[Array, Array]:
    """Box of half sides ``half`` (..., 1, 3)."""
    q = np.abs(P) - half
    qp = np.maximum(q, 0.0)
    out = norm(qp)
    d = out + np.minimum(max3(q), 0.0)
    sign = np.where(P >= 0.0, 1.0, -1.0)
    g_out = sign * qp / np.maximum(out, _TINY)[..., None]
    # inside: the sign of the axis nearest its face (the first of equals), 0 on the others
    g_in = np.where(q.argmax(axis=-1)[..., None] == _AXES, sign, 0.0)  # the method: no wrapper
    return d, np.where((out > _TINY)[..., None], g_out, g_in)


def cylinder(P: Array, radius: Array, half_length: Array) -> tuple[Array, Array]:
    """Cylinder of ``radius`` and half length ``half_length`` along z (flat caps)."""
    x, y, z = P[..., 0], P[..., 1], P[..., 2]
    rho = np.hypot(x, y)
    across = P.copy()
    across[..., 2] = 0.0
    radial = across / np.maximum(rho, _TINY)[..., None]
    radial = np.where((rho > _TINY)[..., None], radial, _X_UNIT)
    dr = rho - radius
    dz = np.abs(z) - half_length
    axial = np.zeros(P.shape, P.dtype)
    axial[..., 2] = np.where(z >= 0.0, 1.0, -1.0)
    a, b = np.maximum(dr, 0.0), np.maximum(dz, 0.0)
    out = np.hypot(a, b)
    d = out + np.minimum(np.maximum(dr, dz), 0.0)
    g_out = (a[..., None] * radial + b[..., None] * axial) / np.maximum(out, _TINY)[..., None]
    g_in = np.where((dr > dz)[..., None], radial, axial)
    return d, np.where((out > _TINY)[..., None], g_out, g_in)


def capsule(P: Array, radius: Array, half_length: Array) -> tuple[Array, Array]:
    """Capsule of ``radius`` around the z segment of half length ``half_length``."""
    zc = np.clip(P[..., 2], -half_length, half_length)
    v = P.copy()
    v[..., 2] -= zc
    n = norm(v)
    return n - radius, _unit_from(v, n, (1.0, 0.0, 0.0))


#: the fallback directions as planes (3, 1, 1): the cylinder's radial x, the capsule's x
_X_PLANES = np.array([1.0, 0.0, 0.0])[:, None, None]
#: the cylinder's radial fallback's first two coordinates as planes (2, 1, 1)
_XY_FALLBACK = _X_PLANES[:2]
#: the coordinate axes' indices as planes (3, 1, 1), to compare with an argmax over planes
_AXES_PLANES = _AXES[:, None, None]


def box_planes(P: Array, half: Array) -> tuple[Array, Array]:
    """:func:`box` on coordinate planes: ``P`` (3, ...) contiguous, ``half`` (3, ...) or
    broadcastable to it (m); returns the distance (...) and the gradient as planes (3, ...).
    Every operation is :func:`box`'s elementwise one on the same numbers (the same bits),
    each point's scalars broadcast along the leading axis only (contiguous loops)."""
    q = np.abs(P) - half
    qp = np.maximum(q, 0.0)
    out = np.sqrt(_sum_planes(qp * qp))
    d = out + np.minimum(np.maximum(np.maximum(q[0], q[1]), q[2]), 0.0)
    sign = np.where(P >= 0.0, 1.0, -1.0)
    g_out = sign * qp / np.maximum(out, _TINY)
    # inside: the sign of the axis nearest its face (the first of equals), 0 on the others
    g_in = np.where(q.argmax(axis=0) == _AXES_PLANES, sign, 0.0)
    return d, np.where(out > _TINY, g_out, g_in)


def cylinder_planes(P: Array, radius: Array, half_length: Array) -> tuple[Array, Array]:
    """:func:`cylinder` on coordinate planes: ``P`` (3, ...) contiguous, ``radius`` and
    ``half_length`` broadcastable to (...) (m); returns the distance (...) and the gradient as
    planes (3, ...). The same elementwise operations on the same numbers as :func:`cylinder`
    (the radial direction's and the axial one's zero components included: ``a·0 + b·n``)."""
    x, y, z = P
    rho = np.hypot(x, y)
    far = rho > _TINY
    radial = np.where(far, P[:2] / np.maximum(rho, _TINY), _XY_FALLBACK)  # its z is 0
    dr = rho - radius
    dz = np.abs(z) - half_length
    axial = np.where(z >= 0.0, 1.0, -1.0)  # the axial direction's z; its x and y are 0
    a, b = np.maximum(dr, 0.0), np.maximum(dz, 0.0)
    out = np.hypot(a, b)
    d = out + np.minimum(np.maximum(dr, dz), 0.0)
    scale = np.maximum(out, _TINY)
    g = np.empty(P.shape)
    g[:2] = (a * radial + b * 0.0) / scale
    g[2] = (a * 0.0 + b * axial) / scale
    side = dr > dz
    outside = out > _TINY
    g[:2] = np.where(outside, g[:2], np.where(side, radial, 0.0))
    g[2] = np.where(outside, g[2], np.where(side, 0.0, axial))
    return d, g


def capsule_planes(P: Array, radius: Array, half_length: Array) -> tuple[Array, Array]:
    """:func:`capsule` on coordinate planes: ``P`` (3, ...) contiguous, ``radius`` and
    ``half_length`` broadcastable to (...) (m); returns the distance (...) and the gradient as
    planes (3, ...), :func:`capsule`'s elementwise operations on the same numbers."""
    v = P.copy()
    v[2] -= np.clip(P[2], -half_length, half_length)
    n = np.sqrt(_sum_planes(v * v))
    g = np.where(n > 1e-12, v / np.maximum(n, 1e-12), _X_PLANES)
    return n - radius, g


def ellipsoid_root_lower_bound(P: Array, a: Array, inside: Array) -> Array:
    """A point left of the root of the ellipsoid's ``F`` (see :func:`ellipsoid`), near it:
    every term of ``F`` is at most 1 at the root, so ``t ≥ a_i |p_i| − a_i²`` for each axis;
    and ``t ≥ 0`` outside, ``t > −min a_i²`` inside (kept 1e-12 relative away from that pole,
    where ``F`` is infinite). ``a``: the semi-axes, ``P``'s shape or broadcastable to it."""
    amin2 = np.minimum(np.minimum(a[..., 0], a[..., 1]), a[..., 2]) ** 2
    floor = np.where(inside, -amin2 * (1.0 - 1e-12), 0.0)
    out: Array = np.maximum(max3(a * np.abs(P) - a * a), floor)
    return out


def ellipsoid(
    P: Array, radii: Array, iterations: int = 30, groups: Array | None = None
) -> tuple[Array, Array]:
    """Ellipsoid of semi-axes ``radii`` (..., 1, 3) along x, y, z: the exact closest point.

    The closest point is ``s_i = a_i² p_i / (t + a_i²)`` with ``t`` the root of
    ``Σ (a_i p_i / (t + a_i²))² = 1`` on ``t > −min a_i²``. Written ``h(t) = 1`` with
    ``h = (Σ (a_i p_i)² (t + a_i²)⁻²)^(−1/2)``, a power mean of exponent −2 of the affine
    ``t + a_i²`` — increasing and concave (linear for a sphere) — Newton's method from a point
    left of the root (:func:`ellipsoid_root_lower_bound`) stays left of it and rises
    monotonically to it, in one step for a sphere, in a few for the ellipsoid. Every root is
    iterated until the largest relative step of the call is below 1e-12.

    ``groups``: for ``P`` of shape (K, N, 3), the first row index of each of several
    consecutive groups of rows (ascending, from 0): each group is then iterated until *its*
    largest step is below that bound: each group's roots are, to the bit, those of a separate
    call on its rows alone (several evaluations in one call, as :mod:`eos_svc.shape.fit`
    batches them).

    The arithmetic runs on the coordinates as three contiguous planes
    (:func:`ellipsoid_planes`): every operation is the same elementwise one on the same
    numbers (the same bits as on (..., 3) rows), without numpy's strided and broadcast loops.
    """
    last = P.ndim - 1
    planes = P.transpose(last, *range(last)).copy()
    a = radii if np.shape(radii) == P.shape else np.broadcast_to(radii, P.shape)
    d, g = ellipsoid_planes(planes, a.transpose(last, *range(last)).copy(), iterations, groups)
    return d, g.transpose(*range(1, P.ndim), 0).copy()


def _sum_planes(v: Array) -> Array:
    """``(v₀ + v₁) + v₂`` over the first axis (of length 3): :func:`sum3`'s order."""
    out: Array = v[0] + v[1] + v[2]
    return out


def ellipsoid_planes(
    P: Array, a: Array, iterations: int = 30, groups: Array | None = None
) -> tuple[Array, Array]:
    """:func:`ellipsoid` on coordinate planes: ``P`` and the semi-axes ``a`` both (3, ...)
    contiguous (m); returns the distance (...) (m) and the gradient as planes (3, ...)."""
    a2 = a * a
    inside = _sum_planes((P / a) ** 2) < 1.0
    # ellipsoid_root_lower_bound's arithmetic, on planes
    amin2 = np.minimum(np.minimum(a[0], a[1]), a[2]) ** 2
    floor = np.where(inside, -amin2 * (1.0 - 1e-12), 0.0)
    low = a * np.abs(P) - a2
    t = np.maximum(np.maximum(np.maximum(low[0], low[1]), low[2]), floor)
    ap2 = (a * P) ** 2
    bounds = [(0, len(t))] if groups is None else list(zip(groups, [*groups[1:], len(t)], strict=True))
    starts = np.array([lo for lo, _ in bounds])
    index = {lo: i for i, (lo, _) in enumerate(bounds)}
    moving = bounds  # the groups still iterating, (first row, end)
    for _ in range(iterations):
        inv = 1.0 / (t + a2)
        uu = ap2 * inv * inv  # (a_i p_i / (t + a_i²))²
        total = _sum_planes(uu)  # h⁻²
        slope = _sum_planes(uu * inv)  # h' · h⁻³
        step = total * (np.sqrt(total) - 1.0) / np.maximum(slope, 1e-300)  # (1 − h) / h'
        if moving is bounds and len(bounds) == 1:  # one group: the whole call
            t = t + step
            if _max(np.abs(step) / (1e-6 + np.abs(t)), axis=None) < 1e-12:
                break
            continue
        if moving is bounds:
            t = t + step
        else:
            for lo, hi in moving:
                t[lo:hi] += step[lo:hi]
        # each group's largest relative step, one reduction per group in one call
        largest = _max_at(_max(np.abs(step) / (1e-6 + np.abs(t)), axis=-1), starts)
        if moving is bounds:
            moving = [bound for bound, m in zip(bounds, largest.tolist(), strict=True) if not m < 1e-12]
        else:
            moving = [(lo, hi) for lo, hi in moving if not largest[index[lo]] < 1e-12]
        if not moving:
            break
    S = a2 * P / (t + a2)
    v = P - S
    dist = np.sqrt(_sum_planes(v * v))
    sign = np.where(inside, -1.0, 1.0)
    away = dist > 1e-12
    g = sign * v / np.maximum(dist, 1e-12)
    if not away.all():  # on the surface: the normal there
        n = S / a2
        unit = np.moveaxis(_unit(np.moveaxis(n, 0, -1), (0.0, 0.0, 1.0)), -1, 0)
        g = np.where(away, g, unit)
    return sign * dist, g
