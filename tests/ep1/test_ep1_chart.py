"""EP1's tactile chart against closed forms: the log chart's geodesic coordinates on the tip
sphere (arc length r·angle, in the tangent basis) and the slope fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.kinematics.ep1 import EP1Error, _chart_at_mean, _fit_slope


def test_chart_coordinates_are_geodesic_arcs_on_the_tip() -> None:
    """A point at angle a from the chart's centre along the tangent direction t lands at r·a·t."""
    r = 0.01
    rng = np.random.default_rng(11)
    for _ in range(20):
        b = rng.normal(size=3)
        b /= np.linalg.norm(b)
        ex_tip = rng.normal(size=3)
        ex = ex_tip - (ex_tip @ b) * b
        ex /= np.linalg.norm(ex)
        ey = np.cross(b, ex)
        angles = rng.uniform(0.0, 0.6, 4)
        headings = rng.uniform(-math.pi, math.pi, 4)
        # points symmetric about b so that their mean direction is b itself
        pts, want = [], []
        for a, h in zip(angles, headings, strict=True):
            for sign in (1.0, -1.0):
                t = sign * (math.cos(h) * ex + math.sin(h) * ey)
                pts.append(r * (math.cos(a) * b + math.sin(a) * t))
                want.append(r * a * np.array([t @ ex, t @ ey]))
        got = _chart_at_mean(np.array(pts), ex_tip, r)
        assert np.allclose(got, np.array(want), atol=1e-12)


def test_fit_slope_recovers_the_quadratics_slope_and_matches_lstsq() -> None:
    """The slope at ϑ = 0 of an exact quadratic (both coordinates), and of noisy samples that of
    numpy's ``lstsq`` within 1e-9 (relative), over a leg's angles (±0.2 rad, 5–40 readings)."""
    rng = np.random.default_rng(5)
    for n in (5, 8, 16, 40):
        theta = rng.uniform(-0.2, 0.2, n)
        exact = (
            np.outer(np.ones(n), [1e-3, -2e-3])
            + np.outer(theta, [0.01, 0.02])
            + np.outer(theta**2, [0.3, -0.1])
        )
        assert np.allclose(_fit_slope(theta, exact), [0.01, 0.02], rtol=0, atol=1e-12)
        noisy = exact + rng.normal(size=(n, 2)) * 2e-4
        X = np.array((np.ones(n), theta, theta * theta)).T
        reference = np.linalg.lstsq(X, noisy, rcond=None)[0][1]
        assert np.allclose(_fit_slope(theta, noisy), reference, rtol=1e-9, atol=1e-12)


def test_fit_slope_names_too_few_distinct_angles() -> None:
    with pytest.raises(EP1Error, match="state"):
        _fit_slope(np.zeros(5), np.zeros((5, 2)))  # the tip never turned
