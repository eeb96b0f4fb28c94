"""Grasps that hold: plan a suite of objects, validate every plan in Drake, compare verdicts.

For each object of the suite (:mod:`eos_svc.experiments.grasp_suite`) and each seed: plan
(weights 0.5, 0.5), then simulate the final grasp in Drake
(:func:`eos_svc.validation.validate_grasp`). Reports per object the success rate, the
good-grasp rate (the end agent's verdict), the Drake hold rate and the median plan time; over
the whole suite the confusion counts of ``good_grasp`` against Drake's ``held`` (the goal:
good grasps are held ≥ 98 %).

    eos experiment grasps                      # the fixed suite, 5 seeds
    eos experiment grasps --held-back          # the seeded held-back suite instead
    eos experiment grasps --quick --seeds 1    # one object per class
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import PlanRequest, plan
from eos_svc.cli.common import int_at_least, positive_float
from eos_svc.errors import ValidationError
from eos_svc.experiments.common import experiment_parser, pyplot, save_figure, write_csv, write_json
from eos_svc.experiments.grasp_suite import SuiteObject, fixed_suite, held_back_suite, quick_suite
from eos_svc.validation import SimulationError, validate_grasp
from eos_svc.validation.validate import MAX_SECONDS

#: the goal: share of good grasps Drake finds held
HELD_GOAL = 0.98


def plan_and_validate(obj: SuiteObject, seed: int, validation: dict[str, Any]) -> dict[str, Any]:
    """One run: plan the object with ``seed``, validate the final grasp; a flat row."""
    row: dict[str, Any] = {"object": obj.label, "shape": obj.spec.shape, "seed": seed}
    try:
        result = plan(PlanRequest(obj=obj.spec, seed=seed), keep_trace=False)
    except ValidationError as exc:  # the planner refuses the request: not a run
        return {**row, "status": "rejected", "reason": str(exc), "good_grasp": None, "held": None}
    try:
        check = validate_grasp(result, **validation)
    except SimulationError as exc:  # counted as not held, and said so
        return {
            **row,
            "status": result.status,
            "reason": result.reason,
            "good_grasp": bool(result.good_grasp),
            "held": False,
            "epsilon": result.epsilon,
            "plan_time_s": result.wall_time_s,
            "validation_time_s": 0.0,
            "max_displacement_m": None,
            "dropped_along": "",
            "validation_reason": str(exc),
        }
    dropped = [o.direction for o in check.outcomes if not o.held]
    return {
        **row,
        "status": result.status,
        "reason": result.reason,
        "good_grasp": bool(result.good_grasp),
        "held": bool(check.held),
        "epsilon": result.epsilon,
        "plan_time_s": result.wall_time_s,
        "validation_time_s": check.wall_time_s,
        "max_displacement_m": max(check.displacement_m.values()),
        "dropped_along": " ".join(dropped),
        "validation_reason": check.reason,
    }


def _rate(values: list[bool]) -> float | None:
    return float(np.mean(values)) if values else None


def summarise(objects: Sequence[SuiteObject], runs: list[dict[str, Any]]) -> tuple[list[dict], dict]:
    """Per-object rows and the totals (confusion counts of good_grasp against held)."""
    rows = []
    for obj in objects:
        mine = [r for r in runs if r["object"] == obj.label]
        done = [r for r in mine if r["status"] != "rejected"]
        good = [r for r in done if r["good_grasp"]]
        rows.append(
            {
                "object": obj.label,
                "shape": obj.spec.shape,
                "runs": len(done),
                "rejected": len(mine) - len(done),
                "success_rate": _rate([r["status"] == "success" for r in done]),
                "good_grasp_rate": _rate([r["good_grasp"] for r in done]),
                "held_rate": _rate([r["held"] for r in done]),
                "good_and_held": sum(r["held"] for r in good),
                "good": len(good),
                "median_plan_time_s": float(np.median([r["plan_time_s"] for r in done])) if done else None,
            }
        )
    done = [r for r in runs if r["status"] != "rejected"]
    confusion = {
        "good_held": sum(r["good_grasp"] and r["held"] for r in done),
        "good_dropped": sum(r["good_grasp"] and not r["held"] for r in done),
        "not_good_held": sum(not r["good_grasp"] and r["held"] for r in done),
        "not_good_dropped": sum(not r["good_grasp"] and not r["held"] for r in done),
    }
    good = confusion["good_held"] + confusion["good_dropped"]
    totals = {
        "runs": len(done),
        "rejected": len(runs) - len(done),
        "confusion": confusion,
        "good_grasp_rate": _rate([r["good_grasp"] for r in done]),
        "held_rate": _rate([r["held"] for r in done]),
        "held_given_good": confusion["good_held"] / good if good else None,
        "held_goal": HELD_GOAL,
        "goal_met": (confusion["good_held"] / good >= HELD_GOAL) if good else None,
        "agreement": (confusion["good_held"] + confusion["not_good_dropped"]) / len(done) if done else None,
        "median_plan_time_s": float(np.median([r["plan_time_s"] for r in done])) if done else None,
        "median_validation_time_s": float(np.median([r["validation_time_s"] for r in done]))
        if done
        else None,
    }
    return rows, totals


def run(
    objects: Sequence[SuiteObject] | None = None,
    seeds: int = 5,
    out: Path = Path("results/grasps"),
    name: str = "grasps",
    quiet: bool = False,
    validation: dict[str, Any] | None = None,
) -> dict:
    """Plan and validate every object over ``seeds`` seeds; write ``name``.json, .csv,
    ``name``_runs.csv and ``name``.png into ``out``."""
    objects = list(fixed_suite() if objects is None else objects)
    validation = dict(validation or {})
    runs: list[dict[str, Any]] = []
    total = len(objects) * seeds
    t0 = time.perf_counter()
    for obj in objects:
        for seed in range(1, seeds + 1):
            runs.append(plan_and_validate(obj, seed, validation))
            if not quiet:
                elapsed = time.perf_counter() - t0
                print(
                    f"\r{name}: {len(runs)}/{total} plans validated, {elapsed:.0f} s, "
                    f"~{elapsed / len(runs) * (total - len(runs)):.0f} s left ({obj.label})        ",
                    end="",
                    file=sys.stderr,
                    flush=True,
                )
    if not quiet:
        print(file=sys.stderr)
    rows, totals = summarise(objects, runs)
    data = {
        "suite": name,
        "seeds": seeds,
        "validation": validation,
        "objects": [{"label": o.label, **o.spec.to_dict()} for o in objects],
        "rows": rows,
        "totals": totals,
        "runs": runs,
    }
    write_json(out / f"{name}.json", data)
    write_csv(out / f"{name}.csv", rows)
    write_csv(out / f"{name}_runs.csv", runs)
    plot(rows, totals, out / f"{name}.png", name)
    return data


def plot(rows: list[dict], totals: dict, path: Path, name: str) -> Path:
    """Good-grasp rate and Drake hold rate per object (horizontal bars)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 0.6 + 0.24 * len(rows)), dpi=120)
    y = np.arange(len(rows))
    ax.barh(y - 0.2, [r["good_grasp_rate"] or 0.0 for r in rows], height=0.4, label="good grasp (end agent)")
    ax.barh(y + 0.2, [r["held_rate"] or 0.0 for r in rows], height=0.4, label="held (Drake)")
    ax.set_yticks(y, [r["object"] for r in rows], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(0, 1.05)
    ax.set_xlabel("rate over seeds")
    median = totals["median_plan_time_s"]
    held = totals["held_given_good"]
    ax.set_title(
        f"{name}: good grasps held {'-' if held is None else f'{held:.0%}'} (goal {HELD_GOAL:.0%}); "
        f"median plan {'-' if median is None else f'{median * 1000:.0f} ms'}",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="lower right")
    return save_figure(fig, path)


def _pct(value: float | None) -> str:
    return "    -" if value is None else f"{value:5.0%}"


def report(data: dict) -> str:
    """Human-readable table and the confusion counts."""
    lines = ["  object                          runs  success  good   held  good->held  plan ms"]
    for r in data["rows"]:
        plan_ms = "-" if r["median_plan_time_s"] is None else f"{r['median_plan_time_s'] * 1000:.0f}"
        lines.append(
            f"  {r['object']:<30} {r['runs']:>5}  {_pct(r['success_rate'])}  {_pct(r['good_grasp_rate'])}"
            f"  {_pct(r['held_rate'])}  {r['good_and_held']:>4}/{r['good']:<5}  {plan_ms:>7}"
        )
    t = data["totals"]
    c = t["confusion"]
    lines += [
        f"runs {t['runs']} (rejected by the planner: {t['rejected']}); "
        f"good grasps {_pct(t['good_grasp_rate'])}, held {_pct(t['held_rate'])}",
        "confusion (end agent's good_grasp vs Drake's held):",
        "                 held  dropped",
        f"  good       {c['good_held']:>8} {c['good_dropped']:>8}",
        f"  not good   {c['not_good_held']:>8} {c['not_good_dropped']:>8}",
        f"good grasps held: {_pct(t['held_given_good'])} (goal {HELD_GOAL:.0%}, met: {t['goal_met']}); "
        f"agreement {_pct(t['agreement'])}; median plan {t['median_plan_time_s'] * 1000:.0f} ms, "
        f"median validation {t['median_validation_time_s']:.1f} s"
        if t["runs"]
        else "no runs",
    ]
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of this experiment."""
    parser = experiment_parser("grasps", __doc__, "results/grasps")
    parser.add_argument(
        "--seeds", type=int_at_least(1), default=None, help="seeds per object (5; 2 with --quick)"
    )
    parser.add_argument("--quick", action="store_true", help="a small subset: one object per class")
    parser.add_argument(
        "--held-back",
        action="store_true",
        help="run the held-back suite (seeded random sizes, poses and positions) instead of the fixed one",
    )
    parser.add_argument(
        "--seconds", type=positive_float, default=1.5, help="Drake load time per direction, s (1.5)"
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment grasps [options]``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.seconds > MAX_SECONDS:
        parser.error(f"argument --seconds: must be ≤ {MAX_SECONDS:g}, got {args.seconds:g}")
    seeds = args.seeds or (2 if args.quick else 5)
    if args.held_back:
        objects, name = held_back_suite(1 if args.quick else 3), "grasps_held_back"
    else:
        objects, name = (quick_suite() if args.quick else fixed_suite()), "grasps"
    data = run(objects, seeds, args.out, name, validation={"seconds": args.seconds})
    print(report(data))
    print(f"wrote {args.out}/{name}.json, {name}.csv, {name}_runs.csv, {name}.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
