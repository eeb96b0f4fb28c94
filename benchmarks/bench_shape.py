"""The shape fit: ``select_class`` on the touches of real plans, this tree against a baseline.

    .venv/bin/python benchmarks/bench_shape.py [--baseline ddccb46] [--all] [--rounds 40]

Runs the default plan (``plan(PlanRequest())``; with ``--all`` also an ellipsoid, a cylinder,
a capsule and a box plan) and keeps the touches its post_shape fitted last. Then
``select_class`` on those touches with this tree's ``eos_svc.shape`` and with the package as it
is at git revision ``--baseline`` (default ``ddccb46``, before the fit's evaluations were fused
and its kernels thinned), imported in the same process under a private name and timed in
alternating rounds (the machine's load changes within a run): the median of each and the
median of the per-round ratios. The two postulates are compared first: class, confidence,
posteriors and every class's χ², bit for bit. This tree's compiled kernels
(``eos_svc.shape.compiled``) are warmed up first — compiled, or loaded from numba's on-disk
cache — and the time that took is printed; nothing compiles inside the timed rounds.
"""

from __future__ import annotations

import argparse
import atexit
import importlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

import eos_svc.agents.post_shape as post_shape
from eos_svc import shape
from eos_svc.agents import PlanRequest, plan
from eos_svc.shape import compiled

ROOT = Path(__file__).resolve().parents[1]
ACROSS = [1.5707963267948966, 0.0, 0.0]  # a cylinder or capsule lying across the approach

#: (label, request JSON): the default plan, then one plan per other class
PLANS: list[tuple[str, dict[str, Any]]] = [
    ("default (sphere)", {}),
    ("ellipsoid", {"seed": 1, "object": {"shape": "ellipsoid", "radii": [0.035, 0.03, 0.025]}}),
    ("cylinder", {"seed": 3, "object": {"shape": "cylinder", "radius": 0.02, "length": 0.08, "rpy": ACROSS}}),
    ("capsule", {"seed": 2, "object": {"shape": "capsule", "radius": 0.028, "length": 0.04, "rpy": ACROSS}}),
    ("box", {"seed": 5, "object": {"shape": "box", "size": [0.05, 0.06, 0.04]}}),
]


def load_shape(rev: str) -> ModuleType:
    """``eos_svc.shape`` of git revision ``rev``, imported as a private package (its own
    imports of ``eos_svc.shape`` rewritten to that name)."""
    listing = subprocess.run(
        ["git", "-C", str(ROOT), "ls-tree", "--name-only", rev, "eos_svc/shape/"],
        capture_output=True, text=True, check=True,
    ).stdout.split()
    tmp = Path(tempfile.mkdtemp(prefix="eos_baseline_shape_"))
    atexit.register(shutil.rmtree, tmp, True)
    name = "eos_baseline_shape_" + re.sub(r"\W", "_", rev)
    pkg = tmp / name
    pkg.mkdir()
    for f in listing:
        if f.endswith(".py"):
            text = subprocess.run(
                ["git", "-C", str(ROOT), "show", f"{rev}:{f}"], capture_output=True, text=True, check=True
            ).stdout
            (pkg / Path(f).name).write_text(text.replace("eos_svc.shape", name))
    sys.path.insert(0, str(tmp))
    return importlib.import_module(name)


def captured_touches(request: dict[str, Any]) -> dict[str, np.ndarray | float]:
    """The arguments of the Touches post_shape fitted last in the plan of ``request``."""
    seen: list[shape.Touches] = []
    original = post_shape.select_class

    def recording(touches: shape.Touches, *args: Any, **kwargs: Any) -> shape.Postulate:
        seen.append(touches)
        return original(touches, *args, **kwargs)

    post_shape.select_class = recording  # type: ignore[assignment]
    try:
        plan(PlanRequest.from_dict({**request, "deadline_s": None}))
    finally:
        post_shape.select_class = original
    if not seen:
        raise SystemExit(f"the plan {request} fitted no touches")
    t = seen[-1]
    return {"centres": t.centres, "normals": t.normals, "radii": t.radii, "free": t.free,
            "free_radii": t.free_radii, "tactile_noise": t.tactile_noise,
            "contact_tolerance": t.contact_tolerance}


def fingerprint(post: Any) -> tuple[Any, ...]:
    """What a postulate says, to compare bit for bit."""
    return (post.kind, post.confidence, tuple(sorted(post.probabilities.items())),
            tuple((k, f.chi2, f.start, f.theta.tobytes()) for k, f in sorted(post.fits.items())))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default="ddccb46", help="git revision to compare with (ddccb46)")
    parser.add_argument("--all", action="store_true", help="also the other classes' plans")
    parser.add_argument("--rounds", type=int, default=40, help="alternating rounds per plan (40)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    compiled.warm_up()
    print(f"compiled kernels: warm_up {time.perf_counter() - t0:.2f} s (compiled, or loaded from the cache)")
    old = load_shape(args.baseline)
    print(f"select_class: this tree against {args.baseline}, {args.rounds} alternating rounds each")
    print(f"{'plan':18s} {'contacts':>8s} {args.baseline:>10s} {'this tree':>10s} {'ratio':>7s}  postulate")
    for label, request in PLANS if args.all else PLANS[:1]:
        kwargs = captured_touches(request)
        new_touches, old_touches = shape.Touches(**kwargs), old.Touches(**kwargs)
        new_post, old_post = shape.select_class(new_touches), old.select_class(old_touches)
        same = "identical" if fingerprint(new_post) == fingerprint(old_post) else "DIFFERS"
        for _ in range(2):  # warm-up
            shape.select_class(new_touches)
            old.select_class(old_touches)
        before, after, ratios = [], [], []
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            old.select_class(old_touches)
            t1 = time.perf_counter()
            shape.select_class(new_touches)
            t2 = time.perf_counter()
            before.append(t1 - t0)
            after.append(t2 - t1)
            ratios.append((t2 - t1) / (t1 - t0))
        print(f"{label:18s} {new_touches.count:8d} {statistics.median(before) * 1e3:7.2f} ms "
              f"{statistics.median(after) * 1e3:7.2f} ms {statistics.median(ratios):6.3f}x  "
              f"{new_post.kind} ({same})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
