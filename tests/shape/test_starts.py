"""The starts' small geometry: frames about an axis."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.shape.starts import frame_with_z


def test_frame_with_z_is_a_rotation_about_the_axis():
    rng = np.random.default_rng(2)
    for axis in [*rng.normal(size=(20, 3)), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -2.0])]:
        R = frame_with_z(axis)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(R[:, 2], axis / np.linalg.norm(axis), atol=1e-15)
