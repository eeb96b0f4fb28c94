"""The rolling step's contact probe (reused coal objects) gives the exact contact: the scene's
analytic closest point (``exact_tips``), the plain way."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.kinematics import Scene
from eos_svc.kinematics.ep1 import ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.tip_contact import SphereTipProbe


@pytest.mark.parametrize(
    ("shape", "size", "tol"),
    [("sphere", 0.04, 1e-9), ("cylinder", 0.03, 1e-9), ("plane", 0.05, 1e-9), ("ellipsoid", 0.05, 1e-8)],
)
def test_probe_equals_the_exact_contact_along_a_path(shape, size, tol):
    sc = ep1_scene(shape, size)
    exact = Scene(sc.hand, sc.object, exact_tips=True)
    q0 = place_hand_for_ep1(sc, "finger1")
    hand = sc.hand
    probe = SphereTipProbe("finger1", hand.tip_radius("finger1"), sc.object.geometry)
    probe.place_object(sc.object.placement)
    rng = np.random.default_rng(4)
    idx = hand.finger_q_index("finger1")
    for k in range(12):  # touching, penetrating and apart
        q = q0.copy()
        q[idx] += rng.uniform(-0.05, 0.05, size=len(idx)) * (k % 3)
        st = hand.state(q)
        plain = exact.contact(st, "finger1")
        fast = probe.measure(st.tip_position("finger1"))
        assert fast.finger == plain.finger
        assert fast.distance == pytest.approx(plain.distance, abs=tol)
        np.testing.assert_allclose(fast.normal, plain.normal, atol=1e3 * tol)
        np.testing.assert_allclose(fast.point_tip, plain.point_tip, atol=250 * tol)
        np.testing.assert_allclose(fast.point_object, plain.point_object, atol=250 * tol)
