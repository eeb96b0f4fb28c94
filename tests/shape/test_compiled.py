"""The fit's compiled residuals (the optional accelerator, numba) against the numpy version.

Tolerance: the compiled loop sums the same terms in another order (and stops the ellipsoid's
Newton iteration per point rather than per call), so the two agree to rounding, not bit for
bit: within 1e-9 of the residuals' scale (whitened units, residuals of order 1–1000).
"""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.shape import fit, kernels, select_class
from eos_svc.shape.starts import ClassStarts
from eos_svc.shape.touches import Touches
from tests.shape.synthetic import objects, touches_on, with_free

pytest.importorskip("numba")

TOLERANCE = 1e-9


@pytest.fixture()
def compiled():
    """The compiled residuals loaded for one test, numpy again after it."""
    assert kernels.load()
    yield kernels.compiled_residuals()
    kernels.unload()


def _agree(a: np.ndarray, b: np.ndarray) -> None:
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) <= TOLERANCE * max(1.0, float(np.max(np.abs(a))))


@pytest.mark.parametrize("kind", fit.N_PARAMS)
def test_compiled_residuals_match_numpy_near_and_far_from_the_fit(kind, compiled):
    """Parameters scattered about every start (sizes ×/÷ up to 1.5, centres off by cm, turned):
    touches inside, outside and on both sides of every face and rim; free samples too."""
    rng = np.random.default_rng(3)
    obj = objects()[kind]
    touches = with_free(touches_on(obj, rng, n=16), obj.centre + rng.normal(0.0, 0.05, (12, 3)), 0.01)
    data = touches
    for theta0, r0 in ClassStarts(touches).of(kind):
        thetas = (
            theta0 + rng.normal(0.0, 0.4, (40, len(theta0))) * np.r_[[0.03] * 3, [1.0] * (len(theta0) - 3)]
        )
        thetas[0] = theta0
        _agree(fit.whitened_residuals(thetas, kind, r0, data), fit.numpy_residuals(thetas, kind, r0, data))


def test_compiled_ellipsoid_near_its_centre_and_surface(compiled):
    """The ellipsoid's hard points: at the centre, on the short axis' plane inside (the pole
    case), on the surface, and a point per parameter vector with its own start orientation."""
    touches = Touches(
        np.array(
            [[0.0, 0.0, 0.0], [0.01, 0.005, 0.0], [0.035, 0.0, 0.0], [0.0, 0.0, 0.05], [1e-4, -2e-3, 1e-9]]
        ),
        np.eye(3)[[0, 1, 2, 0, 1]],
        0.01,
    )
    data = touches
    rng = np.random.default_rng(5)
    thetas = np.concatenate(
        [rng.normal(0.0, 1e-3, (6, 3)), rng.normal(0.0, 0.3, (6, 3)), np.log([[0.035, 0.03, 0.022]] * 6)],
        axis=1,
    )
    r0s = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(6)])
    r0s[np.linalg.det(r0s) < 0] *= -1.0
    _agree(
        fit.whitened_residuals(thetas, "ellipsoid", r0s, data),
        fit.numpy_residuals(thetas, "ellipsoid", r0s, data),
    )


@pytest.mark.parametrize("kind", ["ellipsoid", "box", "capsule"])
def test_selection_is_the_same_with_either_residuals(kind, compiled):
    """The whole selection — kind, posterior, confidence, fitted sizes — with the compiled
    residuals as with numpy (to 1e-6: least squares on residuals equal to rounding)."""
    touches = touches_on(objects()[kind], np.random.default_rng(11), n=20)
    fast = select_class(touches)
    kernels.unload()
    plain = select_class(touches)
    assert fast.kind == plain.kind == kind
    assert fast.confidence == pytest.approx(plain.confidence, abs=1e-6)
    for k in plain.probabilities:
        assert fast.probabilities[k] == pytest.approx(plain.probabilities[k], abs=1e-6)
    np.testing.assert_allclose(
        fast.fits[kind].geometry.half_sizes, plain.fits[kind].geometry.half_sizes, rtol=1e-6
    )


def test_without_load_the_fit_runs_in_numpy():
    """The default: nothing loaded, no compiled residuals."""
    kernels.unload()
    assert kernels.compiled_residuals() is None
