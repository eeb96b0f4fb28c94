"""The starts' small geometry: frames about an axis, products and columns."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.shape.starts import columns, cross, frame_with_z


def test_frame_with_z_is_a_rotation_about_the_axis():
    rng = np.random.default_rng(2)
    for axis in [*rng.normal(size=(20, 3)), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -2.0])]:
        R = frame_with_z(axis)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(R[:, 2], axis / np.linalg.norm(axis), atol=1e-15)


def test_cross_and_columns_are_the_products_and_stack():
    u, v = np.array([0.3, -1.2, 2.0]), np.array([4.0, 0.5, -0.7])
    np.testing.assert_allclose(cross(u, v), np.cross(u, v), rtol=1e-15)
    np.testing.assert_array_equal(columns(u, v, u), np.column_stack([u, v, u]))
