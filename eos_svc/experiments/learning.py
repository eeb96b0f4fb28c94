"""The learned sub-rating (paper §7): a stream of objects with repeats, with and without learning.

Without: weights (0.5, 0.5, 0); with: (0.25, 0.25, 0.5) and a fresh grasp memory (``docs/planner.md``).

    eos experiment learning --out results/learning
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.memory import GraspMemory
from eos_svc.cli.common import int_at_least
from eos_svc.experiments import common
from eos_svc.ratings import Weights

ACROSS = (math.pi / 2, 0.0, 0.0)
POSITION = ObjectSpec().position
OBJECTS: dict[str, ObjectSpec] = {
    "sphere r18": ObjectSpec("sphere", {"radius": 0.018}, POSITION),
    "sphere r30": ObjectSpec("sphere", {"radius": 0.03}, POSITION),
    "sphere r42": ObjectSpec("sphere", {"radius": 0.042}, POSITION),
    "cylinder r25": ObjectSpec("cylinder", {"radius": 0.025, "length": 0.07}, POSITION, ACROSS),
    "box 50x60x40": ObjectSpec("box", {"size": (0.05, 0.06, 0.04)}, POSITION),
}
WITHOUT = Weights(0.5, 0.5, 0.0)
WITH = Weights(0.25, 0.25, 0.5)


def stream(repeats: int, seed: int) -> list[str]:
    """Every object ``repeats`` times, shuffled by ``seed``."""
    names = [name for name in OBJECTS for _ in range(repeats)]
    order = np.random.default_rng(seed).permutation(len(names))
    return [names[i] for i in order]


def run(repeats: int = 3, seed: int = 1, out: Path = Path("results/learning"), quiet: bool = False) -> dict:
    """Plan the stream without and with learning; write learning.json/.csv/.png (+ the memory)."""
    out.mkdir(parents=True, exist_ok=True)
    db = out / "memory.sqlite"
    for suffix in ("", "-wal", "-shm"):
        Path(str(db) + suffix).unlink(missing_ok=True)
    memory = GraspMemory(db)
    names = stream(repeats, seed)
    requests = [PlanRequest(obj=OBJECTS[name], seed=seed * 1000 + i) for i, name in enumerate(names)]
    base = common.run_plans([replace(r, weights=WITHOUT) for r in requests], "without learning", quiet)
    with_memory = [replace(r, weights=WITH) for r in requests]
    learned = common.run_plans(with_memory, "with learning", quiet, memory=memory)
    rows: list[dict[str, Any]] = [
        {
            "index": i,
            "object": name,
            "repeat": name in names[:i],
            "grasp_cycles_without": without.cycles_per_stage.get("grasping", 0),
            "grasp_cycles_with": with_.cycles_per_stage.get("grasping", 0),
            "status_without": without.status,
            "status_with": with_.status,
            "recalled": "recall" in with_.agents_run(),
        }
        for i, (name, without, with_) in enumerate(zip(names, base, learned, strict=True))
    ]
    memory.close()

    def mean(key: str, repeat: bool) -> float | None:  # None: no such plan (no repeats)
        values = [r[key] for r in rows if r["repeat"] == repeat]
        return float(np.mean(values)) if values else None

    summary: dict[str, Any] = {
        "new": {"without": mean("grasp_cycles_without", False), "with": mean("grasp_cycles_with", False)},
        "repeated": {"without": mean("grasp_cycles_without", True), "with": mean("grasp_cycles_with", True)},
    }
    rep = summary["repeated"]
    summary["repeated_reduction"] = 1.0 - rep["with"] / rep["without"] if rep["without"] else None
    summary["new_worse"] = sum(
        not r["repeat"] and r["grasp_cycles_with"] > r["grasp_cycles_without"] for r in rows
    )
    data = {"repeats": repeats, "seed": seed, "rows": rows, "summary": summary, "memory": str(db)}
    common.write_json(out / "learning.json", data)
    common.write_csv(out / "learning.csv", rows)
    plot(rows, out / "learning.png")
    return data


def plot(rows: list[dict], path: Path) -> Path:
    """Grasp cycles per plan along the stream, with and without learning."""
    fig, ax = common.pyplot().subplots(figsize=(7.0, 3.8), dpi=120)
    x = [r["index"] for r in rows]
    ax.plot(x, [r["grasp_cycles_without"] for r in rows], "o-", label="without learning", alpha=0.8)
    ax.plot(x, [r["grasp_cycles_with"] for r in rows], "s-", label="with learning", alpha=0.8)
    for r in rows:
        if r["repeat"]:
            ax.axvspan(r["index"] - 0.4, r["index"] + 0.4, color="0.9", zorder=0)
    ax.set(xlabel="plan in the stream (shaded: an object seen before)", ylabel="grasp-stage cycles")
    ax.set_title("Learned sub-rating: grasp cycles on new and repeated objects")
    ax.legend(fontsize=8)
    return common.save_figure(fig, path)


def report(data: dict) -> str:
    """Human-readable summary."""
    s = data["summary"]
    lines = [f"  {'#':>2}  {'object':<14} {'seen':<5} without  with  recalled"]
    for r in data["rows"]:
        lines.append(
            f"  {r['index']:>2}  {r['object']:<14} {'yes' if r['repeat'] else 'no':<5} "
            f"{r['grasp_cycles_without']:>7}  {r['grasp_cycles_with']:>4}  {r['recalled']}"
        )
    rep, fewer = s["repeated"], s["repeated_reduction"]
    repeated = "none" if rep["without"] is None else f"{rep['without']:.1f} without, {rep['with']:.1f} with"
    lines.append(
        f"mean grasp cycles — new: {s['new']['without']:.1f} without, {s['new']['with']:.1f} with; "
        f"repeated: {repeated} ({'-' if fewer is None else f'{fewer:.0%}'} fewer); "
        f"new objects worse with learning: {s['new_worse']}"
    )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment learning [options]``."""
    parser = common.experiment_parser("learning", __doc__, "results/learning")
    parser.add_argument("--repeats", type=int_at_least(1), default=3, help="times each object appears (3)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the stream order and the plans (1)")
    args = parser.parse_args(argv)
    data = run(args.repeats, args.seed, args.out)
    print(report(data))
    print(f"wrote {args.out}/learning.json, learning.csv, learning.png, memory.sqlite")
    return 0
