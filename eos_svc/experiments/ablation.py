"""Paper §4.1: default vs opportunistic sub-ratings, by running the planner with those weights.

Weights (1, 0), (0, 1) and (0.5, 0.5) on seed 1 and over many seeds, and a sweep of the default
weight from 0 to 1 (figures: ``docs/planner.md``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import PlanRequest, PlanResult, plan
from eos_svc.cli.common import int_at_least
from eos_svc.experiments import common
from eos_svc.ratings import Weights

PAPER_WEIGHTS = ((1.0, 0.0), (0.0, 1.0), (0.5, 0.5))
ALL_STAGES = ("search", "information", "grasping")


def all_stages(result: PlanResult) -> bool:
    """The run completed search, information and grasping."""
    return tuple(result.stages_completed) == ALL_STAGES


def summarize(result: PlanResult) -> dict[str, Any]:
    """The facts of one run the paper talks about."""
    return {
        "status": result.status,
        "reason": result.reason,
        "stages_completed": list(result.stages_completed),
        "all_stages": all_stages(result),
        "cycles": result.cycles,
        "agents_run": result.agents_run(),
    }


def run(
    seeds: int = 20, sweep_points: int = 11, out: Path = Path("results/ablation"), quiet: bool = False
) -> dict:
    """Run the experiment; write ablation.json, ablation_sweep.csv and ablation.png into ``out``."""

    def over_seeds(wd: float, wo: float, label: str) -> list[PlanResult]:
        requests = [PlanRequest(weights=Weights(wd, wo), seed=s) for s in range(1, seeds + 1)]
        return common.run_plans(requests, label, quiet)

    one_seed = {
        f"{wd},{wo}": summarize(plan(PlanRequest(weights=Weights(wd, wo), seed=1), keep_trace=True))
        for wd, wo in PAPER_WEIGHTS
    }
    counts = {}
    for wd, wo in PAPER_WEIGHTS:
        results = over_seeds(wd, wo, f"weights ({wd}, {wo})")
        counts[f"{wd},{wo}"] = {
            "status": dict(Counter(r.status for r in results)),
            "stages_completed": dict(Counter(",".join(r.stages_completed) or "none" for r in results)),
            "all_stages_rate": float(np.mean([all_stages(r) for r in results])),
        }
    sweep = []
    for wd in np.linspace(0.0, 1.0, sweep_points):
        wd = round(float(wd), 6)
        results = over_seeds(wd, round(1.0 - wd, 6), f"sweep default weight {wd:.2f}")
        sweep.append(
            {
                "default_weight": wd,
                "completion_rate": float(np.mean([all_stages(r) for r in results])),
                # success = the end agent judged the grasp good (not merely all fingertips touching)
                "success_rate": float(np.mean([r.status == "success" for r in results])),
                "mean_cycles": float(np.mean([r.cycles for r in results])),
            }
        )
    data = {"seeds": seeds, "one_seed": one_seed, "counts": counts, "sweep": sweep}
    common.write_json(out / "ablation.json", data)
    common.write_csv(out / "ablation_sweep.csv", sweep)
    plot(sweep, out / "ablation.png")
    return data


def plot(sweep: list[dict], path: Path) -> Path:
    """Completion rate and mean cycles against the default weight."""
    fig, ax = common.pyplot().subplots(figsize=(6.4, 4.0), dpi=120)
    w = [row["default_weight"] for row in sweep]
    ax.plot(w, [row["completion_rate"] for row in sweep], "o-", label="all three stages completed")
    ax.plot(w, [row["success_rate"] for row in sweep], "s--", label="success (good grasp)")
    ax.set(xlabel="default weight P(B_d)  (opportunistic weight = 1 - P(B_d))", ylabel="rate over seeds")
    ax.set(ylim=(-0.05, 1.05), title="EOS ablation: default vs opportunistic sub-ratings")
    ax2 = ax.twinx()
    ax2.plot(w, [row["mean_cycles"] for row in sweep], "^:", color="gray", label="mean cycles")
    ax2.set_ylabel("mean cycles per run")
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [str(line.get_label()) for line in lines], loc="center right", fontsize=8)
    return common.save_figure(fig, path)


def report(data: dict) -> str:
    """Human-readable summary."""
    lines = ["one seed (1):"]
    for key, row in data["one_seed"].items():
        agents = " ".join(row["agents_run"][:8]) + (" ..." if len(row["agents_run"]) > 8 else "")
        lines.append(
            f"  weights ({key}): {row['status']:<9} stages {','.join(row['stages_completed']) or 'none'}; "
            f"{row['cycles']} cycles: {agents}"
        )
    lines.append(f"over {data['seeds']} seeds:")
    for key, row in data["counts"].items():
        lines.append(f"  weights ({key}): status {row['status']}, all stages {row['all_stages_rate']:.0%}")
    lines.append("sweep of the default weight:")
    for row in data["sweep"]:
        lines.append(
            f"  P(B_d)={row['default_weight']:.1f}: completion {row['completion_rate']:.0%}, "
            f"success (good grasp) {row['success_rate']:.0%}, mean cycles {row['mean_cycles']:.1f}"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment ablation [options]``."""
    parser = common.experiment_parser("ablation", __doc__, "results/ablation")
    parser.add_argument("--seeds", type=int_at_least(1), default=20, help="seeds per condition (20)")
    parser.add_argument("--sweep-points", type=int_at_least(1), default=11, help="weights in the sweep (11)")
    args = parser.parse_args(argv)
    data = run(args.seeds, args.sweep_points, args.out)
    print(report(data))
    print(f"wrote {args.out}/ablation.json, ablation_sweep.csv, ablation.png")
    return 0
