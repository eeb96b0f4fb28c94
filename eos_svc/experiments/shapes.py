"""Every shape end to end: precision-grip and success (good grasp) rates per object class.

Spheres, ellipsoids, cylinders and capsules (lying across the approach) and boxes at
the default position, several sizes and seeds each, weights (0.5, 0.5).

    eos experiment shapes --seeds 5 --out results/shapes
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.experiments.common import (
    experiment_parser,
    pyplot,
    run_plans,
    save_figure,
    write_csv,
    write_json,
)

ACROSS = (math.pi / 2, 0.0, 0.0)  # cylinder/capsule axis along y: across the approach (x)

#: (label, shape, size fields, rpy) — two sizes per class
OBJECTS: tuple[tuple[str, str, dict[str, Any], tuple[float, float, float]], ...] = (
    ("sphere r20", "sphere", {"radius": 0.02}, (0.0, 0.0, 0.0)),
    ("sphere r35", "sphere", {"radius": 0.035}, (0.0, 0.0, 0.0)),
    ("ellipsoid 35/30/25", "ellipsoid", {"radii": (0.035, 0.03, 0.025)}, (0.0, 0.0, 0.0)),
    ("ellipsoid 25/30/40", "ellipsoid", {"radii": (0.025, 0.03, 0.04)}, (0.0, 0.0, 0.0)),
    ("cylinder r20 l80", "cylinder", {"radius": 0.02, "length": 0.08}, ACROSS),
    ("cylinder r30 l60", "cylinder", {"radius": 0.03, "length": 0.06}, ACROSS),
    ("capsule r20 l60", "capsule", {"radius": 0.02, "length": 0.06}, ACROSS),
    ("capsule r28 l40", "capsule", {"radius": 0.028, "length": 0.04}, ACROSS),
    ("box 50x60x40", "box", {"size": (0.05, 0.06, 0.04)}, (0.0, 0.0, 0.0)),
    ("box 40x40x70", "box", {"size": (0.04, 0.04, 0.07)}, (0.0, 0.0, 0.0)),
)


def run(seeds: int = 5, out: Path = Path("results/shapes"), quiet: bool = False) -> dict:
    """Plan every object over ``seeds`` seeds; write shapes.json, shapes.csv, shapes.png."""
    rows = []
    position = ObjectSpec().position
    for label, shape, size, rpy in OBJECTS:
        spec = ObjectSpec(shape, size, position, rpy)
        results = run_plans([PlanRequest(obj=spec, seed=s) for s in range(1, seeds + 1)], label, quiet)
        classes = [r.shape["class"] if r.shape else "none" for r in results]
        rows.append(
            {
                "object": label,
                "shape": shape,
                "runs": len(results),
                "grip_rate": float(np.mean([r.precision_grip for r in results])),
                # success = the end agent judged the grasp good
                "success_rate": float(np.mean([r.status == "success" for r in results])),
                "postulated": max(set(classes), key=classes.count),
                "mean_cycles": float(np.mean([r.cycles for r in results])),
                "statuses": ",".join(sorted({r.status for r in results})),
            }
        )
    data = {"seeds": seeds, "rows": rows}
    write_json(out / "shapes.json", data)
    write_csv(out / "shapes.csv", rows)
    plot(rows, out / "shapes.png")
    return data


def plot(rows: list[dict], path: Path) -> Path:
    """Precision-grip and success (good grasp) rates per object (horizontal bars)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.2), dpi=120)
    y = np.arange(len(rows))
    ax.barh(y - 0.2, [r["grip_rate"] for r in rows], height=0.4, label="precision grip (all tips touch)")
    ax.barh(y + 0.2, [r["success_rate"] for r in rows], height=0.4, label="success (good grasp)")
    ax.set_yticks(y, [r["object"] for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1.05)
    ax.set_xlabel("rate over seeds")
    ax.set_title("Every shape end to end")
    ax.legend(fontsize=8, loc="lower right")
    return save_figure(fig, path)


def report(data: dict) -> str:
    """Human-readable table."""
    lines = ["  object               postulated  grip   success  cycles  statuses"]
    for r in data["rows"]:
        lines.append(
            f"  {r['object']:<20} {r['postulated']:<10}  {r['grip_rate']:5.0%}"
            f"  {r['success_rate']:6.0%}  {r['mean_cycles']:6.1f}  {r['statuses']}"
        )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of this experiment."""
    parser = experiment_parser("shapes", __doc__, "results/shapes")
    parser.add_argument("--seeds", type=int, default=5, help="seeds per object (5)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment shapes [options]``."""
    args = build_parser().parse_args(argv)
    data = run(args.seeds, args.out)
    print(report(data))
    print(f"wrote {args.out}/shapes.json, shapes.csv, shapes.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
