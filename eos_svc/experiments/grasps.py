"""Grasps that hold: plan a suite of objects, validate every plan in Drake, compare verdicts.

For each object of the suite (:mod:`eos_svc.experiments.grasp_suite`) and each seed: plan
(weights 0.5, 0.5), then simulate the final grasp in Drake
(:func:`eos_svc.validation.validate_grasp`). Reports per object the success rate, the
good-grasp rate (the end agent's verdict), the Drake hold rate and the median plan time; over
the whole suite the confusion counts of ``good_grasp`` against Drake's ``held`` (the goal:
good grasps are held ≥ 98 %; :mod:`eos_svc.experiments.grasps_report`).

    eos experiment grasps                      # the fixed suite, 5 seeds
    eos experiment grasps --held-back          # the seeded held-back suite instead
    eos experiment grasps --quick --seeds 1    # one object per class
    eos experiment grasps --random 40 --draw-seed 3 [--sizes 0.15 0.5] [--no-validate]
                                               # a random draw: any class, size, pose
    eos experiment grasps --world drake        # plans in the Drake world: held = its lift test
    eos experiment grasps --hand trifinger     # another hand (eos hands) or a description file:
                                               # the same objects; those it cannot span are refused
    eos experiment grasps --objects pybullet-random --ids 500-539 --table --seeds 1
                                               # pybullet's random meshes, resting on a table
    eos experiment grasps --objects pybullet-named --table --seeds 3   # the mug, duck and teddy

The pybullet objects (``pip install 'eos_svc[objects]'``) are read from the installed package
and scaled and placed as :mod:`eos_svc.experiments.pybullet_objects` says; ``--table`` puts
the table under them (without it they float where they would rest).

In the Drake world (:mod:`eos_svc.drivers.drake_world`) every plan runs against the simulated
object on its table and ends with the lift test; ``held`` is that test's verdict (no separate
validation), and each run also records how far the object moved (mm) and the real-time factor.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import PlanRequest, plan
from eos_svc.cli.common import int_at_least, positive_float
from eos_svc.cli.hands import add_hand_argument, chosen_hand
from eos_svc.drivers.worlds import WORLDS
from eos_svc.errors import ValidationError
from eos_svc.experiments.common import experiment_parser, write_csv, write_json
from eos_svc.experiments.grasp_suite import (
    DrawnObject,
    SuiteObject,
    fixed_suite,
    held_back_suite,
    quick_suite,
    random_draw,
)
from eos_svc.experiments.grasps_report import CONFIDENCE_RULE, plot, report, summarise
from eos_svc.experiments.pybullet_objects import WorldObject, named_objects, parse_ids, random_objects
from eos_svc.experiments.recognition import surface_error
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import ObjectSpec
from eos_svc.schema.result import PlanResult
from eos_svc.validation import SimulationError, validate_grasp
from eos_svc.validation.validate import MAX_SECONDS
from eos_svc.world.hand_context import HandContext

#: a Drake-world plan's wall-clock budget, s (the simulation runs at about real time)
DRAKE_DEADLINE_S = 600.0


def recognition(spec: ObjectSpec, result: PlanResult) -> dict[str, Any]:
    """What the plan knew of the object: the postulated class, whether it is right, its
    confidence, the shape error (:func:`~eos_svc.experiments.recognition.surface_error`: RMS
    distance of the true surface to the postulated one over the true half extent), and the
    touches and probes it took."""
    shape = result.shape or {}
    guess = shape.get("class", "none")
    error = surface_error(spec, shape.get("object"), np.random.default_rng(result.seed))
    return {
        "postulate": guess,
        "class_right": guess == spec.shape,
        "confidence": float(shape.get("confidence", 0.0)),
        "shape_error": error if math.isfinite(error) else None,
        "touches": result.touches,
        "probes": result.probes,
        "grasped_unsure": "grasping" in result.cycles_per_stage
        and float(shape.get("confidence", 0.0)) < CONFIDENCE_RULE,
    }


def plan_and_validate(
    obj: SuiteObject | DrawnObject | WorldObject,
    seed: int,
    validation: dict[str, Any] | None,
    context: HandContext | None = None,
    options: dict[str, Any] | None = None,
    world: str = "kinematic",
) -> dict[str, Any]:
    """One run: plan the object with ``seed`` (with the hand of ``context``, default hand3x3, and
    the request ``options``, e.g. ``tactile_noise``), validate the final grasp with that hand
    (unless ``validation`` is None: then ``held`` is None); a flat row. In the Drake world
    (``world="drake"``) ``held`` is the plan's own lift test."""
    row: dict[str, Any] = {"object": obj.label, "shape": obj.spec.shape, "seed": seed}
    try:
        drake: dict[str, Any] = {"world": "drake", "deadline_s": DRAKE_DEADLINE_S} if world == "drake" else {}
        result = plan(
            PlanRequest(
                obj=obj.spec, seed=seed, table=getattr(obj, "table", None), **{**drake, **(options or {})}
            ),
            keep_trace=False,
            context=context,
        )
    except ValidationError as exc:  # the planner refuses the request: not a run
        return {
            **row,
            "status": "rejected",
            "reason": str(exc),
            "refused_field": exc.field,
            "good_grasp": None,
            "held": None,
        }
    row.update(recognition(obj.spec, result))

    def ended(held: bool | None, **more: Any) -> dict[str, Any]:
        return {
            **row,
            "status": result.status,
            "reason": result.reason,
            "good_grasp": bool(result.good_grasp),
            "held": held,
            "epsilon": result.epsilon,
            "plan_time_s": result.wall_time_s,
            **more,
        }

    if result.world is not None:
        lift = result.world.get("lift") or {}
        return ended(
            bool(lift.get("held", False)),
            object_moved_mm=result.world["object_moved_mm"],
            lift=lift.get("why", "no lift test"),
            real_time_factor=result.world["real_time_factor"],
        )
    if validation is None:
        return ended(None)
    try:
        check = validate_grasp(result, **validation, hand=None if context is None else context.hand)
    except SimulationError as exc:  # counted as not held, and said so
        return ended(
            False,
            validation_time_s=0.0,
            max_displacement_m=None,
            dropped_along="",
            validation_reason=str(exc),
        )
    return ended(
        bool(check.held),
        validation_time_s=check.wall_time_s,
        max_displacement_m=max(check.displacement_m.values()),
        dropped_along=" ".join(o.direction for o in check.outcomes if not o.held),
        validation_reason=check.reason,
    )


def run(
    objects: Sequence[SuiteObject | DrawnObject | WorldObject] | None = None,
    seeds: int = 5,
    out: Path = Path("results/grasps"),
    name: str = "grasps",
    quiet: bool = False,
    validation: dict[str, Any] | None = None,
    validate: bool = True,
    hand: HandModel | None = None,
    options: dict[str, Any] | None = None,
    world: str = "kinematic",
) -> dict:
    """Plan (and, with ``validate``, validate in Drake) every object over ``seeds`` seeds — a
    drawn object once, with its own seed — with the request ``options`` (e.g. ``tactile_noise``);
    write ``name``.json, .csv, ``name``_runs.csv and ``name``.png into ``out``. ``hand``: plan
    and validate with this hand (default hand3x3)."""
    objects = list(fixed_suite() if objects is None else objects)
    context = None if hand is None else HandContext.build(hand)
    checks = dict(validation or {}) if validate else None
    jobs = [
        (obj, seed)
        for obj in objects
        for seed in ([obj.seed] if isinstance(obj, DrawnObject) else range(1, seeds + 1))
    ]
    runs: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for obj, seed in jobs:
        runs.append(plan_and_validate(obj, seed, checks, context, options, world))
        if not quiet:
            elapsed = time.perf_counter() - t0
            print(
                f"\r{name}: {len(runs)}/{len(jobs)} plans{' validated' if validate else ''}, "
                f"{elapsed:.0f} s, ~{elapsed / len(runs) * (len(jobs) - len(runs)):.0f} s left "
                f"({obj.label})        ",
                end="",
                file=sys.stderr,
                flush=True,
            )
    if not quiet:
        print(file=sys.stderr)
    rows, totals = summarise(objects, runs)
    data = {
        "suite": name,
        "hand": "hand3x3" if hand is None else getattr(hand, "name", str(hand)),
        "seeds": seeds,
        "options": dict(options or {}),
        "validation": checks,
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


def _fraction_pair(text: str) -> float:
    value = positive_float(text)
    if value > 1.5:
        raise argparse.ArgumentTypeError(f"must be a fraction of the hand's span ≤ 1.5, got {text}")
    return value


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
        "--random",
        type=int_at_least(1),
        default=None,
        metavar="N",
        help="a random draw of N objects instead: any class, size, orientation, near the default position",
    )
    parser.add_argument("--draw-seed", type=int, default=1, help="the random draw's seed (1)")
    parser.add_argument(
        "--sizes",
        type=_fraction_pair,
        nargs=2,
        default=(0.15, 0.50),
        metavar=("LO", "HI"),
        help="the random draw's widths as fractions of the hand's span (0.15 0.5)",
    )
    parser.add_argument(
        "--objects",
        choices=("pybullet-random", "pybullet-named"),
        help="pybullet's meshes instead: its random objects (--ids) or the mug, duck and teddy",
    )
    parser.add_argument("--ids", default="0-9", help="the random objects' ids, A-B (0-9)")
    parser.add_argument("--table", action="store_true", help="the pybullet objects rest on a table")
    parser.add_argument("--no-validate", action="store_true", help="plan only: no Drake validation")
    add_hand_argument(parser)
    parser.add_argument(
        "--noise",
        type=float,
        default=None,
        metavar="M",
        help="the requests' tactile noise (standard deviation, m; default 0.0002)",
    )
    parser.add_argument(
        "--encoder-noise",
        type=float,
        default=None,
        metavar="RAD",
        help="the simulated hand's joint-encoder noise (standard deviation, rad; default 0)",
    )
    parser.add_argument(
        "--link-error",
        type=float,
        default=None,
        metavar="M",
        help="the simulated hand's link-length calibration error (standard deviation, m; default 0)",
    )
    parser.add_argument(
        "--deadline",
        type=positive_float,
        default=None,
        metavar="S",
        help="the requests' wall-clock budget per plan (s; default 10): more on a loaded machine",
    )
    parser.add_argument(
        "--world",
        choices=WORLDS,
        default="kinematic",
        help="where the plans run: kinematic, or drake (held = the plan's own lift test) (kinematic)",
    )
    parser.add_argument(
        "--seconds", type=positive_float, default=1.5, help="Drake load time per direction, s (1.5)"
    )
    return parser


def _pybullet(which: str, ids: str, table: bool) -> tuple[list[WorldObject], str]:
    """The pybullet objects asked for (on their table, or floating without ``table``)."""
    if which == "pybullet-named":
        objects, name = named_objects(), "grasps_pybullet_named"
    else:
        span = parse_ids(ids)
        objects, left = random_objects(span)
        name = f"grasps_pybullet_{span.start}_{span.stop - 1}"
        print(
            f"pybullet random objects {ids}: {len(objects)} the hand can span, left out {left}",
            file=sys.stderr,
        )
    if not table:
        return [o._replace(table=None) for o in objects], name
    return objects, name + "_table"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment grasps [options]``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.seconds > MAX_SECONDS:
        parser.error(f"argument --seconds: must be ≤ {MAX_SECONDS:g}, got {args.seconds:g}")
    lo, hi = args.sizes
    if lo > hi:
        parser.error(f"argument --sizes: LO must be ≤ HI, got {lo:g} {hi:g}")
    seeds = args.seeds or (2 if args.quick else 5)
    objects: Sequence[SuiteObject | DrawnObject | WorldObject]
    if args.objects is not None:
        try:
            objects, name = _pybullet(args.objects, args.ids, args.table)
        except ValidationError as exc:
            parser.error(f"argument --{exc.field}: {exc.reason}")
    elif args.random is not None:
        objects, name = random_draw(args.random, args.draw_seed, (lo, hi)), "grasps_random"
        print(
            f"random draw: {args.random} objects, draw seed {args.draw_seed}, "
            f"widths {lo:g}-{hi:g} of the span",
            file=sys.stderr,
        )
    elif args.held_back:
        objects, name = held_back_suite(1 if args.quick else 3), "grasps_held_back"
    else:
        objects, name = (quick_suite() if args.quick else fixed_suite()), "grasps"
    hand = chosen_hand(args)
    if hand is not None:
        name = f"{name}_{hand.name}"
    options: dict[str, Any] = {}
    flags = {"tactile_noise": "--noise", "encoder_noise": "--encoder-noise", "link_error": "--link-error",
             "deadline_s": "--deadline"}  # fmt: skip
    for key, flag in flags.items():
        value = getattr(args, flag[2:].replace("-", "_"))
        if value is not None:
            options[key] = value
    try:  # the request checks every option, naming the field
        PlanRequest(**options)
    except ValidationError as exc:
        parser.error(f"argument {flags[exc.field]}: {exc.reason}")
    if args.world == "drake":
        name += "_drake"
    data = run(
        objects,
        seeds,
        args.out,
        name,
        validation={"seconds": args.seconds},
        validate=not args.no_validate,
        hand=hand,
        options=options,
        world=args.world,
    )
    print(report(data))
    print(f"wrote {args.out}/{name}.json, {name}.csv, {name}_runs.csv, {name}.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
