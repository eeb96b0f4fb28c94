"""Paper §4.2 / Figure 3: grasp-stage cycles against the object-diameter to hand-height ratio.

Spheres of d = ratio × h, many seeds each; a run counts when all three fingertips touch (as in the
paper), the good-grasp rate beside it (figures: ``docs/planner.md``).
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise
from pathlib import Path

import numpy as np

from eos_svc.agents.planner import ratio_sphere_request
from eos_svc.cli.common import int_at_least
from eos_svc.experiments import common

DEFAULT_RATIOS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95)


def run(
    ratios: tuple[float, ...] = DEFAULT_RATIOS,
    seeds: int = 10,
    out: Path = Path("results/ratio"),
    quiet: bool = False,
) -> dict:
    """Run the sweep; write ratio.json, ratio.csv, ratio_runs.csv and ratio.png into ``out``."""
    rows, runs = [], []
    for ratio in ratios:
        requests = [ratio_sphere_request(ratio, seed) for seed in range(1, seeds + 1)]
        results = common.run_plans(requests, f"d/h = {ratio:.2f}", quiet)
        # the paper's Fig. 3 counts every run whose three fingertips touch (good grasp or not)
        grasped = [r for r in results if r.precision_grip]
        cycles = [r.cycles_per_stage.get("grasping", 0) for r in grasped]
        for seed, r in enumerate(results, 1):
            runs.append(
                {
                    "ratio": ratio,
                    "seed": seed,
                    "status": r.status,
                    "precision_grip": r.precision_grip,
                    "grasp_cycles": r.cycles_per_stage.get("grasping", 0),
                    "good_grasp": r.good_grasp,
                    "estimated_d_over_h": r.d_over_h,
                }
            )
        rows.append(
            {
                "ratio": ratio,
                "runs": len(results),
                "grasped": len(grasped),
                "mean_grasp_cycles": float(np.mean(cycles)) if cycles else None,
                "std_grasp_cycles": float(np.std(cycles)) if cycles else None,
                "min_grasp_cycles": int(min(cycles)) if cycles else None,
                "max_grasp_cycles": int(max(cycles)) if cycles else None,
                "good_grasp_rate": float(np.mean([r.good_grasp for r in results])),
            }
        )
    valid = [(row["ratio"], row["mean_grasp_cycles"]) for row in rows if row["mean_grasp_cycles"] is not None]
    xs, ys = np.array(valid, dtype=float).reshape(-1, 2).T
    slope = float(np.polyfit(xs, ys, 1)[0]) if len(valid) >= 2 else None
    falling = all(b <= a for (_, a), (_, b) in pairwise(valid)) if valid else False
    data = {"seeds": seeds, "rows": rows, "slope_cycles_per_ratio": slope, "monotonically_falling": falling}
    common.write_json(out / "ratio.json", data)
    common.write_csv(out / "ratio.csv", rows)
    common.write_csv(out / "ratio_runs.csv", runs)
    plot(rows, runs, out / "ratio.png")
    return data


def plot(rows: list[dict], runs: list[dict], path: Path) -> Path:
    """Grasp cycles against d/h (paper Fig. 3): every run, means with ±1 σ."""
    fig, ax = common.pyplot().subplots(figsize=(6.4, 4.0), dpi=120)
    ok = [r for r in runs if r["precision_grip"]]
    ax.scatter(
        [r["ratio"] for r in ok], [r["grasp_cycles"] for r in ok], s=10, alpha=0.35, label="runs (grasped)"
    )
    good = [row for row in rows if row["mean_grasp_cycles"] is not None]
    ax.errorbar(
        [row["ratio"] for row in good],
        [row["mean_grasp_cycles"] for row in good],
        yerr=[row["std_grasp_cycles"] for row in good],
        fmt="o-",
        capsize=3,
        label="mean ± std",
    )
    ax.set(xlabel="object diameter / hand height  d/h", ylabel="grasp-stage cycles")
    ax.set_title("Grasp cycles fall as d/h rises (paper Fig. 3)")
    ax2 = ax.twinx()
    ax2.plot(
        [row["ratio"] for row in rows],
        [row["good_grasp_rate"] for row in rows],
        "s:",
        color="tab:green",
        label="good-grasp rate",
    )
    ax2.set(ylim=(-0.05, 1.05), ylabel="good-grasp rate (about the diameter, force closure)")
    handles = ax.get_legend_handles_labels()
    handles2 = ax2.get_legend_handles_labels()
    ax.legend(handles[0] + handles2[0], handles[1] + handles2[1], fontsize=8, loc="center left")
    return common.save_figure(fig, path)


def report(data: dict) -> str:
    """Human-readable table."""
    lines = ["  d/h  grasped  grasp cycles (mean ± std)  good-grasp rate"]
    for row in data["rows"]:
        m = row["mean_grasp_cycles"]
        cyc = "      -" if m is None else f"{m:7.1f} ± {row['std_grasp_cycles']:.1f}"
        grasped = f"{row['grasped']:>3}/{row['runs']:<3}"
        lines.append(f"  {row['ratio']:.2f}  {grasped}  {cyc:>24}  {row['good_grasp_rate']:.0%}")
    lines.append(
        f"slope {data['slope_cycles_per_ratio']:.1f} cycles per unit d/h; "
        f"falling monotonically: {data['monotonically_falling']}"
    )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment ratio [options]``."""
    parser = common.experiment_parser("ratio", __doc__, "results/ratio")
    parser.add_argument("--seeds", type=int_at_least(1), default=10, help="seeds per ratio (10)")
    parser.add_argument("--ratios", type=float, nargs="+", default=list(DEFAULT_RATIOS), help="d/h values")
    args = parser.parse_args(argv)
    data = run(tuple(args.ratios), args.seeds, args.out)
    print(report(data))
    print(f"wrote {args.out}/ratio.json, ratio.csv, ratio_runs.csv, ratio.png")
    return 0
