"""Re-locating a known object: its pose refitted to fresh touches, its shape kept.

An object the hand pushed while it explored it is no longer where its postulate says. Its class
and size are still right; only its pose changed. Given fresh touches — fingertip centres ``c_i``
(tip radius ``r_i``) and sensed outward normals ``n_i`` — the new pose is the rigid motion
(translation ``t``, rotation vector ``w`` about the object's centre) of the postulated object
that minimises, by nonlinear least squares (scipy's ``least_squares``, trust region):

- each touch's signed-distance residual ``(d(c_i) − r_i) / σ_d`` (the tip centre one radius
  off the surface; σ_d: the tactile noise, at least :data:`MIN_DISTANCE_SIGMA`);
- each touch's normal residual ``(∇d(c_i) − n_i) / σ_n`` (:data:`NORMAL_SIGMA`);
- with a support (a table), the object's lowest point on it: ``(z_low − h) / σ_s``
  (:data:`SUPPORT_SIGMA`): a pushed object still rests on its table.

The fit starts from the postulated pose and, in case the object toppled, from it turned a
quarter turn about each horizontal axis; the lowest cost wins (the unturned start unless a
turned one explains the touches at least :data:`TOPPLE_GAIN` times better).

SI units: metres, radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares

from eos_svc.grasp.postulate import make_object
from eos_svc.objects import SurfaceObject
from eos_svc.schema.request import ObjectSpec

#: the least standard deviation of a touch's distance residual, m
MIN_DISTANCE_SIGMA = 5e-4
#: standard deviation of a sensed normal (per component)
NORMAL_SIGMA = 0.2
#: standard deviation of the object's lowest point about its support, m
SUPPORT_SIGMA = 1e-3
#: a turned start wins only when its cost is this many times lower than the unturned start's
TOPPLE_GAIN = 4.0
#: rotation vectors of the starts (rad): unturned, then a quarter turn about ±x and ±y
STARTS = (
    (0.0, 0.0, 0.0),
    (0.5 * np.pi, 0.0, 0.0),
    (-0.5 * np.pi, 0.0, 0.0),
    (0.0, 0.5 * np.pi, 0.0),
    (0.0, -0.5 * np.pi, 0.0),
)


@dataclass(frozen=True)
class Relocation:
    """A refitted pose.

    Attributes:
        spec: the object at its new pose (shape and size kept).
        shift: the move of its centre (world, m).
        turn: the angle it turned by, rad.
        rms: the touches' distance residual after the fit (root mean square, m).
    """

    spec: ObjectSpec
    shift: np.ndarray
    turn: float
    rms: float


def touch_misses(obj: SurfaceObject, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """How far each fingertip centre is from lying one tip radius off ``obj``'s surface (m,
    signed: positive outside)."""
    distances, _ = obj.signed_distances(np.asarray(centres, dtype=float).reshape(-1, 3))
    return np.asarray(distances - np.asarray(radii, dtype=float))


def moved_spec(spec: ObjectSpec, shift: np.ndarray, rotation: np.ndarray) -> ObjectSpec:
    """``spec`` turned by ``rotation`` about its position, then moved by ``shift`` (m)."""
    turned = rotation @ pin.rpy.rpyToMatrix(*spec.rpy)
    position = tuple(float(v) for v in np.asarray(spec.position) + shift)
    rpy = tuple(float(v) for v in pin.rpy.matrixToRpy(turned))
    return ObjectSpec(spec.shape, dict(spec.size), position, rpy)  # type: ignore[arg-type]


def refit_pose(
    spec: ObjectSpec,
    centres: np.ndarray,
    normals: np.ndarray,
    radii: np.ndarray,
    support_height: float | None,
    noise: float,
) -> Relocation:
    """The pose of ``spec``'s object that best explains the touches (see the module docstring).

    Args:
        spec: the postulated object (its shape, size and the pose it was believed at).
        centres, normals: the touches' fingertip centres and sensed outward normals (N, 3).
        radii: the fingertip radii (N,), m.
        support_height: the height of the surface it rests on (m), None without one.
        noise: the tactile noise (standard deviation, m).
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    normals = np.asarray(normals, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    obj = make_object(spec)
    start = pin.SE3(obj.placement)
    sigma_d = max(float(noise), MIN_DISTANCE_SIGMA)

    def place(x: np.ndarray) -> None:
        turn = pin.exp3(x[3:])
        obj.placement = pin.SE3(turn @ start.rotation, start.translation + x[:3])

    def residuals(x: np.ndarray) -> np.ndarray:
        place(x)
        distances, gradients = obj.signed_distances(centres)
        parts = [(distances - radii) / sigma_d, ((gradients - normals) / NORMAL_SIGMA).ravel()]
        if support_height is not None:
            low = float(obj.centre[2]) - obj.depth_below_centre()
            parts.append(np.array([(low - support_height) / SUPPORT_SIGMA]))
        return np.concatenate(parts)

    best: tuple[float, np.ndarray] | None = None
    for k, w in enumerate(STARTS):
        x0 = np.concatenate([np.zeros(3), np.asarray(w, dtype=float)])
        fit = least_squares(residuals, x0, method="trf", x_scale=[0.01, 0.01, 0.01, 0.3, 0.3, 0.3])
        cost = float(fit.cost) * (TOPPLE_GAIN if k > 0 else 1.0)
        if best is None or cost < best[0]:
            best = (cost, np.asarray(fit.x))
    assert best is not None
    x = best[1]
    place(x)
    rms = float(np.sqrt(np.mean(touch_misses(obj, centres, radii) ** 2)))
    return Relocation(
        moved_spec(spec, x[:3], pin.exp3(x[3:])), x[:3].copy(), float(np.linalg.norm(x[3:])), rms
    )
