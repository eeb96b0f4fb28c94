"""The grasps experiment's summary: per-object rates, the confusion of the end agent's verdict
against Drake's, the refusals, recognition, and the figure and table that show them."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.experiments import common
from eos_svc.world.parameters import WorldParameters

#: the goal: share of good grasps Drake finds held
HELD_GOAL = 0.98
#: the goal: share of the admitted objects (those that fit between the fingertips along some
#: axis, :func:`~eos_svc.world.fingertip_fit.fit_refusal`) that end in a good grasp
GOOD_GOAL = 0.95
#: the postulate's confidence the grasp stage needs (the world's default threshold, 60 %)
CONFIDENCE_RULE = WorldParameters().confidence_threshold
#: words in a size refusal (admission's fit rule) that tell it from a position refusal
TOO_LARGE = "fits between the fingertips along no axis"


def _rate(values: list[bool | None]) -> float | None:
    known = [v for v in values if v is not None]
    return float(np.mean(known)) if known else None


def summarise(objects: Sequence[Any], runs: list[dict[str, Any]]) -> tuple[list[dict], dict]:
    """Per-object rows and the totals: confusion counts of good_grasp against held (when the
    runs were validated), refusals counted by the field admission named, and every admitted run
    that did not end in a good grasp listed with its status and reason."""
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
                "good_and_held": sum(bool(r["held"]) for r in good),
                "good": len(good),
                "median_plan_time_s": float(np.median([r["plan_time_s"] for r in done])) if done else None,
            }
        )
    done = [r for r in runs if r["status"] != "rejected"]
    refused: dict[str, int] = {}
    refused_why = {"too large": 0, "position": 0}
    for r in runs:
        if r["status"] == "rejected":
            refused[r["refused_field"]] = refused.get(r["refused_field"], 0) + 1
            refused_why["too large" if TOO_LARGE in r["reason"] else "position"] += 1
    failures = [
        {"object": r["object"], "seed": r["seed"], "status": r["status"], "reason": r["reason"]}
        for r in done
        if not r["good_grasp"]
    ]
    validated = [r for r in done if r["held"] is not None]
    confusion = {
        "good_held": sum(r["good_grasp"] and r["held"] for r in validated),
        "good_dropped": sum(r["good_grasp"] and not r["held"] for r in validated),
        "not_good_held": sum(not r["good_grasp"] and r["held"] for r in validated),
        "not_good_dropped": sum(not r["good_grasp"] and not r["held"] for r in validated),
    }
    good = confusion["good_held"] + confusion["good_dropped"]
    timed = [r["validation_time_s"] for r in validated if "validation_time_s" in r]  # not in Drake's
    moved = [r["object_moved_mm"] for r in done if "object_moved_mm" in r]  # the Drake world's
    totals = {
        "runs": len(done),
        "rejected": len(runs) - len(done),
        "refused_by_field": refused,
        "refused_by_reason": refused_why,
        "good_goal": GOOD_GOAL,
        "good_goal_met": (_rate([r["good_grasp"] for r in done]) or 0.0) >= GOOD_GOAL if done else None,
        "validated": len(validated),
        "confusion": confusion,
        "success_rate": _rate([r["status"] == "success" for r in done]),
        "good_grasp_rate": _rate([r["good_grasp"] for r in done]),
        "success_without_good_grasp": sum(r["status"] == "success" and not r["good_grasp"] for r in done),
        "held_rate": _rate([r["held"] for r in validated]),
        "held_given_good": confusion["good_held"] / good if good else None,
        "held_goal": HELD_GOAL,
        "goal_met": (confusion["good_held"] / good >= HELD_GOAL) if good else None,
        "agreement": (confusion["good_held"] + confusion["not_good_dropped"]) / len(validated)
        if validated
        else None,
        "median_plan_time_s": float(np.median([r["plan_time_s"] for r in done])) if done else None,
        **recognition_totals(done),
        "median_validation_time_s": float(np.median(timed)) if timed else None,
        "median_object_moved_mm": float(np.median(moved)) if moved else None,
        "failures": failures,
    }
    return rows, totals


def recognition_totals(done: list[dict[str, Any]]) -> dict[str, Any]:
    """Over the admitted runs: class right, the shape error's median and 90th percentile,
    wrong classes held with confidence ≥ 0.9, and the touches and probes per plan (medians, max)."""
    if not done:
        return {}
    errors = [r["shape_error"] for r in done if r["shape_error"] is not None]
    return {
        "class_right_rate": _rate([r["class_right"] for r in done]),
        "shape_error_median": float(np.median(errors)) if errors else None,
        "shape_error_p90": float(np.percentile(errors, 90)) if errors else None,
        "confident_wrong": sum(not r["class_right"] and r["confidence"] >= 0.9 for r in done),
        "grasped_unsure": sum(r["grasped_unsure"] for r in done),
        "touches_median": float(np.median([r["touches"] for r in done])),
        "touches_max": max(r["touches"] for r in done),
        "probes_median": float(np.median([r["probes"] for r in done])),
        "probes_max": max(r["probes"] for r in done),
    }


def plot(rows: list[dict], totals: dict, path: Path, name: str) -> Path:
    """Good-grasp rate and Drake hold rate per object (horizontal bars)."""
    fig, ax = common.pyplot().subplots(figsize=(7.5, 0.6 + 0.24 * len(rows)), dpi=120)
    y = np.arange(len(rows))
    ax.barh(y - 0.2, [r["good_grasp_rate"] or 0.0 for r in rows], height=0.4, label="good grasp (end agent)")
    ax.barh(y + 0.2, [r["held_rate"] or 0.0 for r in rows], height=0.4, label="held (Drake)")
    ax.set_yticks(y, [r["object"] for r in rows], fontsize=7)
    ax.invert_yaxis()
    ax.set(xlim=(0, 1.05), xlabel="rate over seeds")
    median = totals["median_plan_time_s"]
    held = totals["held_given_good"]
    ax.set_title(
        f"{name}: good grasps held {'-' if held is None else f'{held:.0%}'} (goal {HELD_GOAL:.0%}); "
        f"median plan {'-' if median is None else f'{median * 1000:.0f} ms'}",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="lower right")
    return common.save_figure(fig, path)


def _pct(value: float | None) -> str:
    return "    -" if value is None else f"{value:5.0%}"


def report(data: dict) -> str:
    """Human-readable table, the confusion counts, the refusals by field and every admitted run
    that did not end in a good grasp."""
    lines = ["  object                          runs  success  good   held  good->held  plan ms"]
    for r in data["rows"]:
        if not r["runs"]:
            continue
        plan_ms = "-" if r["median_plan_time_s"] is None else f"{r['median_plan_time_s'] * 1000:.0f}"
        lines.append(
            f"  {r['object']:<30} {r['runs']:>5}  {_pct(r['success_rate'])}  {_pct(r['good_grasp_rate'])}"
            f"  {_pct(r['held_rate'])}  {r['good_and_held']:>4}/{r['good']:<5}  {plan_ms:>7}"
        )
    t = data["totals"]
    c = t["confusion"]
    refused = ", ".join(f"{field} {n}" for field, n in sorted(t["refused_by_field"].items())) or "none"
    why = ", ".join(f"{k} {n}" for k, n in t["refused_by_reason"].items())
    lines.append(
        f"runs {t['runs']} (refused by admission: {t['rejected']}: {refused}; {why}); "
        f"success {_pct(t['success_rate'])}, good grasps {_pct(t['good_grasp_rate'])} of the admitted "
        f"(goal {GOOD_GOAL:.0%}, met: {t['good_goal_met']}), "
        f"success without a good grasp: {t['success_without_good_grasp']}"
    )
    if t["validated"]:
        lines += [
            f"validated in Drake: {t['validated']}; held {_pct(t['held_rate'])}",
            "confusion (end agent's good_grasp vs Drake's held):",
            "                 held  dropped",
            f"  good       {c['good_held']:>8} {c['good_dropped']:>8}",
            f"  not good   {c['not_good_held']:>8} {c['not_good_dropped']:>8}",
            f"good grasps held: {_pct(t['held_given_good'])} (goal {HELD_GOAL:.0%}, met: {t['goal_met']}); "
            f"agreement {_pct(t['agreement'])}"
            + (
                f"; median validation {t['median_validation_time_s']:.1f} s"
                if t["median_validation_time_s"] is not None
                else "; held = the Drake world's lift test"
            ),
        ]
    if t.get("median_object_moved_mm") is not None:
        lines.append(f"median object displacement in the Drake world: {t['median_object_moved_mm']:.1f} mm")
    if t["runs"]:
        lines.append(f"median plan {t['median_plan_time_s'] * 1000:.0f} ms")
        p90 = t["shape_error_p90"]
        lines.append(
            f"recognition: class right {_pct(t['class_right_rate'])}, shape error p90 "
            f"{'-' if p90 is None else f'{p90:.1%}'}, "
            f"wrong class at confidence >= 0.9: {t['confident_wrong']}, "
            f"grasping entered below the {CONFIDENCE_RULE:.0%} rule: {t['grasped_unsure']}; "
            f"per plan: touches median {t['touches_median']:.0f} (max {t['touches_max']}), "
            f"probes median {t['probes_median']:.0f} (max {t['probes_max']})"
        )
    if t["failures"]:
        lines.append(f"not a good grasp ({len(t['failures'])}):")
        lines += [f"  {f['object']} seed {f['seed']}: {f['status']} — {f['reason']}" for f in t["failures"]]
    return "\n".join(lines)
