"""Knowing the object by touch: how often the postulate is right, how close, how sure.

Seeded objects of every class planned at tactile noise 0, 0.2 and 0.4 mm: the class confusion, the
shape-and-pose error, the confidence's calibration ("right": class right, error ≤ 10 %) and the
search length over 100 seeds (figures: ``docs/planner.md``; ``--quick``: a short run).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import ObjectSpec, PlanRequest, keys
from eos_svc.agents.planner import build_world, make_object
from eos_svc.agents.search import search_move
from eos_svc.board import Board
from eos_svc.cli.common import int_at_least
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.experiments import common

CLASSES = ("sphere", "ellipsoid", "cylinder", "capsule", "box")
POSTULATES = (*CLASSES, "plane", "none")
NOISES = (0.0, 2e-4, 4e-4)
#: the tolerance "right" refers to (relative shape-and-pose error)
TOLERANCE = 0.10


def random_object(kind: str, size_index: int, rng: np.random.Generator) -> ObjectSpec:
    """An object of ``kind``: size class ``size_index`` (0 small, 1 medium, 2 large), a position
    within ±2 cm of the default and a random pose (yaw ±0.5 rad; cylinders and capsules lying
    across the approach or upright, boxes and ellipsoids tilted up to ±0.3 rad)."""
    scale = (0.75, 1.0, 1.25)[size_index]
    jitter = rng.uniform(0.9, 1.1, size=3)
    px, py, pz = (float(v) for v in np.asarray(ObjectSpec().position) + rng.uniform(-0.02, 0.02, size=3))
    position = (px, py, pz)
    yaw = float(rng.uniform(-0.5, 0.5))
    if kind == "sphere":
        return ObjectSpec("sphere", {"radius": 0.024 * scale * jitter[0]}, position)
    if kind == "ellipsoid":
        radii = (0.032 * scale * jitter[0], 0.026 * scale * jitter[1], 0.021 * scale * jitter[2])
        rpy = (float(rng.uniform(-0.3, 0.3)), 0.0, yaw)
        return ObjectSpec("ellipsoid", {"radii": radii}, position, rpy)
    if kind in ("cylinder", "capsule"):
        radius = 0.018 * scale * jitter[0]
        length = 0.05 * scale * jitter[1]
        lying = bool(rng.integers(2))
        rpy = (math.pi / 2, 0.0, yaw) if lying else (0.0, 0.0, yaw)
        return ObjectSpec(kind, {"radius": radius, "length": length}, position, rpy)
    size = (0.045 * scale * jitter[0], 0.055 * scale * jitter[1], 0.04 * scale * jitter[2])
    return ObjectSpec("box", {"size": size}, position, (float(rng.uniform(-0.3, 0.3)), 0.0, yaw))


def surface_error(truth: ObjectSpec, postulate: dict | None, rng: np.random.Generator, n: int = 200) -> float:
    """RMS distance (m) from ``n`` points of the true surface to the postulated one, over the
    true half extent; NaN without a postulated object."""
    if postulate is None:
        return math.nan
    true_obj = make_object(truth)
    guess = make_object(ObjectSpec.from_dict(postulate))
    c = np.asarray(truth.position)
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    err = [guess.signed_distance(true_obj.closest_surface_point(c + 0.3 * d)) for d in dirs]
    return float(np.sqrt(np.mean(np.square(err))) / (0.5 * true_obj.diameter))


def pose_and_size_error(truth: ObjectSpec, postulate: dict | None) -> tuple[float, float]:
    """(distance between the postulated and the true centre in m, relative error of the
    bounding diameter); NaN without a postulated object."""
    if postulate is None:
        return math.nan, math.nan
    guess = ObjectSpec.from_dict(postulate)
    distance = float(np.linalg.norm(np.asarray(guess.position) - np.asarray(truth.position)))
    d_true = make_object(truth).diameter
    return distance, abs(make_object(guess).diameter - d_true) / d_true


def search_lengths(seeds: int = 100, limit: int = 2000) -> list[int]:
    """Search moves to locate the default object for seeds 1…``seeds`` (``limit + 1`` if not)."""

    def moves(seed: int) -> int:
        world, board = KinematicDriver(build_world(PlanRequest(seed=seed))), Board()
        for k in range(1, limit + 1):
            search_move(world, board, "wrist")
            if board.get(keys.LOCATED):
                return k
        return limit + 1

    return [moves(seed) for seed in range(1, seeds + 1)]


def run(
    seeds: int = 3,
    sizes: int = 3,
    noises: Sequence[float] = NOISES,
    search_seeds: int = 100,
    out: Path = Path("results/recognition"),
    quiet: bool = False,
) -> dict[str, Any]:
    """Run the experiment; write recognition.csv, recognition.json and three PNGs into ``out``."""
    rng = np.random.default_rng(20261201)
    specs = [random_object(k, s, rng) for k in CLASSES for s in range(sizes)]
    rows: list[dict[str, Any]] = []
    for noise in noises:
        requests = [
            PlanRequest(obj=o, seed=seed, tactile_noise=noise) for o in specs for seed in range(1, seeds + 1)
        ]
        results = common.run_plans(requests, f"noise {noise * 1000:.1f} mm", quiet)
        for request, result in zip(requests, results, strict=True):
            shape = result.shape or {}
            guess = shape.get("class", "none")
            obj = shape.get("object")
            err = surface_error(request.obj, obj, np.random.default_rng(request.seed))
            pos_err, size_err = pose_and_size_error(request.obj, obj)
            right = guess == request.obj.shape and math.isfinite(err) and err <= TOLERANCE
            rows.append(
                {
                    "noise_m": noise,
                    "truth": request.obj.shape,
                    "object": ObjectSpec.to_dict(request.obj),
                    "seed": request.seed,
                    "postulate": guess,
                    "confidence": float(shape.get("confidence", 0.0)),
                    "class_right": guess == request.obj.shape,
                    "surface_error": err,
                    "position_error_m": pos_err,
                    "size_error": size_err,
                    "right": right,
                    "status": result.status,
                    "search_cycles": result.cycles_per_stage.get("search", 0),
                    "information_cycles": result.cycles_per_stage.get("information", 0),
                    "ep2_rounds": sum(1 for r in result.trace if r.chosen == "ep2"),
                    "wall_time_s": result.wall_time_s,
                }
            )
    lengths = search_lengths(search_seeds)
    data = summarize(rows, noises, lengths)
    common.write_csv(out / "recognition.csv", [{**r, "object": str(r["object"])} for r in rows])
    strict = [
        {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in r.items()} for r in rows
    ]
    common.write_json(out / "recognition.json", {**data, "rows": strict})  # NaN as None: strict JSON
    plot_confusion(data, out / "recognition_confusion.png")
    plot_calibration(data, out / "recognition_calibration.png")
    plot_search(lengths, out / "recognition_search.png")
    return data


def summarize(rows: list[dict[str, Any]], noises: Sequence[float], lengths: list[int]) -> dict[str, Any]:
    """Confusion matrices, accuracies, error percentiles, calibration bins, search lengths."""

    def stat(f: Any, values: list, *args: Any) -> float | None:
        return float(f(values, *args)) if len(values) else None

    per_noise = {}
    for noise in noises:
        sub = [r for r in rows if r["noise_m"] == noise]
        confusion = {t: {p: 0 for p in POSTULATES} for t in CLASSES}
        for r in sub:
            confusion[r["truth"]][r["postulate"] if r["postulate"] in POSTULATES else "none"] += 1
        right_class = [r for r in sub if r["class_right"]]
        errs, pos, size = (
            [r[k] for r in right_class if math.isfinite(r[k])]
            for k in ("surface_error", "position_error_m", "size_error")
        )
        confident = [r for r in sub if r["confidence"] >= 0.9]
        per_noise[f"{noise:g}"] = {
            "runs": len(sub),
            "class_accuracy": stat(np.mean, [r["class_right"] for r in sub]) if sub else math.nan,
            "right": stat(np.mean, [r["right"] for r in sub]) if sub else math.nan,
            "confusion": confusion,
            "error_median": stat(np.median, errs),
            "error_p90": stat(np.percentile, errs, 90),
            "position_error_median_m": stat(np.median, pos),
            "size_error_median": stat(np.median, size),
            "confident": len(confident),
            "confident_right": stat(np.mean, [r["right"] for r in confident]),
            "wrong_class_confident": sum(1 for r in confident if not r["class_right"]),
            "median_information_cycles": stat(np.median, [r["information_cycles"] for r in sub]),
            "median_wall_time_s": stat(np.median, [r["wall_time_s"] for r in sub]),
        }
    edges = [0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 1.0001]
    bins = []
    for lo, hi in itertools.pairwise(edges):
        sub = [r for r in rows if lo <= r["confidence"] < hi]
        bins.append(
            {
                "lo": lo,
                "hi": min(hi, 1.0),
                "n": len(sub),
                "mean_confidence": stat(np.mean, [r["confidence"] for r in sub]),
                "accuracy": stat(np.mean, [r["right"] for r in sub]),
            }
        )
    arr = np.array(lengths)
    search = {
        "seeds": len(lengths),
        "median": float(np.median(arr)),
        "p90": float(np.percentile(arr, 90)),
        "p99": float(np.percentile(arr, 99)),
        "max": int(arr.max()),
        "hit_limit": int(np.sum(arr > 2000)),
    }
    return {"per_noise": per_noise, "calibration": bins, "search": search, "tolerance": TOLERANCE}


def plot_confusion(data: dict[str, Any], path: Path) -> Path:
    """One confusion matrix per noise level."""
    noises = list(data["per_noise"])
    fig, axes = common.pyplot().subplots(
        1, len(noises), figsize=(4.2 * len(noises), 3.6), dpi=110, squeeze=False
    )
    for ax, noise in zip(axes[0], noises, strict=True):
        conf = data["per_noise"][noise]["confusion"]
        m = np.array([[conf[t][p] for p in POSTULATES] for t in CLASSES])
        ax.imshow(m, cmap="Blues")
        for i, j in zip(*np.nonzero(m), strict=True):
            ax.text(j, i, str(m[i, j]), ha="center", va="center", fontsize=8)
        ax.set_xticks(range(len(POSTULATES)), POSTULATES, rotation=45, fontsize=7)
        ax.set_yticks(range(len(CLASSES)), CLASSES, fontsize=7)
        ax.set_title(f"noise {float(noise) * 1000:.1f} mm", fontsize=9)
        ax.set_xlabel("postulated", fontsize=8)
    axes[0][0].set_ylabel("truth", fontsize=8)
    return common.save_figure(fig, path)


def plot_calibration(data: dict[str, Any], path: Path) -> Path:
    """Accuracy against confidence (bins), with the diagonal."""
    fig, ax = common.pyplot().subplots(figsize=(4.5, 4.0), dpi=110)
    bins = [b for b in data["calibration"] if b["n"]]
    ax.plot([0, 1], [0, 1], ":", color="grey")
    ax.plot([b["mean_confidence"] for b in bins], [b["accuracy"] for b in bins], "o-")
    for b in bins:
        xy = (b["mean_confidence"], b["accuracy"])
        ax.annotate(str(b["n"]), xy, fontsize=7, xytext=(3, -10), textcoords="offset points")
    ax.set(
        xlabel="confidence", ylabel="fraction right (class and ≤ 10 % error)", xlim=(0, 1.02), ylim=(0, 1.02)
    )
    ax.set_title("Calibration of post_shape's confidence", fontsize=9)
    return common.save_figure(fig, path)


def plot_search(lengths: list[int], path: Path) -> Path:
    """Histogram of search moves over seeds."""
    fig, ax = common.pyplot().subplots(figsize=(4.5, 3.2), dpi=110)
    ax.hist(lengths, bins=range(1, max(lengths) + 2), color="tab:blue")
    ax.set(xlabel="search moves to locate the default object", ylabel="seeds")
    ax.set_title(f"{len(lengths)} seeds: median {np.median(lengths):.0f}, max {max(lengths)}", fontsize=9)
    return common.save_figure(fig, path)


def report(data: dict[str, Any]) -> str:
    """Human-readable summary."""
    lines = ["  noise    runs  class  right  err med  err p90  conf≥0.9 (right)  wrong&conf≥0.9  time med"]
    for noise, d in data["per_noise"].items():
        med = "—" if d["error_median"] is None else f"{d['error_median']:.1%}"
        p90 = "—" if d["error_p90"] is None else f"{d['error_p90']:.1%}"
        cr = "—" if d["confident_right"] is None else f"{d['confident_right']:.0%}"
        lines.append(
            f"  {float(noise) * 1000:4.1f} mm {d['runs']:5d}  {d['class_accuracy']:5.0%}  {d['right']:5.0%}"
            f"  {med:>7}  {p90:>7}  {d['confident']:4d} ({cr:>4})  {d['wrong_class_confident']:14d}"
            f"  {d['median_wall_time_s']:6.2f} s"
        )
    s = data["search"]
    lines.append(
        f"  search over {s['seeds']} seeds: median {s['median']:.0f}, p90 {s['p90']:.0f}, "
        f"p99 {s['p99']:.0f}, max {s['max']} moves; {s['hit_limit']} hit the cycle limit"
    )
    for b in data["calibration"]:
        if b["n"]:
            lines.append(
                f"  confidence [{b['lo']:.1f}, {b['hi']:.1f}): {b['n']:4d} postulates, "
                f"{b['accuracy']:.0%} right"
            )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment recognition [options]``."""
    parser = common.experiment_parser("recognition", __doc__, "results/recognition")
    parser.add_argument("--seeds", type=int_at_least(1), default=3, help="seeds per object and noise (3)")
    parser.add_argument("--sizes", type=int, default=3, choices=(1, 2, 3), help="sizes per class (3)")
    parser.add_argument("--search-seeds", type=int_at_least(1), default=100, help="search run seeds (100)")
    parser.add_argument("--quick", action="store_true", help="1 size, 1 seed, default noise, 10 search seeds")
    args = parser.parse_args(argv)
    if args.quick:
        data = run(seeds=1, sizes=1, noises=(2e-4,), search_seeds=10, out=args.out)
    else:
        data = run(args.seeds, args.sizes, NOISES, args.search_seeds, args.out)
    print(report(data))
    pngs = "recognition_confusion.png, recognition_calibration.png, recognition_search.png"
    print(f"wrote {args.out}/recognition.csv, recognition.json, {pngs}")
    return 0
