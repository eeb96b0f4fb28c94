"""EP1 accuracy: estimated curvatures against the analytic ground truth.

Noise-free on spheres, a plane, a cylinder and an ellipsoid; with tactile noise over seeds
(``docs/ep1.md``; ``eos experiment accuracy``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from eos_svc.cli.common import fraction, int_at_least, non_negative_float
from eos_svc.kinematics.ep1 import (
    ep1_scene,
    ground_truth_form,
    place_hand_for_ep1,
    repeat_ep1,
    run_ep1,
)
from eos_svc.kinematics.tactile import TactileSensor

__all__ = ["AccuracyRow", "NoisyRow", "main", "run", "run_noise_free", "run_noisy"]

SPHERES = (0.01, 0.02, 0.04, 0.08)
CASES: tuple[tuple[str, str, float], ...] = (
    *((f"sphere R={r * 100:g} cm", "sphere", r) for r in SPHERES),
    ("plane (box face)", "plane", 1.0),
    ("cylinder r=2 cm", "cylinder", 0.02),
    ("ellipsoid 4x3x2.4 cm", "ellipsoid", 0.04),
)


@dataclass(frozen=True)
class AccuracyRow:
    """One noise-free case: estimated and true principal curvatures (1/m) and errors."""

    case: str
    k_est: tuple[float, float]
    k_true: tuple[float, float]
    radius_error: float | None  # relative error of the mean radius (curved objects)
    curvature_error: float  # max |k_est − k_true| / max(|k_true|), or max |k_est| (1/m) if flat
    flat: bool
    steps: int
    max_slip: float
    max_gap: float
    ok: bool


@dataclass(frozen=True)
class NoisyRow:
    """One sphere with tactile noise: median over seeds of the radius error after repetition."""

    radius: float
    seeds: int
    median_radius_error: float
    max_radius_error: float
    median_runs: float
    median_steps: float
    median_rating: float
    ok: bool


def run_noise_free(**ep1_kwargs: Any) -> list[AccuracyRow]:
    """One noise-free EP1 per case."""
    rows = []
    for name, shape, size in CASES:
        sc = ep1_scene(shape, size)
        st = sc.hand.state(place_hand_for_ep1(sc, "finger1"))
        res = run_ep1(sc, st, "finger1", TactileSensor(0.0), **ep1_kwargs)
        e = res.estimate
        w = np.linalg.eigvalsh(ground_truth_form(sc.object, res.contact_point, res.frame))
        kt = (float(w[1]), float(w[0]))  # the true principal curvatures, largest first
        ke = e.principal_curvatures
        scale = max(abs(kt[0]), abs(kt[1]))
        if scale > 0:
            cerr = max(abs(ke[0] - kt[0]), abs(ke[1] - kt[1])) / scale
            Ht = 0.5 * (kt[0] + kt[1])
            rerr: float | None = abs(Ht / e.mean_curvature - 1.0)
        else:
            cerr = max(abs(ke[0]), abs(ke[1]))
            rerr = None
        # the goals: a sphere's radius within 0.5 %, a plane flat, the other curvatures within 2 %
        ok = {"sphere": rerr is not None and rerr <= 0.005, "plane": e.is_flat}.get(shape, cerr <= 0.02)
        rows.append(
            AccuracyRow(name, ke, kt, rerr, cerr, e.is_flat, res.steps, res.max_slip_speed, res.max_gap, ok)
        )
    return rows


def run_noisy(
    seeds: int = 8,
    noise_std: float = 2e-4,
    target_rating: float = 0.95,
    max_runs: int = 30,
    **ep1_kwargs: Any,
) -> list[NoisyRow]:
    """Spheres with tactile noise; EP1 repeated until ``target_rating``; medians over seeds."""
    rows = []
    for R in SPHERES:
        errs, runs, steps, ratings = [], [], [], []
        for seed in range(seeds):
            sc = ep1_scene("sphere", R)
            st = sc.hand.state(place_hand_for_ep1(sc, "finger1"))
            sensor = TactileSensor(noise_std, rng=seed)
            res, n, total = repeat_ep1(
                sc, st, "finger1", sensor, target_rating=target_rating, max_runs=max_runs, **ep1_kwargs
            )
            e = res.estimate
            errs.append(abs(1.0 / (R * e.mean_curvature) - 1.0) if e.mean_curvature else math.inf)
            runs.append(n)
            steps.append(total)
            ratings.append(e.rating)
        med = float(np.median(errs))
        n_runs, n_steps, rating = (float(np.median(values)) for values in (runs, steps, ratings))
        rows.append(NoisyRow(R, seeds, med, float(np.max(errs)), n_runs, n_steps, rating, med <= 0.05))
    return rows


def format_tables(clean: Sequence[AccuracyRow], noisy: Sequence[NoisyRow], noise_std: float = 2e-4) -> str:
    """The two Markdown tables."""
    out = [
        "Noise-free (one EP1: 4 directions x 200 steps, omega 0.5 rad/s, dt 10 ms)",
        "",
        "| case | k1 est | k2 est | k1 true | k2 true | radius err | curv. err | flat "
        "| max slip m/s | max gap m | ok |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in clean:
        rerr = "-" if r.radius_error is None else f"{100 * r.radius_error:.3f} %"
        curved = max(map(abs, r.k_true)) > 0
        cerr = f"{100 * r.curvature_error:.3f} %" if curved else f"{r.curvature_error:.3g} 1/m"
        out.append(
            f"| {r.case} | {r.k_est[0]:8.3f} | {r.k_est[1]:8.3f} | {r.k_true[0]:8.3f} | "
            f"{r.k_true[1]:8.3f} | {rerr} | {cerr} | {'yes' if r.flat else 'no'} | "
            f"{r.max_slip:.1e} | {r.max_gap:.1e} | {'PASS' if r.ok else 'FAIL'} |"
        )
    if noisy:
        out += [
            "",
            f"With tactile noise (sigma = {noise_std * 1000:g} mm), EP1 repeated until rating >= target; "
            f"{noisy[0].seeds} seeds per sphere",
            "",
            "| R | median radius err | max radius err | median EP1 runs | median steps "
            "| median rating | ok (<= 5 %) |",
            "|---|---|---|---|---|---|---|",
        ]
        for n in noisy:
            out.append(
                f"| {100 * n.radius:g} cm | {100 * n.median_radius_error:.2f} % | "
                f"{100 * n.max_radius_error:.2f} % | {n.median_runs:g} | {n.median_steps:g} | "
                f"{n.median_rating:.3f} | {'PASS' if n.ok else 'FAIL'} |"
            )
    return "\n".join(out)


def run(
    seeds: int = 8, noise_std: float = 2e-4, target_rating: float = 0.95, noisy: bool = True
) -> dict[str, object]:
    """Both experiments; a JSON-friendly dict with the rows and the formatted table."""
    t0 = time.perf_counter()
    clean = run_noise_free()
    nrows = run_noisy(seeds, noise_std, target_rating) if noisy else []
    return {
        "noise_free": [asdict(r) for r in clean],
        "noisy": [asdict(r) for r in nrows],
        "table": format_tables(clean, nrows, noise_std),
        "all_ok": all(r.ok for r in clean) and all(r.ok for r in nrows),
        "wall_time_s": time.perf_counter() - t0,
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Print the accuracy tables; exit code 0 when every goal is met, 1 otherwise."""
    p = argparse.ArgumentParser(prog="eos experiment accuracy", description=__doc__.split("\n")[0])
    p.add_argument("--seeds", type=int_at_least(1), default=8, help="seeds per sphere in the noisy part")
    p.add_argument("--noise", type=non_negative_float, default=2e-4, help="tactile noise sigma, m")
    p.add_argument(
        "--target-rating", type=fraction, default=0.95, help="EP1 repeated until its rating reaches it"
    )
    p.add_argument("--no-noise", action="store_true", help="only the noise-free table")
    p.add_argument("--json", action="store_true", help="print JSON")
    a = p.parse_args(argv)
    out = run(a.seeds, a.noise, a.target_rating, noisy=not a.no_noise)
    if a.json:
        print(json.dumps(out, default=float))
    else:
        print(out["table"])
        print(f"\nall goals met: {out['all_ok']}  ({out['wall_time_s']:.1f} s)")
    return 0 if out["all_ok"] else 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
