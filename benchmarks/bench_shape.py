"""The shape fit: ``select_class`` on the touches of real plans, this tree against a baseline.

    .venv/bin/python benchmarks/bench_shape.py --baseline-tree ../base [--rounds 15] [--kernels] [--compiled]
    .venv/bin/python benchmarks/bench_shape.py --baseline-tree . --compiled   # compiled vs numpy here

Plans the grasp experiment's fixed suite (seed 1) and keeps every set of touches post_shape
fitted. Then times ``select_class`` over all of them, here and in a child process running the
baseline checkout's own interpreter (``<tree>/.venv/bin/python``), in alternating rounds (the
machine's load changes within a run): the median of each and the median of the per-round
ratios. ``--kernels``: the baseline loads its compiled fit kernels first, where it has them;
``--compiled``: this tree does (:func:`eos_svc.shape.kernels.load`), else it fits in numpy.
``--python``: the baseline's interpreter (default ``<tree>/.venv/bin/python``, else this one).
The postulates are compared too: the same class on every set of touches, and the largest
difference in confidence.
"""

from __future__ import annotations

import argparse
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import eos_svc.agents.post_shape as post_shape
from eos_svc.agents import PlanRequest, plan
from eos_svc.experiments.grasp_suite import fixed_suite
from eos_svc.shape import Touches, kernels, select_class

#: the timing loop, run in this tree and in the baseline's: reads the touches, answers each
#: "time" line with the seconds one pass over them took, "result" with the postulates
CHILD = """
import pickle, sys, time
if sys.argv[2] == "kernels":
    try:
        from eos_svc.shape import kernels
        kernels.load()
    except ImportError:
        pass
from eos_svc.shape import Touches, select_class
touches = [Touches(*a) for a in pickle.load(open(sys.argv[1], "rb"))]
for line in sys.stdin:
    if line.strip() == "time":
        t0 = time.perf_counter()
        for t in touches:
            select_class(t)
        print(time.perf_counter() - t0, flush=True)
    else:
        print([(p.kind, p.confidence) for p in map(select_class, touches)], flush=True)
"""


def suite_touches() -> list[Touches]:
    """Every set of touches post_shape fitted while planning the fixed suite (seed 1)."""
    seen: list[Touches] = []
    fit = post_shape.select_class

    def keep(touches: Touches, **options: object) -> object:
        seen.append(touches)
        return fit(touches, **options)  # type: ignore[arg-type]

    post_shape.select_class = keep  # type: ignore[assignment]
    try:
        for item in fixed_suite():
            plan(PlanRequest(obj=item.spec, seed=1), keep_trace=False)
    finally:
        post_shape.select_class = fit  # type: ignore[assignment]
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline-tree", type=Path, required=True, help="a checkout with its own .venv")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--kernels", action="store_true", help="the baseline loads its compiled kernels")
    parser.add_argument("--compiled", action="store_true", help="this tree loads its compiled residuals")
    parser.add_argument("--python", type=Path, help="the baseline's interpreter")
    args = parser.parse_args()
    if args.compiled and not kernels.load():
        raise SystemExit("--compiled: numba is not installed (the fast extra)")
    touches = suite_touches()
    with tempfile.NamedTemporaryFile(suffix=".pkl", delete=False) as f:
        pickle.dump(
            [
                (t.centres, t.normals, t.radii, t.free, t.free_radii, t.tactile_noise, t.contact_tolerance)
                for t in touches
            ],
            f,
        )
    tree = args.baseline_tree.resolve()
    own = tree / ".venv/bin/python"
    python = args.python or (own if own.exists() else Path(sys.executable))
    child = subprocess.Popen(
        [str(python), "-c", CHILD, f.name, "kernels" if args.kernels else "numpy"],
        cwd=tree,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdin is not None and child.stdout is not None

    def baseline(command: str) -> str:
        child.stdin.write(command + "\n")  # type: ignore[union-attr]
        child.stdin.flush()  # type: ignore[union-attr]
        return child.stdout.readline()  # type: ignore[union-attr]

    ours_post = [select_class(t) for t in touches]
    theirs = eval(baseline("result"))  # a list of (class, confidence) pairs
    same = sum(p.kind == k for p, (k, _) in zip(ours_post, theirs, strict=True))
    worst = max(abs(p.confidence - c) for p, (_, c) in zip(ours_post, theirs, strict=True))
    ours_t, base_t = [], []
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        for t in touches:
            select_class(t)
        ours_t.append(time.perf_counter() - t0)
        base_t.append(float(baseline("time")))
    child.stdin.close()
    child.wait()
    Path(f.name).unlink()
    ratio = statistics.median(a / b for a, b in zip(ours_t, base_t, strict=True))
    print(
        f"{len(touches)} sets of touches from {len(fixed_suite())} plans; same class {same}/{len(touches)}, "
        f"largest confidence difference {worst:.3f}"
    )
    print(
        f"select_class over all: this tree {1000 * statistics.median(ours_t):.1f} ms "
        f"({'compiled' if args.compiled else 'numpy'}), baseline "
        f"{1000 * statistics.median(base_t):.1f} ms ({'kernels' if args.kernels else 'numpy'}), "
        f"median ratio {ratio:.2f}"
    )


if __name__ == "__main__":
    sys.exit(main())
