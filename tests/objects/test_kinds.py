"""Every object kind against independent checks: the batched signed distance against finite
differences and brute-force surface samples, the JSON form, extents, coal's distance, Drake's
inertia."""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest
from pydrake.multibody.tree import SpatialInertia

from eos_svc.errors import ValidationError
from eos_svc.objects import (
    FITTED_KINDS,
    KINDS,
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    ObjectSizeError,
    Sphere,
    SurfaceObject,
    make,
)
from eos_svc.objects import from_dict as object_from_dict

PLACEMENT = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.4, 1.1), np.array([0.2, -0.05, 0.1]))


def every_kind(placement: pin.SE3 = PLACEMENT) -> list[SurfaceObject]:
    return [
        Sphere(0.03, placement),
        Ellipsoid([0.045, 0.03, 0.02], placement),
        Cylinder(0.02, 0.08, placement),
        Capsule(0.02, 0.06, placement),
        Box([0.05, 0.06, 0.04], placement),
    ]


def surface_samples(obj: SurfaceObject, rng: np.random.Generator, n: int = 4000) -> np.ndarray:
    """Points on the surface (world), found independently: bisection of the signed distance's
    sign along rays from the centre."""
    c = obj.centre
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    lo, hi = np.zeros(n), np.full(n, obj.diameter)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        d, _ = obj.signed_distances(c + mid[:, None] * u)
        inside = d < 0.0
        lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
    return c + (0.5 * (lo + hi))[:, None] * u


def test_the_registry_names_every_kind_once():
    assert list(KINDS) == ["sphere", "ellipsoid", "cylinder", "capsule", "box", "mesh"]
    assert list(FITTED_KINDS) == ["sphere", "ellipsoid", "cylinder", "capsule", "box"]
    assert all(cls.kind == name for name, cls in KINDS.items())


@pytest.mark.parametrize("obj", every_kind(), ids=lambda o: o.kind)
def test_the_gradient_is_the_finite_difference_of_the_distance(obj: SurfaceObject):
    rng = np.random.default_rng(1)
    points = obj.centre + rng.normal(scale=0.04, size=(300, 3))
    d, g = obj.signed_distances(points)
    eps = 1e-7
    for p, di, gi in zip(points, d, g, strict=True):
        numeric = np.array(
            [
                (obj.signed_distance(p + eps * e) - obj.signed_distance(p - eps * e)) / (2 * eps)
                for e in np.eye(3)
            ]
        )
        if abs(np.linalg.norm(numeric) - 1.0) < 1e-4:  # away from the kinks (inside a box's diagonals)
            np.testing.assert_allclose(gi, numeric, atol=1e-5)
        assert di == pytest.approx(obj.signed_distance(p), abs=1e-12)  # batched = point-wise


@pytest.mark.parametrize("obj", every_kind(), ids=lambda o: o.kind)
def test_the_distance_is_the_distance_to_the_nearest_surface_sample(obj: SurfaceObject):
    rng = np.random.default_rng(2)
    surface = surface_samples(obj, rng)
    points = obj.centre + rng.normal(scale=0.04, size=(60, 3))
    d, _ = obj.signed_distances(points)
    for p, di in zip(points, d, strict=True):
        brute = float(np.min(np.linalg.norm(surface - p, axis=1)))
        assert abs(di) <= brute + 1e-9  # never farther than a sample ...
        assert abs(di) >= brute - 4e-3  # ... and close to the nearest (the samples' spacing)
        s = obj.closest_surface_point(p)
        assert abs(obj.signed_distance(s)) < 1e-9
        assert np.linalg.norm(p - s) == pytest.approx(abs(di), abs=1e-12)


@pytest.mark.parametrize("obj", every_kind(), ids=lambda o: o.kind)
def test_coal_measures_the_same_distance(obj: SurfaceObject):
    rng = np.random.default_rng(3)
    point, r = coal.Sphere(1e-6), coal.DistanceRequest()
    placed = coal.Transform3s(obj.rotation, obj.centre)
    for p in obj.centre + rng.normal(scale=0.06, size=(40, 3)):
        d = obj.signed_distance(p)
        if d > 1e-3:
            res = coal.DistanceResult()
            coal.distance(obj.geometry, placed, point, coal.Transform3s(np.eye(3), p), r, res)
            assert res.min_distance + 1e-6 == pytest.approx(d, abs=1e-6)


@pytest.mark.parametrize("obj", every_kind(), ids=lambda o: o.kind)
def test_extents_bound_the_surface(obj: SurfaceObject):
    rng = np.random.default_rng(4)
    surface = surface_samples(obj, rng)
    reach = np.max(np.abs(surface - obj.centre), axis=0)
    assert np.all(reach <= obj.half_extents() + 1e-9)
    assert np.all(reach >= obj.half_extents() - 3e-3)
    assert np.max(np.linalg.norm(surface - obj.centre, axis=1)) <= 0.5 * obj.diameter + 1e-9
    for u in rng.normal(size=(20, 3)):
        u /= np.linalg.norm(u)
        t = obj.half_extent(u)
        assert obj.signed_distance(obj.centre + t * u) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("obj", every_kind(pin.SE3.Identity()), ids=lambda o: o.kind)
def test_mass_properties_are_drakes(obj: SurfaceObject):
    a = obj.half_sizes
    drake = {
        "sphere": lambda: SpatialInertia.SolidSphereWithMass(2.0, a[0]),
        "ellipsoid": lambda: SpatialInertia.SolidEllipsoidWithMass(2.0, *a),
        "cylinder": lambda: SpatialInertia.SolidCylinderWithMass(2.0, a[0], 2 * a[1], np.array([0, 0, 1.0])),
        "capsule": lambda: SpatialInertia.SolidCapsuleWithMass(2.0, a[0], 2 * a[1], np.array([0, 0, 1.0])),
        "box": lambda: SpatialInertia.SolidBoxWithMass(2.0, *(2 * a)),
    }[obj.kind]()
    mass, com, inertia = obj.mass_properties(mass=2.0)
    assert mass == 2.0 and np.allclose(com, 0.0)
    np.testing.assert_allclose(
        inertia, drake.CalcRotationalInertia().CopyToFullMatrix3(), rtol=1e-12, atol=1e-15
    )
    assert obj.mass_properties(density=1000.0)[0] == pytest.approx(1000.0 * obj.volume)
    # the volume against the fraction of random points in its bounds that are inside
    rng = np.random.default_rng(5)
    h = obj.half_extents()
    points = rng.uniform(-h, h, size=(200_000, 3))
    inside = np.mean(obj.signed_distances(points)[0] < 0.0)
    assert inside * np.prod(2 * h) == pytest.approx(obj.volume, rel=0.01)


def test_mass_properties_turn_with_the_object():
    upright, turned = Box([0.02, 0.04, 0.08]), every_kind()[-1]
    _, _, inertia = Box([0.02, 0.04, 0.08], PLACEMENT).mass_properties(mass=1.0)
    R = PLACEMENT.rotation
    np.testing.assert_allclose(inertia, R @ upright.mass_properties(mass=1.0)[2] @ R.T, atol=1e-15)
    with pytest.raises(ValidationError):
        turned.mass_properties()


@pytest.mark.parametrize("obj", every_kind(), ids=lambda o: o.kind)
def test_the_json_form_reads_back(obj: SurfaceObject):
    data = obj.to_dict()
    assert data["shape"] == obj.kind and set(obj.size_fields) <= set(data)
    back = object_from_dict(data)
    assert type(back) is type(obj)
    np.testing.assert_allclose(back.half_sizes, obj.half_sizes)
    np.testing.assert_allclose(back.centre, obj.centre)
    if obj.kind != "sphere":
        np.testing.assert_allclose(back.rotation, obj.rotation, atol=1e-12)
    assert make(obj.kind, obj.sizes(), obj.centre.tolist()).kind == obj.kind


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"radius": 0.03}, "object.shape"),
        ({"shape": "cone", "radius": 0.03}, "object.shape"),
        ({"shape": "sphere"}, "object.radius"),
        ({"shape": "sphere", "radius": -1.0}, "object.radius"),
        ({"shape": "sphere", "radius": 0.03, "size": [1, 1, 1]}, "object.size"),
        ({"shape": "box", "size": [0.1, 0.1]}, "object.size"),
        ({"shape": "box", "size": [0.1, 0.0, 0.1]}, "object.size[1]"),
        ({"shape": "cylinder", "radius": 0.02}, "object.length"),
        ({"shape": "capsule", "radius": 0.02, "length": True}, "object.length"),
        ({"shape": "ellipsoid", "radii": [0.1, 0.1, 0.1], "position": [0.0, 1.0]}, "object.position"),
        ({"shape": "ellipsoid", "radii": [0.1, 0.1, 0.1], "rpy": [0.0, math.nan, 0.0]}, "object.rpy"),
    ],
)
def test_a_bad_json_form_names_the_field(data, field):
    with pytest.raises(ValidationError) as exc:
        object_from_dict(data)
    assert exc.value.field == field


def test_size_errors_are_object_size_errors():
    with pytest.raises(ObjectSizeError):
        object_from_dict({"shape": "sphere", "radius": 0.0})


def test_the_ellipsoid_s_gradient_on_its_surface_is_its_outward_normal():
    radii = np.array([0.025, 0.03, 0.04])
    u = np.random.default_rng(2).normal(size=(50, 3))
    S = u / np.linalg.norm(u / radii, axis=1, keepdims=True)  # Σ (s_i / a_i)² = 1
    P = np.concatenate([S, 1.5 * S])  # on the surface, and off it (the gradient along p − s there)
    d, g = Ellipsoid.local_distance(P[None], radii[None, None])
    n = S / radii**2
    np.testing.assert_allclose(g[0, :50], n / np.linalg.norm(n, axis=1, keepdims=True), atol=1e-9)
    np.testing.assert_allclose(d[0, :50], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(g[0, 50:], axis=1), 1.0, atol=1e-12)
    assert np.all(d[0, 50:] > 0.0)
