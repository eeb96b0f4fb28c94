"""EP1's fitting kernels (the log chart, the rotation vectors) give the plain numpy forms'
numbers bit for bit (the forms are kept here as the reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.kinematics.ep1 import _chart_at_mean, _log3
from eos_svc.kinematics.norms import row_norms


def plain_log3(R: np.ndarray) -> np.ndarray:
    v = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    s2 = np.linalg.norm(v, axis=1)
    c = 0.5 * (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1.0)
    theta = np.arctan2(0.5 * s2, c)
    scale = np.where(s2 > 1e-12, theta / np.maximum(s2, 1e-300), 0.5 + theta * theta / 12.0)
    return v * scale[:, None]


def plain_log_chart(points, b, ex, ey, r):
    d = points / np.linalg.norm(points, axis=1, keepdims=True)
    cosang = d @ b
    v = d - np.outer(cosang, b)
    sin_ang = np.linalg.norm(v, axis=1)
    ang = np.arctan2(sin_ang, cosang)
    scale = np.where(sin_ang > 1e-15, r * ang / np.maximum(sin_ang, 1e-300), r)
    v = v * scale[:, None]
    return np.column_stack([v @ ex, v @ ey])


def plain_chart_at_mean(P, ex_t, r):
    ex_t0, ex_t1, ex_t2 = ex_t
    b0, b1, b2 = P.mean(axis=0).tolist()
    nb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
    b0, b1, b2 = b0 / nb, b1 / nb, b2 / nb
    d = ex_t0 * b0 + ex_t1 * b1 + ex_t2 * b2
    e0, e1, e2 = ex_t0 - d * b0, ex_t1 - d * b1, ex_t2 - d * b2
    ne = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    e0, e1, e2 = e0 / ne, e1 / ne, e2 / ne
    return plain_log_chart(
        P,
        np.array((b0, b1, b2)),
        np.array((e0, e1, e2)),
        np.array((b1 * e2 - b2 * e1, b2 * e0 - b0 * e2, b0 * e1 - b1 * e0)),
        r,
    )


def _rotations(rng, n, spread):
    import pinocchio as pin

    return np.array([pin.exp3(rng.normal(size=3) * spread) for _ in range(n)])


@pytest.mark.parametrize("n", [5, 7, 8, 9, 16, 33])
def test_kernels_equal_the_plain_forms(n):
    rng = np.random.default_rng(n)
    for spread in (1e-9, 0.05, 0.4):
        R = _rotations(rng, n, spread)
        assert _log3(R).tolist() == plain_log3(R).tolist()
        r = 0.01
        centre = rng.normal(size=3)
        centre /= np.linalg.norm(centre)
        P = r * (centre + spread * rng.normal(size=(n, 3)))
        P = r * P / np.linalg.norm(P, axis=1, keepdims=True)
        ex = tuple(np.linalg.qr(rng.normal(size=(3, 3)))[0][:, 0].tolist())
        expected = plain_chart_at_mean(P, ex, r).tolist()
        assert _chart_at_mean(P, ex, r).tolist() == expected
        # with the directions normalised once over a larger set, then selected (as run_ep1 does)
        extra = r * rng.normal(size=(n + 3, 3))
        both = np.concatenate([extra, P])
        sel = np.arange(len(both)) >= len(extra)
        directions = (both / row_norms(both, keepdims=True))[sel]
        assert _chart_at_mean(both[sel], ex, r, directions).tolist() == expected


def plain_estimate(samples, kf):
    """CurvatureEstimator.estimate's numbers in their plain numpy form (numpy scalars, stack,
    trace, fancy column order): (form, cov, ks, dirs, sig, H, sH, rel)."""
    from eos_svc.kinematics.curvature import _eigh, _inv, _solve

    m = len(samples)
    U = np.array([s.contact_velocity for s in samples])
    W = np.array([s.omega_xy for s in samples])
    K = np.array([s.K_f for s in samples])
    A3 = np.zeros((m, 2, 3))
    A3[:, 0, :2] = U
    A3[:, 1, 1:] = U
    A = A3.reshape(2 * m, 3)
    Ku = K[:, :, 0] * U[:, :1] + K[:, :, 1] * U[:, 1:]
    b = (np.stack([-W[:, 1], W[:, 0]], axis=1) - Ku).reshape(2 * m)
    AtA = A.T @ A
    assert float(np.trace(AtA)) > 0
    theta = _solve(AtA, A.T @ b)
    r = b - A @ theta
    cov = float(r @ r) / (2 * m - 3) * _inv(AtA)
    form = np.array([[theta[0], theta[1]], [theta[1], theta[2]]])
    evals, evecs = _eigh(form)
    order = [1, 0]
    ks = (float(evals[order[0]]), float(evals[order[1]]))
    dirs = evecs[:, order]
    sig = []
    for j in range(2):
        vx, vy = dirs[:, j]
        g = np.array([vx * vx, 2 * vx * vy, vy * vy])
        sig.append(math.sqrt(max(float(g @ cov @ g), 0.0)))
    gH = np.array([0.5, 0.0, 0.5])
    H = 0.5 * (theta[0] + theta[2])
    sH = math.sqrt(max(float(gH @ cov @ gH), 0.0))
    return form, cov, ks, dirs, sig, float(H), sH, sH / max(abs(H), kf)


@pytest.mark.parametrize("seed", range(6))
def test_estimate_equals_the_plain_form(seed: int) -> None:
    from eos_svc.kinematics.curvature import CurvatureEstimator

    rng = np.random.default_rng(seed)
    est = CurvatureEstimator()
    k = rng.normal(size=(2, 2)) * 30.0
    k = k + k.T
    for _ in range(int(rng.integers(2, 13))):
        phi = rng.uniform(0.0, math.pi)
        w = np.array([math.cos(phi), math.sin(phi)])
        u = np.linalg.solve(k + np.eye(2) / 0.01, np.array([-w[1], w[0]])) + rng.normal(size=2) * 1e-4
        est.add_sample(w, u, np.eye(2) / 0.01)
    got = est.estimate()
    form, cov, ks, dirs, sig, H, sH, rel = plain_estimate(est.samples, est.flat_curvature)
    assert got.form.tobytes() == form.tobytes() and got.covariance.tobytes() == cov.tobytes()
    assert got.principal_curvatures == ks and got.principal_directions.tobytes() == dirs.tobytes()
    assert got.sigma_curvatures == tuple(sig)
    assert (got.mean_curvature, got.sigma_mean_curvature, got.relative_error) == (H, sH, rel)
