"""Every shape end to end: precision-grip and success (good grasp) rates per object class.

Every class in several sizes and poses, several seeds each; ``--oracle`` plans each again on the
true object instead of post_shape's postulate (the grasp stage alone). Figures: ``docs/planner.md``.

    eos experiment shapes --seeds 5 --out results/shapes
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.cli.common import int_at_least
from eos_svc.experiments import common

ACROSS = (math.pi / 2, 0.0, 0.0)  # cylinder/capsule axis along y: across the approach (x)

#: (label, shape, size fields, rpy) — two sizes per class, then other poses
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
    ("cylinder r20 l80 upright", "cylinder", {"radius": 0.02, "length": 0.08}, (0.0, 0.0, 0.0)),
    ("capsule r20 l60 along", "capsule", {"radius": 0.02, "length": 0.06}, (0.0, math.pi / 2, 0.0)),
    ("capsule r20 l60 angled", "capsule", {"radius": 0.02, "length": 0.06}, (0.5, 0.7, 0.3)),
    ("box 70x35x45 yaw 0.5", "box", {"size": (0.07, 0.035, 0.045)}, (0.0, 0.0, 0.5)),
)


def run(
    seeds: int = 5, out: Path = Path("results/shapes"), quiet: bool = False, oracle: bool = False
) -> dict:
    """Plan every object over ``seeds`` seeds (and, with ``oracle``, again on the true
    object); write shapes.json, shapes.csv, shapes.png."""
    rows = []
    position = ObjectSpec().position
    for label, shape, size, rpy in OBJECTS:
        spec = ObjectSpec(shape, size, position, rpy)
        requests = [PlanRequest(obj=spec, seed=s) for s in range(1, seeds + 1)]
        results = common.run_plans(requests, label, quiet)
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
        if oracle:
            truth = common.run_plans(requests, f"{label} (oracle postulate)", quiet, oracle_postulate=True)
            rows[-1]["oracle_success_rate"] = float(np.mean([r.status == "success" for r in truth]))
            rows[-1]["oracle_statuses"] = ",".join(sorted({r.status for r in truth}))
    data = {"seeds": seeds, "rows": rows}
    common.write_json(out / "shapes.json", data)
    common.write_csv(out / "shapes.csv", rows)
    plot(rows, out / "shapes.png")
    return data


def plot(rows: list[dict], path: Path) -> Path:
    """Precision-grip and success (good grasp) rates per object (horizontal bars)."""
    fig, ax = common.pyplot().subplots(figsize=(7.0, 6.0), dpi=120)
    y = np.arange(len(rows))
    bars = [("grip_rate", "precision grip (all tips touch)"), ("success_rate", "success (good grasp)")]
    if all("oracle_success_rate" in r for r in rows):
        bars.append(("oracle_success_rate", "success with the true object as postulate (grasp stage alone)"))
    height = 0.8 / len(bars)
    for i, (key, label) in enumerate(bars):
        offset = (i - 0.5 * (len(bars) - 1)) * height
        ax.barh(y + offset, [r[key] for r in rows], height=height, label=label)
    ax.set_yticks(y, [r["object"] for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set(xlim=(0, 1.05), xlabel="rate over seeds", title="Every shape end to end")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=1)
    return common.save_figure(fig, path)


def report(data: dict) -> str:
    """Human-readable table."""
    oracle = any("oracle_success_rate" in r for r in data["rows"])
    head = "  object                     postulated  grip   success  cycles  statuses"
    lines = [head + ("  |  oracle success  statuses" if oracle else "")]
    for r in data["rows"]:
        line = (
            f"  {r['object']:<26} {r['postulated']:<10}  {r['grip_rate']:5.0%}"
            f"  {r['success_rate']:6.0%}  {r['mean_cycles']:6.1f}  {r['statuses']}"
        )
        if oracle:
            line += f"  |  {r['oracle_success_rate']:6.0%}  {r['oracle_statuses']}"
        lines.append(line)
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment shapes [options]``."""
    parser = common.experiment_parser("shapes", __doc__, "results/shapes")
    parser.add_argument("--seeds", type=int_at_least(1), default=5, help="seeds per object (5)")
    parser.add_argument(
        "--oracle", action="store_true", help="also plan on the true object (grasp stage alone)"
    )
    args = parser.parse_args(argv)
    data = run(args.seeds, args.out, oracle=args.oracle)
    print(report(data))
    print(f"wrote {args.out}/shapes.json, shapes.csv, shapes.png")
    return 0
