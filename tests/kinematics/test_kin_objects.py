"""Objects: surface membership, normals and curvatures against independent implicit surfaces
differentiated numerically; closest points; size validation; undefined curvature on edges."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.objects import (
    Box,
    Capsule,
    CurvatureUndefinedError,
    Cylinder,
    Ellipsoid,
    ObjectSizeError,
    Sphere,
    SurfaceObject,
)

Implicit = Callable[[np.ndarray], float]


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _placement(rng: np.random.Generator) -> pin.SE3:
    return pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.1)


# Each case: (object factory, sampler of local surface points with its own implicit function).
def _sphere(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    R = 0.03
    return Sphere(R, _placement(rng)), R * _unit(rng), lambda p: float(np.linalg.norm(p) - R)


def _ellipsoid(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    a = np.array([0.05, 0.03, 0.02])
    obj = Ellipsoid(a, _placement(rng))
    return obj, a * _unit(rng), lambda p: float(np.sum((p / a) ** 2) - 1.0)


def _cylinder_side(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    r, length = 0.025, 0.08
    th = rng.uniform(0, 2 * np.pi)
    s = np.array([r * np.cos(th), r * np.sin(th), rng.uniform(-0.3, 0.3) * length])
    return Cylinder(r, length, _placement(rng)), s, lambda p: float(np.hypot(p[0], p[1]) - r)


def _cylinder_cap(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    r, length = 0.025, 0.08
    th, rho, sg = rng.uniform(0, 2 * np.pi), rng.uniform(0, 0.7) * r, rng.choice([-1.0, 1.0])
    s = np.array([rho * np.cos(th), rho * np.sin(th), sg * length / 2])
    return Cylinder(r, length, _placement(rng)), s, lambda p: float(abs(p[2]) - length / 2)


def _capsule_side(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    r, length = 0.02, 0.06
    th = rng.uniform(0, 2 * np.pi)
    s = np.array([r * np.cos(th), r * np.sin(th), rng.uniform(-0.3, 0.3) * length])
    return Capsule(r, length, _placement(rng)), s, lambda p: float(np.hypot(p[0], p[1]) - r)


def _capsule_cap(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    r, length = 0.02, 0.06
    u = _unit(rng)
    u[2] = abs(u[2]) + 0.3
    u /= np.linalg.norm(u)
    c = np.array([0.0, 0.0, length / 2])
    return Capsule(r, length, _placement(rng)), c + r * u, lambda p: float(np.linalg.norm(p - c) - r)


def _box_face(rng: np.random.Generator) -> tuple[SurfaceObject, np.ndarray, Implicit]:
    size = np.array([0.04, 0.06, 0.08])
    h = size / 2
    i = int(rng.integers(3))
    s = rng.uniform(-0.7, 0.7, size=3) * h
    s[i] = rng.choice([-1.0, 1.0]) * h[i]
    return Box(size, _placement(rng)), s, lambda p: float(abs(p[i]) - h[i])


CASES = {
    "sphere": _sphere,
    "ellipsoid": _ellipsoid,
    "cylinder_side": _cylinder_side,
    "cylinder_cap": _cylinder_cap,
    "capsule_side": _capsule_side,
    "capsule_cap": _capsule_cap,
    "box_face": _box_face,
}


def _height(g: Implicit, s: np.ndarray, n: np.ndarray, t: np.ndarray, span: float) -> float:
    """λ with g(s + t + λ n) = 0 by bisection (g < 0 inside)."""
    lo, hi = -span, span
    assert g(s + t + lo * n) < 0 < g(s + t + hi * n)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if g(s + t + mid * n) < 0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _numeric_form(
    g: Implicit,
    s: np.ndarray,
    n: np.ndarray,
    e1: np.ndarray,
    e2: np.ndarray,
    hs: float = 3e-4,
    span: float = 0.01,
) -> np.ndarray:
    """-Hessian of the surface height over the tangent plane (central differences)."""

    def f(a: float, b: float) -> float:
        return _height(g, s, n, a * e1 + b * e2, span)

    f0 = f(0, 0)
    faa = (f(hs, 0) - 2 * f0 + f(-hs, 0)) / hs**2
    fbb = (f(0, hs) - 2 * f0 + f(0, -hs)) / hs**2
    fab = (f(hs, hs) - f(hs, -hs) - f(-hs, hs) + f(-hs, -hs)) / (4 * hs**2)
    return -np.array([[faa, fab], [fab, fbb]])


@pytest.mark.parametrize("case", list(CASES))
def test_normal_and_curvature_against_numerical_surface(case: str) -> None:
    rng = np.random.default_rng(11)
    for _ in range(5):
        obj, s_local, g = CASES[case](rng)
        M = obj.placement
        p = M.act(s_local)
        # on the surface, and projection is the identity there
        assert abs(g(s_local)) < 1e-12
        assert np.allclose(obj.closest_surface_point(p), p, atol=1e-10)
        assert abs(obj.signed_distance(p)) < 1e-10
        # normal = normalised gradient of the independent implicit function
        eps = 1e-7
        grad = np.array([(g(s_local + eps * e) - g(s_local - eps * e)) / (2 * eps) for e in np.eye(3)])
        n_local = grad / np.linalg.norm(grad)
        n = obj.surface_normal(p)
        assert np.allclose(n, M.rotation @ n_local, atol=1e-6)
        # second fundamental form = -Hessian of the height over the tangent plane
        k1, k2, d1, d2 = obj.principal_curvatures(p)
        assert k1 >= k2 >= -1e-12
        for d in (d1, d2):
            assert abs(d @ n) < 1e-9 and abs(np.linalg.norm(d) - 1) < 1e-9
        assert abs(d1 @ d2) < 1e-9
        e1, e2 = M.rotation.T @ d1, M.rotation.T @ d2
        II_num = _numeric_form(g, s_local, n_local, e1, e2)
        assert np.allclose(II_num, np.diag([k1, k2]), rtol=1e-3, atol=1e-2)
        II = obj.curvature_form(p, d1, d2)
        assert np.allclose(II, np.diag([k1, k2]), atol=1e-9)
        # an arbitrary tangent basis gives the rotated form
        c, sn = np.cos(0.7), np.sin(0.7)
        Rb = np.array([[c, -sn], [sn, c]])
        II_rot = obj.curvature_form(p, c * d1 + sn * d2, -sn * d1 + c * d2)
        assert np.allclose(II_rot, Rb.T @ np.diag([k1, k2]) @ Rb, atol=1e-9)


@pytest.mark.parametrize(
    ("obj", "expected"),
    [
        (Sphere(0.03), (1 / 0.03, 1 / 0.03)),
        (Cylinder(0.02, 0.1), (1 / 0.02, 0.0)),
        (Capsule(0.02, 0.1), (1 / 0.02, 0.0)),
        (Box([0.1, 0.1, 0.1]), (0.0, 0.0)),
    ],
)
def test_closed_form_curvatures(obj: SurfaceObject, expected: tuple[float, float]) -> None:
    k1, k2, _, _ = obj.principal_curvatures(np.array([1.0, 0.0, 0.0]))
    assert (k1, k2) == pytest.approx(expected)


def test_ellipsoid_vertex_curvatures() -> None:
    a, b, c = 0.05, 0.03, 0.02
    e = Ellipsoid([a, b, c])
    k1, k2, d1, _ = e.principal_curvatures(np.array([1.0, 0.0, 0.0]))  # vertex (a, 0, 0)
    assert (k1, k2) == pytest.approx((a / c**2, a / b**2))
    assert abs(d1[2]) == pytest.approx(1.0)
    k1, k2, _, _ = e.principal_curvatures(np.array([0.0, 0.0, -1.0]))  # vertex (0, 0, -c)
    assert (k1, k2) == pytest.approx((c / b**2, c / a**2))


def test_capsule_cap_curvature() -> None:
    k1, k2, _, _ = Capsule(0.02, 0.1).principal_curvatures(np.array([0.0, 0.0, 1.0]))
    assert (k1, k2) == pytest.approx((50.0, 50.0))


def test_ellipsoid_closest_point_optimality() -> None:
    rng = np.random.default_rng(5)
    e = Ellipsoid([0.05, 0.03, 0.02], _placement(rng))
    a = np.array([0.05, 0.03, 0.02])
    R, t = e.placement.rotation, e.placement.translation
    samples = (a * np.array([_unit(rng) for _ in range(4000)])) @ R.T + t
    for _ in range(20):
        p = e.placement.act(rng.normal(size=3) * 0.05)
        s = e.closest_surface_point(p)
        n = e.surface_normal(s)
        d = p - s
        if np.linalg.norm(d) > 1e-9:  # p - s is along the normal at s
            assert np.linalg.norm(np.cross(d / np.linalg.norm(d), n)) < 1e-6
        if e.signed_distance(p) > 0:
            assert np.linalg.norm(d) <= np.min(np.linalg.norm(samples - p, axis=1)) + 1e-9


def test_box_and_cylinder_edges_raise() -> None:
    box = Box([0.1, 0.2, 0.3])
    with pytest.raises(CurvatureUndefinedError):
        box.principal_curvatures(np.array([0.05, 0.1, 0.0]))
    with pytest.raises(CurvatureUndefinedError):
        box.surface_normal(np.array([1.0, 1.0, 1.0]))  # nearest point is a corner
    cyl = Cylinder(0.02, 0.1)
    with pytest.raises(CurvatureUndefinedError):
        cyl.principal_curvatures(np.array([0.02, 0.0, 0.05]))


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: Sphere(0.0), "radius"),
        (lambda: Sphere(float("nan")), "radius"),
        (lambda: Ellipsoid([0.1, 0.2]), "radii"),
        (lambda: Ellipsoid([0.1, -0.2, 0.1]), "radii[1]"),
        (lambda: Cylinder(0.1, float("inf")), "length"),
        (lambda: Capsule(-1.0, 0.1), "radius"),
        (lambda: Box([0.1, 0.1, 0.0]), "size[2]"),
        (lambda: Sphere("big"), "radius"),  # type: ignore[arg-type]
    ],
)
def test_bad_sizes(make: Callable[[], SurfaceObject], field: str) -> None:
    with pytest.raises(ObjectSizeError) as exc:
        make()
    assert exc.value.field == field
    assert isinstance(exc.value, ValueError)


def test_kinds_geometry_diameter() -> None:
    assert Sphere(0.03).diameter == pytest.approx(0.06)
    for obj, kind in [
        (Sphere(0.03), "sphere"),
        (Ellipsoid([0.01, 0.02, 0.03]), "ellipsoid"),
        (Cylinder(0.01, 0.02), "cylinder"),
        (Box([0.01, 0.02, 0.03]), "box"),
        (Capsule(0.01, 0.02), "capsule"),
    ]:
        assert obj.kind == kind
        assert obj.geometry is not None and obj.diameter > 0


@pytest.mark.parametrize(
    "p",
    [[0.02, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.001], [0.0, 0.0, 0.0], [0.01, 0.005, 0.002]],
)
def test_ellipsoid_closest_point_inside_and_degenerate(p: list[float]) -> None:
    """Interior points, including those on the axes (where the Lagrange root degenerates)."""
    a = np.array([0.05, 0.03, 0.02])
    e = Ellipsoid(a)
    s = e.closest_surface_point(np.array(p))
    assert np.sum((s / a) ** 2) == pytest.approx(1.0, abs=1e-12)
    rng = np.random.default_rng(2)
    u = rng.normal(size=(100_000, 3))
    samples = a * (u / np.linalg.norm(u, axis=1)[:, None])
    brute = np.min(np.linalg.norm(samples - np.array(p), axis=1))
    assert np.linalg.norm(s - p) <= brute + 1e-9
    assert e.signed_distance(np.array(p)) == pytest.approx(-np.linalg.norm(s - p))
