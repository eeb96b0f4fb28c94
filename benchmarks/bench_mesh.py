"""Mesh objects against primitives of the same size: median plan time and their ratio.

    .venv/bin/python benchmarks/bench_mesh.py [--rounds 7]

Pairs planned alternately in this process, the same seeds, the fit's compiled kernels loaded
(a long-lived process's state), medians over the rounds:

- a box (50 × 60 × 50 mm) as the ``box`` primitive and as its triangle mesh given inline
  (``{"shape": "mesh", "vertices", "faces"}``: coal's BVH distances, the winding-number sign,
  trimesh's mass properties), resting on a table and floating;
- when pybullet is installed (``eos_svc[objects]``), pybullet's random object 500 on its table
  against a box of its bounding extents at the same pose (the mesh is planned on the convex
  hull of its touches, the box on its fit).

Goal: a mesh plan within 2× of the primitive's (median ratio).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).parent))

from eos_svc.agents import PlanRequest, plan
from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.schema.request import ObjectSpec, Table
from eos_svc.shape import kernels

SIZE = (0.05, 0.06, 0.05)
POSITION = (0.21, 0.02, 0.0)
TABLE = Table(-0.025)


def box_pair() -> tuple[ObjectSpec, ObjectSpec]:
    box = trimesh.creation.box(extents=SIZE)
    mesh = {"vertices": box.vertices.tolist(), "faces": box.faces.tolist()}
    return ObjectSpec("box", {"size": SIZE}, POSITION), ObjectSpec("mesh", mesh, POSITION)


def pybullet_pair() -> tuple[ObjectSpec, ObjectSpec, Table] | None:
    try:
        from eos_svc.experiments.pybullet_objects import random_object

        obj = random_object(500)
    except ValidationError:
        return None
    if obj is None or obj.table is None:
        return None
    mesh = make_object(obj.spec)
    extents = np.ptp(np.asarray(mesh.hull.vertices), axis=0)  # its own axes
    box = ObjectSpec("box", {"size": tuple(float(e) for e in extents)}, obj.spec.position, obj.spec.rpy)
    return box, obj.spec, obj.table


def timed(request: PlanRequest) -> tuple[float, str]:
    t0 = time.perf_counter()
    result = plan(request, keep_trace=False)
    return time.perf_counter() - t0, result.status


def compare(name: str, primitive: PlanRequest, mesh: PlanRequest, rounds: int) -> float:
    """Alternate the two plans ``rounds`` times; print and return the median ratio mesh/primitive."""
    timed(primitive), timed(mesh)  # warm-up: contexts, imports
    a, b, statuses = [], [], set()
    for _ in range(rounds):
        ta, sa = timed(primitive)
        tb, sb = timed(mesh)
        a.append(ta)
        b.append(tb)
        statuses.add((sa, sb))
    ma, mb = statistics.median(a), statistics.median(b)
    ratio = mb / ma
    print(
        f"{name:<42} primitive {ma * 1000:7.1f} ms   mesh {mb * 1000:7.1f} ms"
        f"   ratio {ratio:5.2f}x   statuses {sorted(statuses)}"
    )
    return ratio


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    kernels.load()
    box, mesh = box_pair()
    ratios = [
        compare(
            "box 50x60x50 mm on a table",
            PlanRequest(obj=box, table=TABLE),
            PlanRequest(obj=mesh, table=TABLE),
            args.rounds,
        ),
        compare("box 50x60x50 mm floating", PlanRequest(obj=box), PlanRequest(obj=mesh), args.rounds),
    ]
    pair = pybullet_pair()
    if pair is None:
        print("pybullet not installed: the random object's pair is skipped (pip install 'eos_svc[objects]')")
    else:
        pbox, pmesh, table = pair
        compare(
            "pybullet random 500 vs box of its extents",
            PlanRequest(obj=pbox, table=table),
            PlanRequest(obj=pmesh, table=table),
            args.rounds,
        )
    worst = max(ratios)
    print(
        f"goal: the box's mesh within 2x of the box (median ratio): worst {worst:.2f}x, met: {worst <= 2.0}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
