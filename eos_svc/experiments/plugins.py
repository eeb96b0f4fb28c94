"""A plug-in grasp agent among the planner's own: chosen when its grasps are better, passed over
when worse, and the plan's result following.

Every object of the grasps suite (:func:`eos_svc.experiments.grasp_suite.fixed_suite`) is
planned three times with the same request (seed 1, weights 0.5/0.5): without plug-ins, and with
each of two configurations of the worked example plug-in
(:mod:`eos_svc.agents.plugins.sampled_grasp_points`):

- ``sampled+primitive``: GraspIt's orientations for the primitive and 12 sampled closing axes,
  the best ε of all (never worse than the stock synthesis on the postulate; better where the
  stock rule's preference for little wrist rotation or its four scored candidates cost ε);
- ``sampled only``: 6 sampled closing axes alone (usually worse).

Per object and configuration: the predicted ε of the plug-in's best grasp and of the stock
synthesis's (on post_shape's postulate, as the plug-in compares them when it rates itself),
whether the plug-in's is better (by more than 1 %, its own rule), which agent chose the grasp,
and the plan's status and final ε (the end agent's, on the true
object) with and without the plug-in.

    eos experiment plugins --out results/plugins
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.plugins.sampled_grasp_points import BETTER_BY, SampledGraspPointsAgent
from eos_svc.experiments.common import experiment_parser, pyplot, save_figure, write_csv, write_json
from eos_svc.experiments.grasp_suite import fixed_suite

#: the plug-in's configurations: name -> its factory's settings
CONFIGS: dict[str, dict[str, Any]] = {
    "sampled+primitive": {"samples": 12, "primitive_frames": True},
    "sampled only": {"samples": 6, "primitive_frames": False},
}


def grasp_agent(result: Any) -> str | None:
    """The agent that chose the grasp (grasp_points or the plug-in), if any did."""
    for record in result.trace:
        if record.chosen in ("grasp_points", "sampled_grasp_points") and record.outcome is not None:
            return str(record.chosen)
    return None


def one(label: str, request: PlanRequest, base: Any, config: str) -> dict[str, Any]:
    """Plan ``request`` with the plug-in in configuration ``config``; the row of the table."""
    made: list[SampledGraspPointsAgent] = []

    def factory(world: Any) -> SampledGraspPointsAgent:
        made.append(SampledGraspPointsAgent(world, **CONFIGS[config]))
        return made[0]

    result = plan(request, agents=[factory])
    compared = list(made[0]._compared.values())
    own, stock = compared[-1] if compared else (None, None)
    chosen = grasp_agent(result)
    better = own is not None and stock is not None and own > stock * (1.0 + BETTER_BY)
    return {
        "object": label,
        "config": config,
        "predicted_eps_plugin": own,
        "predicted_eps_stock": stock,
        "plugin_better": better if own is not None else None,
        "chosen": chosen,
        "status": result.status,
        "status_without": base.status,
        "eps": result.epsilon,
        "eps_without": base.epsilon,
    }


def run(out: Path = Path("results/plugins"), quiet: bool = False) -> dict[str, Any]:
    """Run the experiment; write plugins.json, plugins.csv and plugins.png into ``out``."""
    rows = []
    suite = fixed_suite()
    for i, obj in enumerate(suite, 1):
        request = PlanRequest(obj=obj.spec, seed=1)
        base = plan(request)
        for config in CONFIGS:
            rows.append(one(obj.label, request, base, config))
        if not quiet:
            print(f"\r{i}/{len(suite)} objects", end="", flush=True)
    if not quiet:
        print()
    summary = {config: summarize([r for r in rows if r["config"] == config]) for config in CONFIGS}
    write_json(out / "plugins.json", {"summary": summary, "rows": rows})
    write_csv(out / "plugins.csv", rows)
    plot(rows, out / "plugins.png")
    return summary


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per configuration: how often the plug-in was compared, better, chosen; whether the choice
    followed the comparison; and the plans' final ε with and without it."""
    compared = [r for r in rows if r["plugin_better"] is not None]
    chosen = [r for r in compared if r["chosen"] == "sampled_grasp_points"]
    passed = [r for r in compared if r["chosen"] == "grasp_points"]

    def mean(values: list[float]) -> float | None:
        return sum(values) / len(values) if values else None

    return {
        "objects": len(rows),
        "compared": len(compared),
        "plugin_better": sum(r["plugin_better"] for r in compared),
        "chosen": len(chosen),
        "passed_over": len(passed),
        "choice_follows_comparison": sum(
            (r["chosen"] == "sampled_grasp_points") == r["plugin_better"] for r in compared
        ),
        "chosen_mean_eps": mean([r["eps"] for r in chosen]),
        "chosen_mean_eps_without": mean([r["eps_without"] for r in chosen]),
        "chosen_eps_higher": sum(r["eps"] > r["eps_without"] for r in chosen),
        "chosen_success": sum(r["status"] == "success" for r in chosen),
        "chosen_success_without": sum(r["status_without"] == "success" for r in chosen),
        "passed_over_same_eps": sum(r["eps"] == r["eps_without"] for r in passed),
    }


def plot(rows: list[dict[str, Any]], path: Path) -> Path:
    """Predicted ε gain of the plug-in (x) against the plan's final ε gain (y), per configuration;
    filled: the plug-in was chosen."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for config, colour in zip(CONFIGS, ("tab:blue", "tab:orange"), strict=True):
        for chosen in (True, False):
            pts = [
                (r["predicted_eps_plugin"] - r["predicted_eps_stock"], r["eps"] - r["eps_without"])
                for r in rows
                if r["config"] == config
                and r["plugin_better"] is not None
                and (r["chosen"] == "sampled_grasp_points") == chosen
            ]
            if pts:
                xs, ys = zip(*pts, strict=True)
                ax.scatter(
                    xs,
                    ys,
                    s=28,
                    c=colour if chosen else "none",
                    edgecolors=colour,
                    label=f"{config}: {'chosen' if chosen else 'passed over'} ({len(pts)})",
                )
    ax.axvline(0.0, color="grey", lw=0.6)
    ax.axhline(0.0, color="grey", lw=0.6)
    ax.set_xlabel("predicted ε: plug-in minus stock synthesis (on the postulate)")
    ax.set_ylabel("plan's final ε: with minus without the plug-in")
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def main(argv: Sequence[str] | None = None) -> int:
    parser: argparse.ArgumentParser = experiment_parser("plugins", __doc__, "results/plugins")
    parser.add_argument("--quiet", action="store_true", help="no progress")
    args = parser.parse_args(argv)
    summary = run(args.out, args.quiet)
    for config, s in summary.items():
        print(
            f"{config}: {s['compared']} objects compared, plug-in better on {s['plugin_better']}, "
            f"chosen {s['chosen']}, passed over {s['passed_over']}; choice follows the comparison on "
            f"{s['choice_follows_comparison']}/{s['compared']}"
        )
        if s["chosen"]:
            print(
                f"  chosen: mean final ε {s['chosen_mean_eps']:.4f} vs {s['chosen_mean_eps_without']:.4f} "
                f"without; higher on {s['chosen_eps_higher']}/{s['chosen']}; success "
                f"{s['chosen_success']} vs {s['chosen_success_without']} without"
            )
        print(f"  passed over: the same final ε as without on {s['passed_over_same_eps']}/{s['passed_over']}")
    print(f"wrote {args.out}/plugins.json, plugins.csv, plugins.png")
    return 0
