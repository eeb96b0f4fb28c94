"""Synthetic touches on known primitives (the kinematics objects' closed forms)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from eos_svc.objects import Box, Capsule, Cylinder, Ellipsoid, Sphere, SurfaceObject
from eos_svc.shape import Touches

TIP = 0.01


def placement(rpy=(0.3, 0.2, 0.5), position=(0.2, 0.0, 0.0)) -> pin.SE3:
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.asarray(position, dtype=float))


def objects(rpy=(0.3, 0.2, 0.5)) -> dict[str, SurfaceObject]:
    pl = placement(rpy)
    return {
        "sphere": Sphere(0.03, pl),
        "ellipsoid": Ellipsoid([0.035, 0.03, 0.022], pl),
        "cylinder": Cylinder(0.02, 0.08, pl),
        "capsule": Capsule(0.02, 0.06, pl),
        "box": Box([0.05, 0.06, 0.04], pl),
    }


def touches_on(
    obj: SurfaceObject,
    rng: np.random.Generator,
    n: int = 18,
    noise: float = 2e-4,
    keep=lambda d: d[0] > -0.6,
    gap_tolerance: float = 1e-4,
) -> Touches:
    """``n`` guarded probes: a fingertip (radius TIP) moving along a random direction ``d``
    that ``keep`` accepts (default: not toward −x, i.e. not from behind the object), on a
    line offset at random from the object's centre, stops at first touch (sphere tracing on
    the closed-form signed distance); its centre then sits r + a uniform gap in [0, tolerance]
    off the surface, and the sensed normal carries the tactile noise. Probes that miss are
    skipped."""
    centres, normals = [], []
    c0 = np.asarray(obj.placement.translation)
    half = 0.5 * float(obj.diameter)
    while len(centres) < n:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if not keep(d):
            continue
        lateral = rng.uniform(-0.7 * half, 0.7 * half, size=3)
        lateral -= (lateral @ d) * d
        p = c0 + lateral - 0.3 * d
        gap = TIP + rng.uniform(0.0, gap_tolerance)
        for _ in range(200):
            step = obj.signed_distance(p) - gap
            if step < 1e-9 or np.linalg.norm(p - c0) > 0.5:
                break
            p = p + step * d
        if abs(obj.signed_distance(p) - gap) > 1e-7:
            continue  # missed
        s = obj.closest_surface_point(p)
        nn = (p - s) / np.linalg.norm(p - s)  # the tip's normal, on edges and rims too
        centres.append(p)
        t = rng.normal(0.0, noise / TIP, size=3)
        t -= (t @ nn) * nn
        m = nn + t
        normals.append(m / np.linalg.norm(m))
    return Touches(
        np.array(centres), np.array(normals), TIP, tactile_noise=noise, contact_tolerance=gap_tolerance
    )


def with_free(touches: Touches, free: np.ndarray, free_radius: float) -> Touches:
    """``touches`` with the free tip samples ``free`` (radius ``free_radius``) added."""
    return Touches(
        touches.centres,
        touches.normals,
        touches.radii,
        np.vstack([touches.free, free]),
        np.concatenate([touches.free_radii, np.full(len(free), free_radius)]),
        touches.tactile_noise,
        touches.contact_tolerance,
        touches.kinematic_sigma,
    )
