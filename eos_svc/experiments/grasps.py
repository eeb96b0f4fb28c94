"""Grasps that hold: plan a suite of objects, validate every plan in Drake, compare verdicts.

Per object (:mod:`eos_svc.experiments.grasp_suite`, or pybullet's meshes:
:mod:`eos_svc.experiments.pybullet_objects`) and seed: plan (weights 0.5, 0.5), then simulate
the final grasp in Drake (:func:`eos_svc.validation.validate_grasp`); in the Drake world
(``--world drake``) ``held`` is the plan's own lift test instead. The summary and the goals:
:mod:`eos_svc.experiments.grasps_report`; the suites, the options and the figures:
``docs/validation.md``.

    eos experiment grasps [--quick | --held-back | --random N --draw-seed S] [--seeds N]
    eos experiment grasps --objects pybullet-random --ids 500-539 --table --seeds 1
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eos_svc.agents import PlanRequest, plan
from eos_svc.cli.common import int_at_least, positive_float
from eos_svc.cli.hands import add_hand_argument, chosen_hand
from eos_svc.drivers.worlds import WORLDS
from eos_svc.errors import ValidationError
from eos_svc.experiments.common import experiment_parser, with_progress, write_csv, write_json
from eos_svc.experiments.grasp_suite import (
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
from eos_svc.validation import SimulationError, validate_grasp
from eos_svc.validation.validate import MAX_SECONDS
from eos_svc.world.hand_context import HandContext

#: a Drake-world plan's wall-clock budget, s (the simulation runs at about real time)
DRAKE_DEADLINE_S = 600.0
#: the request options the command line sets, by their flag (``--noise`` is ``tactile_noise``)
SENSING_FLAGS = {"tactile_noise": "--noise", "encoder_noise": "--encoder-noise", "link_error": "--link-error"}


def plan_and_validate(
    obj: SuiteObject | WorldObject,
    seed: int,
    validation: dict[str, Any] | None,
    context: HandContext | None = None,
    options: dict[str, Any] | None = None,
    world: str = "kinematic",
) -> dict[str, Any]:
    """One run as a flat row: plan the object with ``seed`` (the hand of ``context``, default
    hand3x3; the request ``options``, e.g. ``tactile_noise``), say what the plan knew of the
    object (its postulate; the shape error: :func:`~eos_svc.experiments.recognition.surface_error`),
    then validate the final grasp with that hand (``held`` None when ``validation`` is None; in
    the Drake world, the plan's lift test)."""
    row: dict[str, Any] = {"object": obj.label, "shape": obj.spec.shape, "seed": seed}
    drake: dict[str, Any] = {"world": "drake", "deadline_s": DRAKE_DEADLINE_S} if world == "drake" else {}
    try:
        request = PlanRequest(
            obj=obj.spec, seed=seed, table=getattr(obj, "table", None), **{**drake, **(options or {})}
        )
        result = plan(request, keep_trace=False, context=context)
    except ValidationError as exc:  # the planner refuses the request: not a run
        refused = {"status": "rejected", "reason": str(exc), "refused_field": exc.field}
        return row | refused | {"good_grasp": None, "held": None}
    shape = result.shape or {}  # what the plan knew of the object
    guess, confidence = shape.get("class", "none"), float(shape.get("confidence", 0.0))
    error = surface_error(obj.spec, shape.get("object"), np.random.default_rng(result.seed))
    row |= {
        "postulate": guess,
        "class_right": guess == obj.spec.shape,
        "confidence": confidence,
        "shape_error": error if math.isfinite(error) else None,
        "touches": result.touches,
        "probes": result.probes,
        "grasped_unsure": "grasping" in result.cycles_per_stage and confidence < CONFIDENCE_RULE,
        "status": result.status,
        "reason": result.reason,
        "good_grasp": bool(result.good_grasp),
        "held": None,
        "epsilon": result.epsilon,
        "plan_time_s": result.wall_time_s,
    }
    if result.world is not None:
        lift = result.world.get("lift") or {}
        return row | {
            "held": bool(lift.get("held", False)),
            "object_moved_mm": result.world["object_moved_mm"],
            "lift": lift.get("why", "no lift test"),
            "real_time_factor": result.world["real_time_factor"],
        }
    if validation is None:
        return row
    try:
        check = validate_grasp(result, **validation, hand=None if context is None else context.hand)
    except SimulationError as exc:  # counted as not held, and said so
        return row | {
            "held": False,
            "validation_time_s": 0.0,
            "max_displacement_m": None,
            "dropped_along": "",
            "validation_reason": str(exc),
        }
    return row | {
        "held": bool(check.held),
        "validation_time_s": check.wall_time_s,
        "max_displacement_m": max(check.displacement_m.values()),
        "dropped_along": " ".join(o.direction for o in check.outcomes if not o.held),
        "validation_reason": check.reason,
    }


def run(
    objects: Sequence[SuiteObject | WorldObject] | None = None,
    seeds: int = 5,
    out: Path = Path("results/grasps"),
    name: str = "grasps",
    quiet: bool = False,
    validation: dict[str, Any] | None = None,
    hand: HandModel | None = None,
    options: dict[str, Any] | None = None,
    world: str = "kinematic",
) -> dict:
    """Plan every object over ``seeds`` seeds — a drawn object once, with its own seed — with the
    request ``options`` and ``hand`` (default hand3x3), and validate every plan in Drake with the
    ``validation`` arguments (None: plan only); write ``name``.json, .csv, ``name``_runs.csv and
    ``name``.png into ``out``."""
    objects = list(fixed_suite() if objects is None else objects)
    context = None if hand is None else HandContext.build(hand)

    def seeds_of(obj: SuiteObject | WorldObject) -> Sequence[int]:
        drawn = getattr(obj, "seed", None)  # a drawn object once, with its own seed
        return range(1, seeds + 1) if drawn is None else [drawn]

    jobs = [(obj, seed) for obj in objects for seed in seeds_of(obj)]
    runs = [
        plan_and_validate(o, seed, validation, context, options, world)
        for o, seed in with_progress(jobs, name, quiet)
    ]
    rows, totals = summarise(objects, runs)
    data = {
        "suite": name,
        "hand": "hand3x3" if hand is None else getattr(hand, "name", str(hand)),
        "seeds": seeds,
        "options": dict(options or {}),
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


def _fraction_pair(text: str) -> float:
    value = positive_float(text)
    if value > 1.5:
        raise argparse.ArgumentTypeError(f"must be a fraction of the hand's span ≤ 1.5, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of this experiment."""
    parser = experiment_parser("grasps", __doc__, "results/grasps")
    add = parser.add_argument
    add("--seeds", type=int_at_least(1), default=None, help="seeds per object (5; 2 with --quick)")
    add("--quick", action="store_true", help="a small subset: one object per class")
    add("--held-back", action="store_true", help="the seeded held-back suite instead of the fixed one")
    add("--random", type=int_at_least(1), metavar="N", help="a random draw of N objects instead")
    add("--draw-seed", type=int, default=1, help="the random draw's seed (1)")
    add(
        "--sizes",
        type=_fraction_pair,
        nargs=2,
        default=(0.15, 0.50),
        metavar=("LO", "HI"),
        help="the random draw's widths as fractions of the hand's span (0.15 0.5)",
    )
    add(
        "--poses",
        choices=("any", "resting"),
        help="the random draw's orientations: any, or turned to rest on a table "
        "(default: resting in the Drake world, whose object rests on a table; any otherwise)",
    )
    add("--objects", choices=("pybullet-random", "pybullet-named"), help="pybullet's meshes instead")
    add("--ids", default="0-9", help="the pybullet random objects' ids, A-B (0-9)")
    add("--table", action="store_true", help="the pybullet objects rest on a table")
    add("--no-validate", action="store_true", help="plan only: no Drake validation")
    add_hand_argument(parser)
    add("--noise", dest="tactile_noise", type=float, metavar="M", help="tactile noise (std, m; 0.0002)")
    add("--encoder-noise", type=float, metavar="RAD", help="the hand's joint-encoder noise (std, rad; 0)")
    add("--link-error", type=float, metavar="M", help="the hand's link-length error (std, m; 0)")
    add("--deadline", dest="deadline_s", type=positive_float, metavar="S", help="each plan's budget, s (10)")
    add("--world", choices=WORLDS, default="kinematic", help="where the plans run (kinematic)")
    add("--seconds", type=positive_float, default=1.5, help="Drake load time per direction, s (1.5)")
    return parser


def chosen_objects(args: argparse.Namespace) -> tuple[Sequence[SuiteObject | WorldObject], str]:
    """The objects the options ask for and the name of the experiment's files."""
    if args.objects == "pybullet-named":
        objects, name = named_objects(), "grasps_pybullet_named"
    elif args.objects == "pybullet-random":
        span = parse_ids(args.ids)
        objects, left = random_objects(span)
        name = f"grasps_pybullet_{span.start}_{span.stop - 1}"
        kept = f"{len(objects)} the hand can span, left out {left}"
        print(f"pybullet random objects {args.ids}: {kept}", file=sys.stderr)
    elif args.random is not None:
        lo, hi = args.sizes
        drawn = f"{args.random} objects, draw seed {args.draw_seed}"
        resting = (args.poses or ("resting" if args.world == "drake" else "any")) == "resting"
        drawn += ", resting poses" if resting else ""
        print(f"random draw: {drawn}, widths {lo:g}-{hi:g} of the span", file=sys.stderr)
        return random_draw(args.random, args.draw_seed, (lo, hi), resting=resting), "grasps_random"
    elif args.held_back:
        return held_back_suite(1 if args.quick else 3), "grasps_held_back"
    else:
        return (quick_suite() if args.quick else fixed_suite()), "grasps"
    if not args.table:
        return [o._replace(table=None) for o in objects], name
    return objects, name + "_table"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: ``eos experiment grasps [options]``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.seconds > MAX_SECONDS:
        parser.error(f"argument --seconds: must be ≤ {MAX_SECONDS:g}, got {args.seconds:g}")
    if args.sizes[0] > args.sizes[1]:
        parser.error(f"argument --sizes: LO must be ≤ HI, got {args.sizes[0]:g} {args.sizes[1]:g}")
    flags = {**SENSING_FLAGS, "deadline_s": "--deadline"}  # the request's fields the options set
    options = {key: getattr(args, key) for key in flags if getattr(args, key) is not None}
    try:  # the request checks every option, naming the field
        PlanRequest(**options)
        objects, name = chosen_objects(args)
    except ValidationError as exc:
        parser.error(f"argument {flags.get(exc.field, '--' + exc.field)}: {exc.reason}")
    hand = chosen_hand(args)
    name += "" if hand is None else f"_{hand.name}"
    name += "_drake" if args.world == "drake" else ""
    data = run(
        objects,
        args.seeds or (2 if args.quick else 5),
        args.out,
        name,
        validation=None if args.no_validate else {"seconds": args.seconds},
        hand=hand,
        options=options,
        world=args.world,
    )
    print(report(data))
    print(f"wrote {args.out}/{name}.json, {name}.csv, {name}_runs.csv, {name}.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
