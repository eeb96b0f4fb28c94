"""The one tangent basis: the scalar hot-path form equals the plain numpy construction."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.errors import ValidationError
from eos_svc.kinematics.geometry import NEAR_AXIS, tangent_basis, tangent_pair


def tangent_basis_reference(n, prefer: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The same basis built the plain way with numpy (projection, ``np.cross``): what the tests
    compare :func:`tangent_pair` and :func:`tangent_basis` with."""
    nv = np.asarray(n, dtype=float).reshape(3)
    a = np.eye(3)[prefer] if abs(nv[prefer]) < NEAR_AXIS else np.eye(3)[1]
    t1 = a - (a @ nv) * nv
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(nv, t1)


def _normals(seed: int, count: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(count, 3))
    near = np.array(
        [[1, 0, 0], [0, 0, 1], [0, 1, 0], [-1, 0, 0], [0, 0, -1], [0.9, 0.43589, 0], [0, 0.4359, 0.9]]
    )
    n = np.vstack([n, near, near + 1e-3])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


@pytest.mark.parametrize("prefer", [0, 2])
def test_scalar_form_equals_the_plain_numpy_construction(prefer):
    for n in _normals(seed=prefer + 1, count=500):
        t1, t2 = tangent_basis(n, prefer)
        r1, r2 = tangent_basis_reference(n, prefer)
        np.testing.assert_allclose(t1, r1, atol=1e-15)
        np.testing.assert_allclose(t2, r2, atol=1e-15)
        assert np.array(tangent_pair(*n.tolist(), prefer)) == pytest.approx(np.r_[t1, t2], abs=0)
        # right-handed orthonormal (t1, t2, n)
        frame = np.column_stack([t1, t2, n])
        np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-14)
        assert np.linalg.det(frame) == pytest.approx(1.0, abs=1e-14)


def test_preferred_axis_projected_unless_nearly_parallel():
    n = np.array([0.0, 0.6, 0.8])
    t1, _ = tangent_basis(n, prefer=0)
    np.testing.assert_allclose(t1, [1.0, 0.0, 0.0])  # world x is already tangent
    t1, _ = tangent_basis(n, prefer=2)
    np.testing.assert_allclose(t1, [0.0, -0.8, 0.6])  # world z projected: (0,0,1) − 0.8 n, normalised
    t1, _ = tangent_basis([0.95, 0.0, 0.3122498999], prefer=0)  # within ~25° of x: world y is used
    np.testing.assert_allclose(t1, [0.0, 1.0, 0.0], atol=1e-12)


def test_unknown_preferred_axis_is_refused():
    with pytest.raises(ValidationError, match="prefer"):
        tangent_pair(0.0, 0.0, 1.0, prefer=1)
