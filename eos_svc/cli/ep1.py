"""``eos ep1``: run EP1 alone — roll a fingertip on an object and estimate its curvature."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from eos_svc.cli.common import fraction, int_at_least, non_negative_float, positive_float

SHAPES = ("sphere", "plane", "cylinder", "ellipsoid")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``eos ep1``."""
    parser.add_argument("--shape", choices=SHAPES, default="sphere", help=f"object: {', '.join(SHAPES)}")
    parser.add_argument(
        "--radius",
        type=positive_float,
        default=0.04,
        help="sphere/cylinder radius, ellipsoid's largest semi-axis, m (default 0.04; ignored for a plane)",
    )
    parser.add_argument("--noise", type=non_negative_float, default=2e-4, help="tactile noise, m")
    parser.add_argument("--seed", type=int_at_least(0), default=0, help="tactile noise seed")
    parser.add_argument("--finger", default="finger1", help="rolling finger (default finger1)")
    parser.add_argument("--omega", type=positive_float, default=0.5, help="rolling rate, rad/s")
    parser.add_argument("--dt", type=positive_float, default=0.01, help="time step, s")
    parser.add_argument(
        "--steps", type=int_at_least(8), default=100, help="steps per direction's sweep (default 100)"
    )
    parser.add_argument("--solver", default="osqp", help="QP backend (osqp default, or daqp, ...)")
    parser.add_argument(
        "--until-rating",
        type=fraction,
        default=0.95,
        help="repeat EP1 until its rating (1 - sigma_R/R) reaches this (default 0.95)",
    )
    parser.add_argument("--max-runs", type=int_at_least(1), default=30, help="most EP1 repetitions")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def _f(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _radius(k: float) -> float:
    return math.inf if abs(k) < 1e-9 else 1.0 / k


def run(args: argparse.Namespace) -> int:
    """Run EP1 with the parsed options; 0 on success, 2 on bad input, 1 on a failed run."""
    import numpy as np
    import qpsolvers

    from eos_svc.kinematics.ep1 import (
        EP1Error,
        ep1_scene,
        ground_truth_form,
        place_hand_for_ep1,
        repeat_ep1,
    )
    from eos_svc.kinematics.hand import KinematicsError
    from eos_svc.kinematics.rolling import RollingQPError
    from eos_svc.kinematics.tactile import TactileSensor

    def fail(field: str, reason: str, code: int = 2) -> int:
        if args.json:
            print(json.dumps({"error": {"field": field, "reason": reason}}))
        print(f"eos ep1: error: {field}: {reason}", file=sys.stderr)
        return code

    if args.solver != "osqp" and args.solver not in qpsolvers.available_solvers:
        return fail(
            "--solver", f"unknown QP solver {args.solver!r}; available: {qpsolvers.available_solvers}"
        )
    try:
        scene = ep1_scene(args.shape, args.radius, finger=args.finger)
    except KinematicsError as exc:
        field = "--finger" if exc.field == "finger" else f"--{exc.field}"
        return fail(field, exc.reason)
    try:
        q0 = place_hand_for_ep1(scene, args.finger)
        state = scene.hand.state(q0)
        res, runs, steps = repeat_ep1(
            scene,
            state,
            args.finger,
            TactileSensor(args.noise, rng=args.seed),
            target_rating=args.until_rating,
            max_runs=args.max_runs,
            omega=args.omega,
            steps_per_direction=args.steps,
            dt=args.dt,
            solver=args.solver,
        )
    except (EP1Error, RollingQPError, KinematicsError) as exc:
        return fail(getattr(exc, "field", "ep1"), str(getattr(exc, "reason", exc)), 1)
    e = res.estimate
    K = ground_truth_form(scene.object, res.contact_point, res.frame)
    kt = np.linalg.eigvalsh(K)[::-1]
    Ht = 0.5 * float(kt[0] + kt[1])
    radius_err = abs(Ht / e.mean_curvature - 1.0) if Ht != 0 and e.mean_curvature != 0 else None
    out: dict[str, Any] = {
        "shape": args.shape,
        "size": args.radius if args.shape != "plane" else None,
        "finger": args.finger,
        "noise_std": args.noise,
        "seed": args.seed,
        "estimate": e.to_dict(),
        "ground_truth": {
            "principal_curvatures": [float(k) for k in kt],
            "radii": [_f(_radius(float(k))) for k in kt],
            "mean_radius": _f(_radius(Ht)),
        },
        "radius_error": radius_err,
        "runs": runs,
        "steps": steps,
        "samples": e.n_samples,
        "max_slip_speed": res.max_slip_speed,
        "max_gap": res.max_gap,
    }
    if args.json:
        print(json.dumps(out))
        return 0

    def r_txt(r: float) -> str:
        return "flat (inf)" if not math.isfinite(r) else f"{100 * r:.3f} cm"

    k1, k2 = e.principal_curvatures
    s1, s2 = e.sigma_curvatures
    size = "" if args.shape == "plane" else f" {args.radius:g} m"
    print(f"EP1 on {args.shape}{size} with {args.finger} (noise {args.noise:g} m, seed {args.seed})")
    print(f"  estimate     k1 = {k1:9.3f} ± {s1:.3f} 1/m   k2 = {k2:9.3f} ± {s2:.3f} 1/m")
    print(
        f"               radii {r_txt(e.radii[0])}, {r_txt(e.radii[1])};  mean radius {r_txt(e.mean_radius)}"
    )
    print(f"  uncertainty  sigma_R/R = {e.relative_error:.4f}   rating = {e.rating:.3f}")
    print(
        f"  ground truth k1 = {kt[0]:9.3f} 1/m          k2 = {kt[1]:9.3f} 1/m   "
        f"mean radius {r_txt(_radius(Ht))}"
    )
    if radius_err is not None:
        print(f"  radius error {100 * radius_err:.3f} %")
    print(
        f"  runs {runs}, steps {steps}, samples {e.n_samples}; max slip {res.max_slip_speed:.1e} m/s, "
        f"max gap {res.max_gap:.1e} m"
    )
    return 0
