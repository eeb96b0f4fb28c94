"""The fit's speed helpers against the plain computations they replace."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.shape import Touches, fit_class, kernels, select_class
from eos_svc.shape import fit as shape_fit
from eos_svc.shape import primitives as shape_primitives
from eos_svc.shape.primitives import ellipsoid, ellipsoid_root_lower_bound, norm
from eos_svc.shape.selection import (
    CLASSES,
    GOOD_FIT,
    HOPELESS,
    QUICK_NFEV,
    fit_probability,
    quick_fit,
    screen,
    tolerance_probability,
)
from tests.shape.synthetic import TIP, objects, touches_on

KINDS = ["sphere", "ellipsoid", "cylinder", "capsule", "box"]


def plain_select(touches: Touches) -> tuple[str, float, dict[str, float], shape_fit.ClassFit]:
    """(class, confidence, posteriors, chosen fit) by fitting the classes in their order, each
    from its starts in order — no screening, no reuse (the selection before it was sped up)."""
    m = 3 * touches.count
    fits: dict[str, shape_fit.ClassFit] = {}
    for kind in CLASSES:
        best = min((f.chi2 for f in fits.values()), default=math.inf)
        if best > GOOD_FIT * m:
            fits[kind] = fit_class(kind, touches)
            continue
        quick = fit_class(kind, touches, max_nfev=QUICK_NFEV, hopeless=best + HOPELESS)
        if quick.chi2 > best + HOPELESS or quick.chi2 <= GOOD_FIT * m:
            fits[kind] = quick
            continue
        fits[kind] = fit_class(kind, touches, hopeless=best + HOPELESS)
    bic = {k: f.chi2 + f.n_params * math.log(m) for k, f in fits.items()}
    low = min(bic.values())
    weights = {k: math.exp(-0.5 * (b - low)) for k, b in bic.items()}
    probs = {k: w / sum(weights.values()) for k, w in weights.items()}
    kind = max(CLASSES, key=lambda k: (probs[k], -CLASSES.index(k)))
    conf = probs[kind] * tolerance_probability(fits[kind], touches) * fit_probability(fits[kind], m)
    return kind, conf, probs, fits[kind]


def random_touches(kind: str, seed: int) -> Touches:
    rng = np.random.default_rng(seed)
    obj = objects(rpy=tuple(rng.uniform(-1.0, 1.0, 3)))[kind]
    t = touches_on(obj, rng, n=24)
    # a few free samples beyond the object (behind it, along +x)
    c = np.asarray(obj.placement.translation)
    free = c + np.column_stack([np.full(5, 0.06), rng.uniform(-0.02, 0.02, (5, 2))])
    return t.merged(Touches(free=free, free_radii=TIP))


@pytest.mark.parametrize("seed", [11, 12])
@pytest.mark.parametrize("kind", KINDS)
def test_screened_selection_postulates_what_the_plain_selection_does(kind, seed):
    touches = random_touches(kind, seed)
    post = select_class(touches)
    kind0, conf0, probs0, fit0 = plain_select(touches)
    assert post.kind == kind0 == kind
    assert post.confidence == pytest.approx(conf0, abs=2e-3)
    for k, p in probs0.items():
        assert post.probabilities[k] == pytest.approx(p, abs=2e-3)
    chosen = post.best
    assert chosen is not None
    np.testing.assert_allclose(chosen.geometry.centre, fit0.geometry.centre, atol=2e-5)  # m
    np.testing.assert_allclose(sorted(chosen.geometry.sizes), sorted(fit0.geometry.sizes), rtol=2e-3)
    assert chosen.chi2 == pytest.approx(fit0.chi2, rel=1e-3)


@pytest.mark.parametrize("kind", KINDS)
def test_ranked_starts_are_the_starts_from_the_nearest(kind):
    touches = random_touches(kind, 3)
    plain = shape_fit.starts(kind, touches)
    ranked = shape_fit.ranked_starts(kind, touches)
    assert len(ranked) == len(plain)
    chi2 = [float(np.sum(shape_fit.residuals(theta, kind, r0, touches) ** 2)) for theta, r0 in ranked]
    assert chi2 == sorted(chi2)
    keys = sorted((tuple(t), tuple(r.ravel())) for t, r in plain)
    assert sorted((tuple(t), tuple(r.ravel())) for t, r in ranked) == keys


@pytest.mark.parametrize("seed", [5, 6])
@pytest.mark.parametrize("kind", KINDS)
def test_quick_fit_from_a_screening_is_the_plain_quick_fit(kind, seed):
    # selection.quick_fit reuses a class's screening fit when it began from the class's first
    # start and is above the hopeless bound or explains the touches
    touches = random_touches("box" if kind != "box" else "cylinder", seed)
    screened = screen(touches, (kind,))[kind]
    for hopeless in (screened.chi2 - 1.0, screened.chi2 + 1.0, math.inf):
        got = quick_fit(kind, touches, hopeless, screened)
        plain = fit_class(kind, touches, max_nfev=QUICK_NFEV, hopeless=hopeless)
        assert got.chi2 == plain.chi2 and got.start == plain.start
        np.testing.assert_array_equal(got.theta, plain.theta)
        np.testing.assert_array_equal(got.covariance, plain.covariance)


def test_residual_count_is_the_residuals_length():
    touches = random_touches("box", 7)
    for kind in KINDS:
        theta, r0 = shape_fit.starts(kind, touches)[0]
        assert len(shape_fit.residuals(theta, kind, r0, touches)) == shape_fit.residual_count(touches)


@pytest.mark.parametrize("kind", KINDS)
def test_fused_residuals_equal_contacts_and_free_samples_apart(kind):
    # batch_residuals evaluates the contacts and the free samples in one call
    touches = random_touches(kind, 8)
    rng = np.random.default_rng(9)
    starts = shape_fit.starts(kind, touches)
    theta0, r0 = starts[0]
    thetas = theta0 + rng.normal(scale=0.05, size=(4, len(theta0)))
    fused = shape_fit.batch_residuals(thetas, kind, r0, touches)
    for theta, row in zip(thetas, fused, strict=True):
        g = shape_fit.geometry_from(kind, theta, r0)
        d, n = g.signed_distance(touches.centres)
        f, _ = g.signed_distance(touches.free)
        plain = np.concatenate(
            [
                (d - touches.radii - touches.gap_offset) / touches.sigma_distance,
                ((n - touches.normals) / touches.sigma_normal).ravel(),
                np.minimum(f - touches.free_radii, 0.0) / touches.sigma_distance,
            ]
        )
        np.testing.assert_allclose(row, plain, rtol=1e-9, atol=1e-9)
    # each parameter vector about its own start orientation, as ranked_starts evaluates them
    thetas = np.array([t for t, _ in starts])
    own = shape_fit.batch_residuals(thetas, kind, np.array([r for _, r in starts]), touches)
    for (theta, r), row in zip(starts, own, strict=True):
        np.testing.assert_allclose(row, shape_fit.residuals(theta, kind, r, touches), rtol=1e-12, atol=1e-9)


def _ellipsoid_root_function(t: np.ndarray, P: np.ndarray, a: np.ndarray) -> np.ndarray:
    out: np.ndarray = np.sum((a * P / (t[..., None] + a * a)) ** 2, axis=-1) - 1.0
    return out


def test_ellipsoid_newton_start_is_left_of_the_root_and_near_it():
    rng = np.random.default_rng(21)
    a = np.broadcast_to(rng.uniform(0.01, 0.05, 3), (2000, 3))
    P = rng.normal(scale=0.04, size=(2000, 3))
    inside = np.sum((P / a) ** 2, axis=-1) < 1.0
    assert inside.any() and (~inside).any()
    t0 = ellipsoid_root_lower_bound(P, a, inside)
    assert np.all(t0 > -(np.min(a, axis=-1) ** 2))
    assert np.all(_ellipsoid_root_function(t0, P, a) >= -1e-12)  # F decreasing: t0 ≤ root
    # the plain start (0 outside, near the shortest axis' pole inside) is never nearer the root
    amin = np.min(a, axis=-1)
    plain = np.where(inside, -amin * amin + amin * np.abs(P[np.arange(len(P)), np.argmin(a, axis=-1)]), 0.0)
    assert np.all(t0 >= plain - 1e-18)
    d, g = ellipsoid(P, a)
    # Newton from there converges: the closest point, d along the gradient, is on the surface
    S = P - d[:, None] * g
    np.testing.assert_allclose(np.sum((S / a) ** 2, axis=-1), 1.0, atol=1e-8)


def test_norm_and_cross_are_numpys():
    rng = np.random.default_rng(31)
    u, v = rng.normal(size=(2, 40, 3))
    np.testing.assert_array_equal(norm(u), np.linalg.norm(u, axis=-1))
    np.testing.assert_array_equal(norm(u.reshape(4, 10, 3)), np.linalg.norm(u.reshape(4, 10, 3), axis=-1))
    np.testing.assert_array_equal(shape_fit._cross(u, v), np.cross(u, v))


def _ellipsoid_closest_plain(P: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Closest points by Newton's method on F(t) = Σ (a_i p_i / (t + a_i²))² − 1 from t = 0
    outside, from near the shortest axis' pole inside (the plain iteration)."""
    inside = np.sum((P / a) ** 2, axis=-1) < 1.0
    amin = np.min(a, axis=-1)
    pmin = np.abs(P[np.arange(len(P)), np.argmin(a, axis=-1)])
    t = np.where(inside, -amin * amin + amin * pmin + 1e-12 * amin * amin, 0.0)
    for _ in range(200):
        den = t[:, None] + a * a
        uu = (a * P / den) ** 2
        step = (uu.sum(axis=-1) - 1.0) / np.minimum(-2.0 * (uu / den).sum(axis=-1), -1e-300)
        t = t - step
        if np.max(np.abs(step) / (1e-6 + np.abs(t))) < 1e-14:
            break
    out: np.ndarray = a * a * P / (t[:, None] + a * a)
    return out


@pytest.mark.parametrize("radii", [(0.03, 0.03, 0.03), (0.035, 0.03, 0.022), (0.05, 0.01, 0.004)])
def test_ellipsoid_closest_point_is_the_plain_newtons(radii):
    rng = np.random.default_rng(41)
    a = np.broadcast_to(np.asarray(radii), (3000, 3))
    P = rng.normal(scale=0.04, size=(3000, 3))
    d, g = ellipsoid(P, a)
    np.testing.assert_allclose(P - d[:, None] * g, _ellipsoid_closest_plain(P, a), rtol=0, atol=1e-15)


@pytest.mark.parametrize("kind", KINDS)
def test_levenberg_marquardt_runs_what_least_squares_runs(kind):
    from scipy.optimize import least_squares

    touches = random_touches(kind if kind != "box" else "ellipsoid", 13)
    for theta0, r0 in shape_fit.starts(kind, touches)[:2]:
        for max_nfev in (QUICK_NFEV, 20):
            theta, fun = shape_fit.levenberg_marquardt(theta0, kind, r0, touches, max_nfev)
            plain = least_squares(
                shape_fit.residuals,
                theta0,
                jac=shape_fit._jacobian,
                args=(kind, r0, touches),
                method="lm",
                x_scale="jac",
                max_nfev=max_nfev,
                ftol=1e-8,
                xtol=1e-8,
                gtol=1e-8,
            )
            np.testing.assert_array_equal(theta, plain.x)
            np.testing.assert_array_equal(fun, plain.fun)


def test_start_helpers_equal_their_loops():
    rng = np.random.default_rng(51)
    touches = random_touches("box", 52)
    points, normals = touches.surface_points, touches.normals
    prior = points.mean(axis=0)
    # the normal lines' nearest point: the sum over contacts written as a loop
    A, b = np.zeros((3, 3)), np.zeros(3)
    for s, n in zip(points, normals, strict=True):
        P = np.eye(3) - np.outer(n, n)
        A, b = A + P, b + P @ s
    lam = 1e-3 * len(points)
    plain = np.linalg.solve(A + lam * np.eye(3), b + lam * prior)
    got_centre = shape_fit._normal_line_centre(points, normals, prior)
    np.testing.assert_allclose(got_centre, plain, rtol=0, atol=1e-12)
    # greedy clusters of the normals, one member test at a time
    noisy = normals + rng.normal(scale=0.05, size=normals.shape)
    noisy /= np.linalg.norm(noisy, axis=1, keepdims=True)
    left, groups = list(range(len(noisy))), []
    cos = math.cos(math.radians(15.0))
    while left:
        members = [i for i in left if noisy[i] @ noisy[left[0]] >= cos]
        mean = noisy[members].sum(axis=0)
        groups.append((len(members), mean / np.linalg.norm(mean)))
        left = [i for i in left if i not in members]
    groups.sort(key=lambda g: -g[0])
    got = shape_fit._normal_clusters(noisy)
    assert len(got) == len(groups) > 3
    for g, (_, mean) in zip(got, groups, strict=True):
        np.testing.assert_allclose(g, mean, rtol=0, atol=1e-12)
    axis = rng.normal(size=3)
    frame = shape_fit.frame_with_z(axis)
    np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-12)
    assert np.linalg.det(frame) == pytest.approx(1.0)
    assert frame[:, 2] @ axis == pytest.approx(np.linalg.norm(axis))


@pytest.mark.parametrize("radii", [(0.03, 0.03, 0.03), (0.035, 0.03, 0.022), (0.05, 0.01, 0.004)])
def test_grouped_ellipsoid_roots_are_those_of_separate_calls(radii):
    # several evaluations in one call (the fit's residuals with their difference points): each
    # group iterates as long as it would alone, so its roots are the same to the bit
    rng = np.random.default_rng(61)
    a = np.asarray(radii)
    sizes = np.stack([a, a * 1.01, a * 0.97, a * 1.2, a])[:, None, :]  # (5, 1, 3)
    P = rng.normal(scale=0.04, size=(5, 30, 3))
    groups = np.array([0, 3, 4])
    d, g = ellipsoid(P, sizes, groups=groups)
    for lo, hi in zip(groups, [*groups[1:], len(P)], strict=True):
        d_alone, g_alone = ellipsoid(P[lo:hi], sizes[lo:hi])
        np.testing.assert_array_equal(d[lo:hi], d_alone)
        np.testing.assert_array_equal(g[lo:hi], g_alone)
    # and one group is the ungrouped call
    d_one, g_one = ellipsoid(P, sizes, groups=np.array([0]))
    d_all, g_all = ellipsoid(P, sizes)
    np.testing.assert_array_equal(d_one, d_all)
    np.testing.assert_array_equal(g_one, g_all)


@pytest.mark.parametrize("kind", KINDS)
def test_fused_evaluations_are_the_residuals_and_the_jacobian(kind):
    # _Evaluations computes the residuals and the difference Jacobian of a point in one call
    # (several seeds: a cylinder's axes rounded as one product of all the rows would differ
    # from the plain residuals' in a few of these evaluations)
    for seed in range(14, 20):
        touches = random_touches(kind, seed)
        rng = np.random.default_rng(seed + 1)
        for theta0, r0 in shape_fit.starts(kind, touches)[:2]:
            evaluations = shape_fit._Evaluations(kind, r0, touches)
            for theta in theta0 + rng.normal(scale=0.02, size=(3, len(theta0))):
                J = evaluations.jacobian(theta)  # the Jacobian first, then the (remembered) residuals
                plain = shape_fit.residuals(theta, kind, r0, touches)
                np.testing.assert_array_equal(evaluations.residuals(theta), plain)
                np.testing.assert_array_equal(J, shape_fit._jacobian(theta, kind, r0, touches))
                got, plain_geometry = evaluations.geometry(theta), shape_fit.geometry_from(kind, theta, r0)
                np.testing.assert_array_equal(got.centre, plain_geometry.centre)
                np.testing.assert_array_equal(got.rotation, plain_geometry.rotation)
                assert got.sizes == plain_geometry.sizes and got.kind == kind
            assert len(evaluations.known) == 3


def test_sum3_and_max3_are_numpys_reductions():
    rng = np.random.default_rng(71)
    # a wide dynamic range: the order of the additions shows in the last bits
    v = rng.normal(size=(7, 40, 3)) * np.exp(rng.normal(scale=6.0, size=(7, 40, 3)))
    np.testing.assert_array_equal(shape_primitives.sum3(v), np.sum(v, axis=-1))
    np.testing.assert_array_equal(shape_primitives.max3(v), np.max(v, axis=-1))
    v[0, 0, 1] = np.nan
    assert np.isnan(shape_primitives.max3(v)[0, 0]) and np.isnan(np.max(v, axis=-1)[0, 0])


def test_shared_class_starts_are_each_class_s_own():
    # select_class computes the starts of every class from one ClassStarts: the pieces the
    # classes share (scatter axes, the normal lines' centre, the axial frames) change nothing
    touches = random_touches("capsule", 72)
    shared = shape_fit.ClassStarts(touches)
    for kind in reversed(KINDS):
        for (t_shared, r_shared), (t_own, r_own) in zip(
            shared.of(kind), shape_fit.ClassStarts(touches).of(kind), strict=True
        ):
            np.testing.assert_array_equal(t_shared, t_own)
            np.testing.assert_array_equal(r_shared, r_own)
    S = touches.surface_points
    mid = 0.5 * (S.min(axis=0) + S.max(axis=0))
    centre = shape_fit._normal_line_centre(S, touches.normals, mid)
    np.testing.assert_array_equal(shared.of("sphere")[0][0][:3], centre)
    for theta0, _ in shared.of("ellipsoid"):
        np.testing.assert_array_equal(theta0[:3], centre)
    V = shape_fit._normal_scatter_axes(touches.normals)
    axes = shape_fit._distinct([V[:, 0], *np.eye(3), V[:, 1], V[:, 2]])
    for kind in ("cylinder", "capsule"):
        frames = [r0 for _, r0 in shared.of(kind)]
        assert len(frames) == len(axes)
        for r0, axis in zip(frames, axes, strict=True):
            np.testing.assert_array_equal(r0, shape_fit.frame_with_z(axis))


def test_chi2_survival_is_scipy_stats():
    from scipy import stats

    from eos_svc.shape.selection import chi2_survival

    for dof in (1, 5, 97, 400):
        for x in (0.0, 1e-9, 0.5, 3.0, float(dof), 2.0 * dof, 50.0 * dof, 1e6, math.inf):
            assert chi2_survival(x, dof) == float(stats.chi2.sf(x, dof))


def test_normal_clusters_at_the_bound_are_decided_as_the_plain_loop_does():
    # a cosine within rounding of the group bound: membership is decided by each normal's
    # own product (the plain loop), not by the Gram matrix
    rng = np.random.default_rng(73)
    normals = rng.normal(size=(20, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    angle = math.acos(float(normals[0] @ normals[1]))
    cos = math.cos(angle)
    assert abs(float((normals @ normals.T)[0, 1]) - cos) < shape_fit._CLUSTER_MARGIN
    left, plain = np.arange(len(normals)), []
    while len(left):
        near = normals[left] @ normals[left[0]] >= cos
        plain.append(left[near].tolist())
        left = left[~near]
    assert shape_fit._cluster_members(normals, cos) == plain
    # away from the bound, the Gram matrix's groups are the plain loop's
    for angle in (0.2, 0.3, 0.5):
        cos = math.cos(angle)
        left, plain = np.arange(len(normals)), []
        while len(left):
            near = normals[left] @ normals[left[0]] >= cos
            plain.append(left[near].tolist())
            left = left[~near]
        assert shape_fit._cluster_members(normals, cos) == plain


def test_median_and_columns_are_numpys():
    rng = np.random.default_rng(74)
    for n in (1, 2, 5, 26, 27):
        v = rng.normal(size=n) * np.exp(rng.normal(scale=4.0, size=n))
        assert shape_fit._median(v) == float(np.median(v))
    x, y, z = rng.normal(size=(3, 3))
    np.testing.assert_array_equal(shape_fit._columns(x, y, z), np.column_stack([x, y, z]))


def _ellipsoid_rows(P: np.ndarray, radii: np.ndarray, groups: np.ndarray | None = None):
    """The ellipsoid kernel on (..., 3) rows, broadcast semi-axes: the arithmetic
    :func:`~eos_svc.shape.primitives.ellipsoid` runs on coordinate planes."""
    sum3, _max = shape_primitives.sum3, np.maximum.reduce
    a = radii
    a2 = a * a
    inside = sum3((P / a) ** 2) < 1.0
    t = ellipsoid_root_lower_bound(P, a, inside)
    ap2 = (a * P) ** 2
    bounds = [(0, len(P))] if groups is None else list(zip(groups, [*groups[1:], len(P)], strict=True))
    moving = bounds
    for _ in range(30):
        inv = 1.0 / (t[..., None] + a2)
        uu = ap2 * inv * inv
        total, slope = sum3(uu), sum3(uu * inv)
        step = total * (np.sqrt(total) - 1.0) / np.maximum(slope, 1e-300)
        if moving is bounds and len(bounds) == 1:
            t = t + step
            if _max(np.abs(step) / (1e-6 + np.abs(t)), axis=None) < 1e-12:
                break
            continue
        if moving is bounds:
            t = t + step
        else:
            for lo, hi in moving:
                t[lo:hi] += step[lo:hi]
        relative = _max(np.abs(step) / (1e-6 + np.abs(t)), axis=-1)
        moving = [(lo, hi) for lo, hi in moving if not _max(relative[lo:hi], axis=None) < 1e-12]
        if not moving:
            break
    S = a2 * P / (t[..., None] + a2)
    v = P - S
    dist = norm(v)
    sign = np.where(inside, -1.0, 1.0)
    away = dist > 1e-12
    g = sign[..., None] * v / np.maximum(dist, 1e-12)[..., None]
    if not away.all():
        g = np.where(away[..., None], g, shape_primitives._unit(S / a2, (0.0, 0.0, 1.0)))
    return sign * dist, g


def test_ellipsoid_on_planes_is_the_kernel_on_rows():
    # the kernel runs on three contiguous coordinate planes: the same operations on the same
    # numbers as on (..., 3) rows with broadcast semi-axes, so the same bits — on batches with
    # groups, single point sets, points on the surface and at the centre
    rng = np.random.default_rng(81)
    for trial in range(60):
        K, n = int(rng.integers(1, 12)), int(rng.integers(1, 35))
        P = rng.normal(scale=0.04, size=(K, n, 3))
        a = rng.uniform(0.004, 0.05, size=(K, 1, 3))
        if trial % 3 == 0:
            P[0, 0] = 0.0  # the centre
            P[-1, -1] = [a[-1, 0, 0], 0.0, 0.0]  # a vertex, on the surface
        groups = None if trial % 2 else np.array(sorted({0, *rng.integers(1, K + 1, size=2).tolist()} - {K}))
        d, g = ellipsoid(P, a, groups=groups)
        d_rows, g_rows = _ellipsoid_rows(P, a, groups)
        np.testing.assert_array_equal(d, d_rows)
        np.testing.assert_array_equal(g, g_rows)
        assert g.flags.c_contiguous
    P = rng.normal(scale=0.04, size=(500, 3))
    a = np.broadcast_to(np.array([0.035, 0.02, 0.01]), P.shape)
    for got, plain in zip(ellipsoid(P, a), _ellipsoid_rows(P, a), strict=True):
        np.testing.assert_array_equal(got, plain)


@pytest.mark.parametrize("kind", KINDS)
def test_fits_sharing_evaluations_are_the_fits_alone(kind):
    # select_class's fits of a class (screening, quick fit, full fit) share one ClassStarts
    # and with it each start's evaluated points: every fit is, to the bit, the fit alone
    for seed in (21, 22):
        touches = random_touches("box" if kind != "box" else "cylinder", seed)
        shared = shape_fit.ClassStarts(touches)
        calls = [
            {"max_nfev": QUICK_NFEV, "max_starts": 1, "nearest_first": True},
            {"max_nfev": QUICK_NFEV},
            {},
            {"max_nfev": QUICK_NFEV},  # again, every point known
        ]
        for kwargs in calls:
            got = fit_class(kind, touches, class_starts=shared, **kwargs)
            alone = fit_class(kind, touches, **kwargs)
            assert got.chi2 == alone.chi2 and got.start == alone.start
            np.testing.assert_array_equal(got.theta, alone.theta)
            np.testing.assert_array_equal(got.covariance, alone.covariance)
            np.testing.assert_array_equal(got.geometry.rotation, alone.geometry.rotation)
        # MINPACK writes into the residuals its driver got first: the remembered ones stay
        for (k, _), evaluations in shared._evaluations.items():
            for key, (r, J, _) in evaluations.known.items():
                theta = np.frombuffer(key).copy()
                np.testing.assert_array_equal(r, shape_fit.residuals(theta, k, evaluations.r0, touches))
                np.testing.assert_array_equal(J, shape_fit._jacobian(theta, k, evaluations.r0, touches))


def test_batched_ellipsoid_distance_is_the_kernel_on_rows():
    # batch_signed_distance hands the ellipsoid its local points and semi-axes as planes
    rng = np.random.default_rng(83)
    for K, groups in ((1, None), (11, np.array([0, 10])), (7, np.array([0, 2, 5]))):
        centres = rng.normal(scale=0.01, size=(K, 3))
        rotations = np.array([shape_fit.rotation_vector(w) for w in rng.normal(size=(K, 3))])
        sizes = rng.uniform(0.01, 0.05, size=(K, 3))
        points = rng.normal(scale=0.04, size=(1, 29, 3))
        d, g = shape_fit.batch_signed_distance("ellipsoid", points, centres, rotations, sizes, groups)
        local = (points - centres[:, None, :]) @ rotations
        d_rows, g_rows = _ellipsoid_rows(local, sizes[:, None, :], groups)
        np.testing.assert_array_equal(d, d_rows)
        np.testing.assert_array_equal(g, g_rows @ rotations.transpose(0, 2, 1))


def test_difference_points_and_identities_are_the_plain_ones():
    # the difference points' diagonal stepped through a strided view, as fancy indexing does
    rng = np.random.default_rng(85)
    for k in (4, 7, 9):
        theta = rng.normal(scale=3.0, size=k)
        for copies in (1, 2):
            thetas, h = shape_fit._difference_points(theta, copies)
            plain = np.repeat(theta[None], k + copies, axis=0)
            plain[np.arange(k), np.arange(k)] += h
            np.testing.assert_array_equal(thetas, plain)
    # the sphere's rotations: contiguous identities, the products with them the broadcast view's
    K = 6
    rotations = shape_fit._identities(K)
    np.testing.assert_array_equal(rotations, np.broadcast_to(np.eye(3), (K, 3, 3)))
    assert shape_fit._identities(K) is rotations and not rotations.flags.writeable
    local = rng.normal(size=(K, 30, 3))
    local[0, :3] = [[-0.0, 0.0, 1.0], [0.0, -0.0, -0.0], [-0.0, -0.0, -0.0]]  # signed zeros
    for got, plain in ((local @ rotations, local @ np.broadcast_to(np.eye(3), (K, 3, 3))),
                       (local @ rotations.transpose(0, 2, 1), local @ np.broadcast_to(np.eye(3), (K, 3, 3)))):
        np.testing.assert_array_equal(got, plain)
        assert np.array_equal(np.signbit(got), np.signbit(plain))


@pytest.mark.parametrize("kind", ["box", "cylinder", "capsule"])
def test_kernels_on_planes_are_the_kernels_on_rows(kind):
    # box_planes, cylinder_planes, capsule_planes: the row kernels' elementwise operations on
    # the same numbers, so the same bits — at random points, on the axis, at the centre, on
    # faces, edges and caps, at ties between faces
    rng = np.random.default_rng(91)
    for trial in range(40):
        K, n = int(rng.integers(1, 12)), int(rng.integers(1, 35))
        P = rng.normal(scale=0.04, size=(K, n, 3))
        s = rng.uniform(0.004, 0.05, size=(K, 3))
        if trial % 2 == 0:
            P[0, 0] = 0.0  # the centre (a tie between all faces, on the axis)
            P[-1, -1] = [0.0, 0.0, 0.07]  # on the axis, outside
            P[0, -1] = [s[0, 0], 0.0, 0.0]  # on a face or the mantle
            P[-1, 0] = [-s[-1, 0], s[-1, 1], -s[-1, 1]]  # on an edge or beyond a cap
            P[K // 2, n // 2] = [0.5 * s[K // 2, 0], 0.0, 0.5 * s[K // 2, 0]]  # a tie inside
        planes = P.transpose(2, 0, 1).copy()
        if kind == "box":
            rows = shape_primitives.box(P, s[:, None, :])
            got = shape_primitives.box_planes(planes, s.T[:, :, None])
        elif kind == "cylinder":
            rows = shape_primitives.cylinder(P, s[:, :1], s[:, 1:2])
            got = shape_primitives.cylinder_planes(planes, s[:, :1], s[:, 1:2])
        else:
            rows = shape_primitives.capsule(P, s[:, :1], s[:, 1:2])
            got = shape_primitives.capsule_planes(planes, s[:, :1], s[:, 1:2])
        np.testing.assert_array_equal(got[0], rows[0])
        np.testing.assert_array_equal(got[1].transpose(1, 2, 0), rows[1])
        # the signs of zeros too (a zero gradient component enters the normal residuals)
        np.testing.assert_array_equal(np.signbit(got[1].transpose(1, 2, 0)), np.signbit(rows[1]))


@pytest.mark.parametrize("kind", ["box", "cylinder", "capsule"])
def test_batched_distance_is_the_row_kernel(kind):
    # batch_signed_distance runs these kernels on planes: the rows' distances and gradients
    rng = np.random.default_rng(93)
    kernel = {"box": shape_primitives.box, "cylinder": shape_primitives.cylinder,
              "capsule": shape_primitives.capsule}[kind]
    for K in (1, 7, 11):
        centres = rng.normal(scale=0.01, size=(K, 3))
        rotations = np.array([shape_fit.rotation_vector(w) for w in rng.normal(size=(K, 3))])
        sizes = rng.uniform(0.01, 0.05, size=(K, 3 if kind == "box" else 2))
        points = rng.normal(scale=0.04, size=(1, 29, 3))
        d, g = shape_fit.batch_signed_distance(kind, points, centres, rotations, sizes)
        local = (points - centres[:, None, :]) @ rotations
        args = (sizes[:, None, :],) if kind == "box" else (sizes[:, :1], sizes[:, 1:2])
        d_rows, g_rows = kernel(local, *args)
        np.testing.assert_array_equal(d, d_rows)
        np.testing.assert_array_equal(g, g_rows @ rotations.transpose(0, 2, 1))


@pytest.mark.parametrize("kind", KINDS)
def test_starts_evaluated_in_one_call_are_each_evaluated_alone(kind):
    # ClassStarts.evaluate_starts: every start's residuals, Jacobian and geometry at its own
    # parameters (compiled, one call each; the numpy reference: all in one batched call) —
    # to the bit what its _Evaluations computes alone; the nearest order from them is
    # _nearest_order's
    kernels.load()  # evaluate_starts compiled (until the kernels are ready it runs the numpy batch)
    for seed in (41, 42, 43):
        touches = random_touches("cylinder" if kind == "box" else "box", seed)
        shared = shape_fit.ClassStarts(touches)
        shared.evaluate_starts(kind)
        reference = shape_fit.ClassStarts(touches)
        shape_fit._evaluate_starts_numpy(reference, kind)
        candidates = shared.of(kind)
        for i, (theta0, r0) in enumerate(candidates):
            batched = shared.evaluations(kind, i)
            numpy_batched = reference.evaluations(kind, i)
            np.testing.assert_array_equal(batched.residuals(theta0), numpy_batched.residuals(theta0))
            np.testing.assert_array_equal(batched.jacobian(theta0), numpy_batched.jacobian(theta0))
            rotations = batched.geometry(theta0).rotation, numpy_batched.geometry(theta0).rotation
            np.testing.assert_array_equal(*rotations)
            alone = shape_fit._Evaluations(kind, r0, touches)
            np.testing.assert_array_equal(batched.residuals(theta0), alone.residuals(theta0))
            np.testing.assert_array_equal(batched.jacobian(theta0), alone.jacobian(theta0))
            g_batched, g_alone = batched.geometry(theta0), alone.geometry(theta0)
            np.testing.assert_array_equal(g_batched.rotation, g_alone.rotation)
            np.testing.assert_array_equal(g_batched.centre, g_alone.centre)
            assert g_batched.sizes == g_alone.sizes
        assert shared.nearest_order(kind) == shape_fit._nearest_order(kind, touches, candidates)


def test_offsets_from_point_planes_are_the_broadcast_difference():
    # offsets_from: the same subtractions on contiguous planes, laid out as C-contiguous rows
    rng = np.random.default_rng(95)
    for K, n, shared in ((1, 5, True), (11, 43, True), (7, 29, False)):
        points = rng.normal(scale=0.05, size=(1 if shared else K, n, 3))
        centres = rng.normal(scale=0.05, size=(K, 3))
        planes = np.ascontiguousarray(points.transpose(2, 0, 1))
        got = shape_fit.offsets_from(points, centres, planes)
        np.testing.assert_array_equal(got, points - centres[:, None, :])
        np.testing.assert_array_equal(shape_fit.offsets_from(points, centres), points - centres[:, None, :])
        assert got.flags.c_contiguous and got.shape == (K, n, 3)
