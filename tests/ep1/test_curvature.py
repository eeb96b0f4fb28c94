"""The estimator: sign convention proved on independent rolling kinematics, LS, σ, rating."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eos_svc.kinematics.curvature import CurvatureEstimator, UnderdeterminedError

from . import synthetic as syn

R_F = 0.01
KF = np.eye(2) / R_F


def _sample_from_roll(closest, p0, n0, axis_c, frame, omega=0.5, T=0.02):
    """One sample (ω_xy, u) in contact frame from a short synthetic roll."""
    w_world = omega * (frame @ np.array([axis_c[0], axis_c[1], 0.0]))
    traj, t = syn.roll(closest, p0, n0, R_F, w_world, T, steps=200)
    # initial rate of the tactile point (tip frame == world at t=0), 2nd-order one-sided
    h = t[1] - t[0]
    u_world = (-3 * traj[0] + 4 * traj[1] - traj[2]) / (2 * h)
    u_c = frame.T @ u_world
    assert abs(u_c[2]) < 1e-6
    return omega * np.asarray(axis_c, float), u_c[:2]


@pytest.mark.parametrize(
    ("name", "closest", "p0", "n0", "k_true"),
    [
        ("sphere4cm", syn.sphere(0.04), np.array([0.04, 0, 0]), np.array([1.0, 0, 0]), (25.0, 25.0)),
        ("plane", syn.plane(), np.zeros(3), np.array([0, 0, 1.0]), (0.0, 0.0)),
        ("cyl2cm", syn.cylinder(0.02), np.array([0.02, 0, 0]), np.array([1.0, 0, 0]), (50.0, 0.0)),
    ],
)
def test_sign_convention_on_independent_kinematics(name, closest, p0, n0, k_true):
    """(K_o + K_f) u = [-ω_y, ω_x] holds on rolling simulated without the estimator."""
    frame = syn.contact_frame(n0)
    est = CurvatureEstimator()
    for axis in ([1.0, 0.0], [0.0, 1.0], [math.sqrt(0.5), math.sqrt(0.5)]):
        w, u = _sample_from_roll(closest, p0, n0, axis, frame)
        est.add_sample(w, u, KF)
    e = est.estimate()
    assert sorted(e.principal_curvatures) == pytest.approx(sorted(k_true), abs=0.05)
    assert e.residual_rms < 1e-4
    if name == "plane":
        assert e.is_flat and e.radii == (math.inf, math.inf)
    # the opposite sign of the right-hand side would give a wildly wrong form
    wrong = CurvatureEstimator()
    for s in est.samples:
        wrong.add_sample(-s.omega_xy, s.contact_velocity, KF)
    assert wrong.estimate().mean_curvature < -1.5 / R_F


def test_arc_rate_closed_form_sphere_and_plane():
    """Contact speed over the tip = |ω| r_f R / (r_f + R) on a sphere, |ω| r_f on a plane."""
    om = 0.7
    for R, closest, p0, n0 in [
        (0.02, syn.sphere(0.02), np.array([0.02, 0, 0]), np.array([1.0, 0, 0])),
        (math.inf, syn.plane(), np.zeros(3), np.array([0, 0, 1.0])),
    ]:
        frame = syn.contact_frame(n0)
        traj, _t = syn.roll(closest, p0, n0, R_F, om * frame[:, 0], 0.3, steps=3000)
        arc = np.sum(np.linalg.norm(np.diff(traj, axis=0), axis=1))
        expected = om * R_F * (1.0 if math.isinf(R) else R / (R_F + R)) * 0.3
        assert arc == pytest.approx(expected, rel=1e-4)


def _forward_samples(K_o, rng, n=20, noise=0.0):
    """Samples from u = (K_o + K_f)^-1 [-ω_y, ω_x] with random tangent ω."""
    out = []
    for _ in range(n):
        w = rng.normal(size=2)
        u = np.linalg.solve(K_o + KF, np.array([-w[1], w[0]]))
        out.append((w, u + noise * rng.normal(size=2)))
    return out


def test_recovers_arbitrary_symmetric_form():
    rng = np.random.default_rng(1)
    for _ in range(20):
        a = rng.normal(scale=30, size=(2, 2))
        K = 0.5 * (a + a.T)
        if np.min(np.linalg.eigvalsh(K + KF)) < 10:
            continue
        est = CurvatureEstimator()
        for w, u in _forward_samples(K, rng):
            est.add_sample(w, u, KF)
        e = est.estimate()
        np.testing.assert_allclose(e.form, K, atol=1e-8)
        k1, k2 = e.principal_curvatures
        assert k1 >= k2
        np.testing.assert_allclose(sorted((k1, k2)), np.linalg.eigvalsh(K), atol=1e-8)
        d = e.principal_directions
        np.testing.assert_allclose(K @ d[:, 0], k1 * d[:, 0], atol=1e-8)


def test_sigma_matches_monte_carlo_spread():
    """The residual-based σ of H agrees with the spread of estimates over seeds."""
    K = np.eye(2) * 25.0
    Hs, sig = [], []
    for seed in range(300):
        rng = np.random.default_rng(seed)
        est = CurvatureEstimator()
        for w, u in _forward_samples(K, rng, n=30, noise=1e-3):
            est.add_sample(w, u, KF)
        e = est.estimate()
        Hs.append(e.mean_curvature)
        sig.append(e.sigma_mean_curvature)
    assert np.std(Hs) == pytest.approx(np.median(sig), rel=0.25)
    e = est.estimate()
    assert 0.0 <= e.rating <= 1.0
    assert e.rating == pytest.approx(max(0.0, 1 - e.relative_error))
    assert e.relative_error == pytest.approx(e.sigma_mean_curvature / abs(e.mean_curvature))


def test_rating_floor_and_inf_without_dof():
    est = CurvatureEstimator()
    rng = np.random.default_rng(3)
    # two samples: 4 equations, 1 dof -> finite; rating is in [0, 1]
    for w, u in _forward_samples(np.eye(2) * 25, rng, n=2, noise=0.01):
        est.add_sample(w, u, KF)
    e = est.estimate()
    assert 0.0 <= e.rating <= 1.0
    # huge noise -> relative error > 1 -> rating floored at 0
    bad = CurvatureEstimator()
    for w, u in _forward_samples(np.eye(2) * 25, rng, n=10, noise=0.004):
        bad.add_sample(w, u, KF)
    assert bad.estimate().rating == 0.0


def test_underdetermined_and_bad_input():
    est = CurvatureEstimator()
    with pytest.raises(UnderdeterminedError):
        est.estimate()
    for _ in range(5):  # one roll direction only
        est.add_sample([1.0, 0.0], [0.0, 0.008], KF)
    with pytest.raises(UnderdeterminedError, match="two independent"):
        est.estimate()
    with pytest.raises(ValueError, match="omega_xy"):
        est.add_sample([math.nan, 0.0], [0.0, 1.0], KF)
    with pytest.raises(ValueError, match="K_f"):
        est.add_sample([1.0, 0.0], [0.0, 1.0], [[1.0, 2.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="flat_curvature"):
        CurvatureEstimator(flat_curvature=-1.0)


def test_accumulates_across_estimators():
    rng = np.random.default_rng(5)
    a, b = CurvatureEstimator(), CurvatureEstimator()
    for w, u in _forward_samples(np.diag([30.0, 10.0]), rng, n=6, noise=1e-4):
        a.add_sample(w, u, KF)
    b.add_samples(a.samples)
    assert b.n_samples == 6
    np.testing.assert_allclose(a.estimate().form, b.estimate().form)
    d = a.estimate().to_dict()
    assert d["n_samples"] == 6 and len(d["radii"]) == 2


@settings(max_examples=60, deadline=None)
@given(
    k=st.tuples(st.floats(-50, 200), st.floats(-60, 60), st.floats(-50, 200)),
    phis=st.lists(st.floats(0, math.pi), min_size=2, max_size=6, unique=True),
)
def test_property_recovers_any_form_from_two_directions(k, phis):
    """Any symmetric K_o with K_o + K_f positive definite is recovered exactly from rolls
    along at least two independent directions."""
    K = np.array([[k[0], k[1]], [k[1], k[2]]])
    if np.min(np.linalg.eigvalsh(K + KF)) < 5.0:
        return
    dirs = np.array([[math.cos(p), math.sin(p)] for p in phis])
    if abs(np.linalg.det(dirs[:2] @ dirs[:2].T)) < 1e-3:
        return
    est = CurvatureEstimator()
    for w in dirs:
        est.add_sample(w, np.linalg.solve(K + KF, np.array([-w[1], w[0]])), KF)
    np.testing.assert_allclose(est.estimate().form, K, atol=1e-6 * (1 + np.abs(K).max()))
