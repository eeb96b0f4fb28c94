"""The touches' support of predicted contacts, and grasp synthesis ranking by it."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from eos_svc.agents import ObjectSpec
from eos_svc.grasp.support import SUPPORT_ANGLE_DEG, SUPPORT_RADIUS, TouchSupport
from eos_svc.grasp.synthesis import GraspSynthesis
from tests.grasp.scenes import HERE, synthesis


def test_a_contact_is_supported_by_a_near_touch_with_a_like_normal():
    up = np.array([0.0, 0.0, 1.0])
    support = TouchSupport(np.array([[0.0, 0.0, 0.0]]), up[None, :])
    assert support.supported(np.array([0.0, 0.0, 0.9 * SUPPORT_RADIUS]), up)
    assert not support.supported(np.array([1.1 * SUPPORT_RADIUS, 0.0, 0.0]), up)  # too far
    tilt = math.radians(SUPPORT_ANGLE_DEG + 1.0)
    assert not support.supported(np.zeros(3), np.array([math.sin(tilt), 0.0, math.cos(tilt)]))
    tilt = math.radians(SUPPORT_ANGLE_DEG - 1.0)
    assert support.supported(np.zeros(3), np.array([math.sin(tilt), 0.0, math.cos(tilt)]))


def test_synthesis_prefers_the_grasp_whose_contacts_were_touched():
    box = trimesh.creation.box(extents=[0.05, 0.04, 0.045])
    size = {"vertices": box.vertices.tolist(), "faces": box.faces.tolist(), "scale": 1.0}
    plain = synthesis(ObjectSpec("mesh", size, HERE))
    ranked = plain.candidates()
    assert len(ranked) >= 2
    last = ranked[-1]  # the least preferred on ε and wrist rotation alone
    opposing = plain.opposing
    hits = last.landings.values()
    touched = TouchSupport(np.array([h.point for h in hits]), np.array([h.normal for h in hits]))
    assert touched.rank(last, opposing) == (True, len(last.landings))
    supported = GraspSynthesis(
        plain.hand, plain.sweeps, plain.params, plain.obj, plain.friction, support=touched
    )
    best = supported.candidates()[0]
    assert touched.rank(best, opposing) == (True, len(best.landings))
    assert best.label == last.label and np.allclose(best.wrist, last.wrist)
