"""EP1, the exploratory procedure: roll one fingertip on the object and estimate its curvature
(:func:`run_ep1`: rolls about tangent axes with one :class:`~.rolling.RollingQP`, the tactile
readings fitted per radian, Montana's equation solved by :class:`~.curvature.CurvatureEstimator`;
the procedure: ``docs/ep1.md``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.linalg import lapack

from eos_svc.objects import Box, CurvatureUndefinedError, Cylinder, Ellipsoid, Sphere, SurfaceObject

from .curvature import CurvatureEstimate, CurvatureEstimator, CurvatureSample
from .geometry import tangent_basis
from .hand import HandModel, HandState, KinematicsError
from .rolling import RollingQP
from .scene import Scene
from .tactile import TactileSensor

__all__ = [
    "DEFAULT_DIRECTIONS",
    "EP1Error",
    "EP1Result",
    "contact_frame",
    "ep1_scene",
    "ground_truth_form",
    "place_hand_for_ep1",
    "repeat_ep1",
    "run_ep1",
]

#: Roll directions in the tangent plane, degrees from the frame's x axis.
DEFAULT_DIRECTIONS: tuple[float, ...] = (0.0, 90.0, 45.0, 135.0)

#: |gap| above which the fingertip does not count as touching at the start, m.
CONTACT_TOLERANCE = 1e-4


class EP1Error(KinematicsError):
    """EP1 cannot run (no contact at the start, bad parameters)."""


@dataclass(frozen=True)
class EP1Result:
    """Outcome of one EP1 run: the estimate (this run's samples and the estimator's earlier
    ones), the final q (the start, up to drift), the steps, this run's samples, the largest
    no-slip residual (m/s) and |gap| (m), the world contact frame (columns x, y, z) the form is
    in, the start's contact point (m) and object normal, and the configurations every
    ``path_every`` steps (empty unless asked)."""

    estimate: CurvatureEstimate
    q_final: np.ndarray
    steps: int
    samples: tuple[CurvatureSample, ...]
    max_slip_speed: float
    max_gap: float
    frame: np.ndarray
    contact_point: np.ndarray
    normal: np.ndarray
    path: tuple[np.ndarray, ...] = ()


def contact_frame(normal: np.ndarray) -> np.ndarray:
    """The EP1 contact frame (columns x, y, z) for the world object ``normal``: ``z = −normal``,
    ``x`` world z on the tangent plane (world y near vertical), ``y = z × x``."""
    z = -np.asarray(normal, dtype=float)
    z = z / np.linalg.norm(z)
    x, y = tangent_basis(z, prefer=2)
    return np.column_stack([x, y, z])


def ground_truth_form(obj: SurfaceObject, point: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """The object's analytic curvature form at ``point`` in the frame's ``(x, y)``, 1/m."""
    return obj.curvature_form(point, frame[:, 0], frame[:, 1])


def place_hand_for_ep1(
    scene: Scene,
    finger: str = "finger1",
    q: np.ndarray | None = None,
    point: np.ndarray | None = None,
    *,
    scratch: HandState | None = None,
) -> np.ndarray:
    """A configuration where ``finger``'s tip touches the object with zero gap: the wrist of ``q``
    (default neutral) translated so the tip centre sits at ``s + r_f n`` (``s`` the surface point
    closest to ``point``, default to the tip; ``n`` its normal, or the direction from ``s`` to
    ``point`` on an edge). ``scratch``: a state of the scene's hand to compute in (it is moved).
    Raises :class:`WorkspaceError` (the wrist leaves its workspace) or :class:`KinematicsError`."""
    hand = scene.hand
    if scratch is None:
        st = hand.state(q)
    elif scratch.hand is not hand:
        raise KinematicsError("scratch", "belongs to another hand model than the scene")
    else:
        st = scratch
        st.update(hand.neutral() if q is None else q)
    c = st.tip_position(finger).copy()
    obj = scene.object
    target = c if point is None else np.asarray(point, dtype=float)
    s = obj.closest_surface_point(target)
    try:
        n = obj.surface_normal(target)
    except CurvatureUndefinedError:
        # an edge or a corner: the tip touches it along the direction from the edge to the target
        away = target - s
        n = away / np.linalg.norm(away)
    if point is None and obj.signed_distance(c) < 0:
        n = -n if (c - s) @ n < 0 else n  # tip centre inside: still put the tip outside
    dp = s + hand.tip_radius(finger) * n - c
    q_new = st.move_wrist(dp)
    # polish: the closest point of the moved tip may differ slightly on curved surfaces
    for _ in range(3):
        st.update(q_new)
        ct = scene.contact(st, finger)
        if abs(ct.distance) < 1e-12:
            break
        q_new = st.move_wrist(-ct.distance * ct.normal)
    return q_new


def _log_chart(
    points: np.ndarray, b: np.ndarray, ex: np.ndarray, ey: np.ndarray, r: float, directions: np.ndarray | None
) -> np.ndarray:
    """Geodesic (log-map) coordinates on the tip sphere of radius ``r`` around the unit ``b``, in
    the tangent basis ex, ey at b, m (``directions``: the points normalised, when known)."""
    d = points / np.linalg.norm(points, axis=1)[:, None] if directions is None else directions
    cosang = d @ b
    v = d - np.outer(cosang, b)
    sin_ang = np.linalg.norm(v, axis=1)
    ang = np.arctan2(sin_ang, cosang)
    scale = np.where(sin_ang > 1e-15, r * ang / np.maximum(sin_ang, 1e-300), r)
    v = v * scale[:, None]
    return np.array((v @ ex, v @ ey)).T


def _chart_at_mean(
    P: np.ndarray, ex_tip: np.ndarray, r: float, directions: np.ndarray | None = None
) -> np.ndarray:
    """The tactile points ``P`` (tip frame, m) in the log chart at their mean direction b, with the
    frame's x (``ex_tip``, tip frame) projected on the tangent plane at b as the chart's first axis."""
    b = P.mean(axis=0)
    b /= np.linalg.norm(b)
    ex = ex_tip - (ex_tip @ b) * b
    ex /= np.linalg.norm(ex)
    return _log_chart(P, b, ex, pin.skew(b) @ ex, r, directions)  # b × ex (np.cross costs 15 times)


def _fit_slope(theta: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Slope at ϑ = 0 of c(ϑ) = c₀ + s ϑ + s₂ ϑ² by least squares (both coordinates), from the
    normal equations ``XᵀX p = Xᵀc`` (three unknowns, ϑ of order 0.1 rad: well conditioned)."""
    X = np.array((np.ones_like(theta), theta, theta * theta))  # Xᵀ
    _, p, info = lapack.dposv(X.dot(X.T), X.dot(c))
    if info != 0:
        raise EP1Error("state", "the roll's angles do not determine the fit (too few distinct ones)")
    out: np.ndarray = p[1]
    return out


def run_ep1(
    scene: Scene,
    state: HandState,
    finger: str,
    tactile_sensor: TactileSensor,
    *,
    omega: float = 0.5,
    steps_per_direction: int = 100,
    dt: float = 0.01,
    directions: Sequence[float] = DEFAULT_DIRECTIONS,
    solver: str = "osqp",
    estimator: CurvatureEstimator | None = None,
    path_every: int = 0,
) -> EP1Result:
    """Run EP1 from ``state`` (updated to the final q; ``finger``'s tip must touch the object)
    and estimate the curvature.

    ``omega``: rolling rate, rad/s; ``steps_per_direction``: steps of one direction's full sweep
    (``omega · dt · steps_per_direction`` rad about the start; each direction takes twice this);
    ``dt``: time step, s; ``directions``: degrees in the tangent plane (≥ 2 independent);
    ``solver``: QP backend (:class:`~.rolling.RollingQP`); ``estimator``: accumulate into it;
    ``path_every`` > 0: keep every that many steps' q in :attr:`EP1Result.path`. Raises
    :class:`EP1Error` (no contact, bad parameters) or :class:`RollingQPError`.
    """
    if not (math.isfinite(omega) and omega > 0):
        raise EP1Error("omega", f"must be a finite number > 0 rad/s, got {omega!r}")
    if not (isinstance(steps_per_direction, int) and steps_per_direction >= 8):
        raise EP1Error("steps_per_direction", f"must be an integer >= 8, got {steps_per_direction!r}")
    if not (math.isfinite(dt) and dt > 0):
        raise EP1Error("dt", f"must be a finite number > 0 s, got {dt!r}")
    dirs = [float(d) for d in directions]
    if len(dirs) < 2 or not all(math.isfinite(d) for d in dirs):
        raise EP1Error("directions", "need at least two finite directions (degrees)")
    hand: HandModel = scene.hand
    ct0 = scene.contact(state, finger)
    if abs(ct0.distance) > CONTACT_TOLERANCE:
        raise EP1Error(
            "state",
            f"{finger}'s tip is {ct0.distance:.3g} m from the object (tolerance "
            f"{CONTACT_TOLERANCE} m); bring it into contact first (place_hand_for_ep1)",
        )
    F = contact_frame(ct0.normal)
    r = hand.tip_radius(finger)
    R0 = state.tip_placement(finger).rotation
    K_f = np.eye(2) / r
    half = steps_per_direction // 2
    full = 2 * half
    legs = ((1.0, half, 0), (-1.0, full, 1), (1.0, half, 0))  # (sign, steps, reading set)
    est = estimator if estimator is not None else CurvatureEstimator()
    samples: list[CurvatureSample] = []
    slips: list[float] = []
    gaps: list[float] = [abs(ct0.distance)]
    ex_tip = R0.T @ F[:, 0]  # the frame's x in the tip frame
    in_plane = [np.array([math.cos(math.radians(d)), math.sin(math.radians(d))]) for d in dirs]
    rq: RollingQP | None = None
    steps = 0
    path: list[np.ndarray] = [state.q.copy()] if path_every > 0 else []
    q_start = state.q
    try:
        for phi_deg, a_xy in zip(dirs, in_plane, strict=True):
            axis = F[:, :2] @ a_xy
            points: list[np.ndarray] = []  # tactile points in contact (tip frame)
            rotations: list[np.ndarray] = []  # the tip's rotation at each of them
            set_of: list[int] = []  # 0: the outward half-legs, 1: the sweep back
            for sign, n_steps, k_set in legs:
                # the axis stays the one tangent at the start (fixed for the whole direction)
                if rq is None:
                    rq = RollingQP(
                        state, finger, axis, sign * omega, dt, solver, scene=scene, tactile=tactile_sensor,
                        project_axis=False,
                    )  # fmt: skip
                else:
                    rq.retarget(axis, sign * omega, project_axis=False)
                for _ in range(n_steps):
                    s = rq.step()
                    assert s.reading is not None
                    if s.reading.in_contact:
                        points.append(s.reading.point_tip)
                        rotations.append(s.tip_rotation)
                        set_of.append(k_set)
                    slips.append(s.slip_speed)
                    gaps.append(abs(s.contact.distance))
                    steps += 1
                    if path_every > 0 and steps % path_every == 0:
                        path.append(rq.q)
            P_all = np.array(points).reshape(-1, 3)
            R_all = np.array(rotations).reshape(-1, 3, 3)
            sets = np.array(set_of, dtype=int)
            # realized net roll angle of the tip about a (not the commanded ω·t)
            th_all = np.array([pin.log3(R) for R in np.matmul(R0.T, R_all)]) @ (R0.T @ axis)
            for k in (0, 1):
                P = P_all[sets == k]
                if len(P) < 5:
                    raise EP1Error("state", f"{finger} lost contact while rolling (direction {phi_deg}°)")
                s_fit = _fit_slope(th_all[sets == k], _chart_at_mean(P, ex_tip, r))
                samples.append(est.add_sample(a_xy, s_fit, K_f))
    except BaseException:  # the roller moved the state's kinematics: back to the start
        state.update(q_start)
        raise
    assert rq is not None
    state.update(rq.q)
    return EP1Result(
        estimate=est.estimate(),
        q_final=state.q,
        steps=steps,
        samples=tuple(samples),
        max_slip_speed=max(slips),
        max_gap=max(gaps),
        frame=F,
        contact_point=np.array(ct0.point_object, dtype=float),
        normal=np.array(ct0.normal, dtype=float),
        path=tuple(path),
    )


def repeat_ep1(
    scene: Scene,
    state: HandState,
    finger: str,
    tactile_sensor: TactileSensor,
    *,
    target_rating: float = 0.95,
    max_runs: int = 30,
    estimator: CurvatureEstimator | None = None,
    **kwargs: Any,
) -> tuple[EP1Result, int, int]:
    """Repeat EP1 in place, accumulating samples, until ``estimate.rating >= target_rating`` or
    ``max_runs`` runs: ``(last result, whose estimate covers all runs; runs; total steps)``."""
    if not (0.0 <= target_rating <= 1.0):
        raise EP1Error("target_rating", f"must be in [0, 1], got {target_rating!r}")
    if not (isinstance(max_runs, int) and max_runs >= 1):
        raise EP1Error("max_runs", f"must be an integer >= 1, got {max_runs!r}")
    est = estimator if estimator is not None else CurvatureEstimator()
    total = 0
    runs = 0
    while True:
        res = run_ep1(scene, state, finger, tactile_sensor, estimator=est, **kwargs)
        runs += 1
        total += res.steps
        if res.estimate.rating >= target_rating or runs >= max_runs:
            return res, runs, total


#: Shapes :func:`ep1_scene` builds.
SHAPES = ("sphere", "plane", "cylinder", "ellipsoid")


def ep1_scene(
    shape: str = "sphere",
    size: float = 0.04,
    *,
    hand: HandModel | None = None,
    finger: str = "finger1",
) -> Scene:
    """An object in front of ``finger``'s tip (hand at neutral) for EP1: a sphere of radius
    ``size``, a box's −x face (``plane``), a cylinder of radius ``size`` (axis world z) or an
    ellipsoid of semi-axes ``size · (1, 0.75, 0.6)`` turned so the touched point is off its axes."""
    from .hand import load_hand

    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise EP1Error("size", f"must be a finite number > 0 m, got {size!r}")
    h = hand if hand is not None else load_hand()
    c = h.state().tip_position(finger).copy()
    r = h.tip_radius(finger)
    gap = 0.005
    obj: SurfaceObject
    if shape == "sphere":
        obj = Sphere(size, pin.SE3(np.eye(3), c + np.array([r + gap + size, 0.0, 0.0])))
    elif shape == "plane":
        half = 0.025
        obj = Box((2 * half, 0.2, 0.2), pin.SE3(np.eye(3), c + np.array([r + gap + half, 0.0, 0.0])))
    elif shape == "cylinder":
        obj = Cylinder(size, 0.2, pin.SE3(np.eye(3), c + np.array([r + gap + size, 0.0, 0.0])))
    elif shape == "ellipsoid":
        radii = size * np.array([1.0, 0.75, 0.6])
        Rot = pin.rpy.rpyToMatrix(0.5, 0.4, 0.3)
        e = Ellipsoid(radii, pin.SE3(Rot, np.zeros(3)))
        # the surface point whose outward normal faces the fingertip (−x world)
        nl = Rot.T @ np.array([-1.0, 0.0, 0.0])
        s_local = radii**2 * nl / np.linalg.norm(radii * nl)
        s_world = Rot @ s_local
        e.placement = pin.SE3(Rot, c + np.array([r + gap, 0.0, 0.0]) - s_world)
        obj = e
    else:
        raise EP1Error("shape", f"unknown shape {shape!r}; choose from {', '.join(SHAPES)}")
    return Scene(h, obj)
