"""Fitting the object kinds to touches: recovery of known objects, model selection."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents.planner import make_object
from eos_svc.schema.request import ObjectSpec
from eos_svc.shape import Touches, fit_class, select_class
from eos_svc.shape.selection import object_dict
from tests.shape.synthetic import TIP, objects, touches_on, with_free


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("kind", ["sphere", "ellipsoid", "cylinder", "capsule", "box"])
def test_select_recovers_known_primitives(kind, seed):
    obj = objects(rpy=(0.1 * seed, 0.2, 0.4 * seed))[kind]
    rng = np.random.default_rng(seed)
    post = select_class(touches_on(obj, rng, n=30, keep=lambda d: True))
    assert post.kind == kind, post.probabilities
    assert post.confidence >= 0.6  # sure enough to grasp (an end touched by few probes is less sure)
    spec = ObjectSpec.from_dict(post.object())  # the request's own form
    fitted = make_object(spec)
    # every point of the true surface within 1 mm of the postulated one
    probe = np.asarray(obj.placement.translation) + rng.normal(scale=0.1, size=(100, 3))
    surface = np.array([obj.closest_surface_point(p) for p in probe])
    err = np.array([abs(fitted.signed_distance(s)) for s in surface])
    assert np.sqrt(np.mean(err**2)) < 1e-3, err.max()


def test_a_cylinder_felt_only_on_its_side_is_not_known_as_a_cylinder():
    # contacts on the curved side only: a capsule of the same radius fits them as well
    obj = objects(rpy=(0.0, 0.0, 0.0))["cylinder"]  # axis along z, caps at ±40 mm
    post = select_class(touches_on(obj, np.random.default_rng(3), keep=lambda d: abs(d[2]) < 0.05))
    assert post.kind in ("cylinder", "capsule")
    assert post.probabilities["cylinder"] + post.probabilities["capsule"] > 0.95
    assert post.confidence < 0.6  # the ends are not known: not confident


def test_one_face_is_a_plane():
    rng = np.random.default_rng(4)
    centres = np.column_stack([rng.uniform(-0.05, 0.05, 10), rng.uniform(-0.05, 0.05, 10), np.full(10, TIP)])
    normals = np.tile([0.0, 0.0, 1.0], (10, 1)) + rng.normal(scale=0.01, size=(10, 3))
    post = select_class(Touches(centres, normals, TIP))
    assert post.kind == "plane" and post.object() is None and post.confidence == 0.0


def test_too_few_contacts_is_a_clear_error():
    with pytest.raises(ValueError, match="at least"):
        select_class(Touches(np.zeros((2, 3)), np.tile([0.0, 0.0, 1.0], (2, 1)), TIP))


def test_free_space_bounds_a_box_that_no_contact_bounds():
    # the box's back (+x) is never touched; free tip samples behind it bound its depth
    obj = objects(rpy=(0.0, 0.0, 0.0))["box"]  # 50 × 60 × 40 mm at x = 0.2
    rng = np.random.default_rng(5)
    t = touches_on(obj, rng, n=20, keep=lambda d: d[0] > 0.95)  # probes along +x: the front face
    alone = fit_class("box", t)
    n = 8
    free = np.column_stack(
        [np.full(n, 0.2 + 0.025 + TIP + 0.001), rng.uniform(-0.03, 0.03, n), rng.uniform(-0.02, 0.02, n)]
    )
    bounded = fit_class("box", with_free(t, free, TIP))
    assert alone.size_sigmas()[0] > 0.5  # depth unknown from the front alone
    assert object_dict(bounded)["size"][0] <= 0.05 + 2e-3  # the free samples bound it
