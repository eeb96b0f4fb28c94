"""``eos experiment NAME [options]``: the paper's experiments and ours, on the real planner; each
has its own options (``--help``), writes JSON/CSV and PNG plots to ``--out`` and prints a summary.
"""

from __future__ import annotations

import argparse
import importlib

from eos_svc.shape import kernels

#: experiment name -> (module, help)
EXPERIMENTS = {
    "ablation": ("eos_svc.experiments.ablation", "paper §4.1: weights (1,0), (0,1), (0.5,0.5) and a sweep"),
    "ratio": ("eos_svc.experiments.ratio", "paper Fig. 3: grasp-stage cycles against d/h"),
    "accuracy": (
        "eos_svc.experiments.accuracy",
        "EP1 curvature accuracy: spheres, plane, cylinder, ellipsoid",
    ),
    "shapes": ("eos_svc.experiments.shapes", "every shape end to end: success and good-grasp rates"),
    "learning": ("eos_svc.experiments.learning", "paper §7: learned sub-rating on a stream with repeats"),
    "grasps": ("eos_svc.experiments.grasps", "a suite of objects planned and validated in Drake: held?"),
    "recognition": (
        "eos_svc.experiments.recognition",
        "knowing the object by touch: confusion, shape error, calibration, search length",
    ),
    "plugins": (
        "eos_svc.experiments.plugins",
        "a plug-in grasp agent: chosen when its grasps are better, passed over when worse",
    ),
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    names = ", ".join(f"{k} ({v[1]})" for k, v in EXPERIMENTS.items())
    parser.add_argument("experiment", choices=list(EXPERIMENTS), metavar="NAME", help=names)
    parser.add_argument("options", nargs=argparse.REMAINDER, help="the experiment's own options")


#: the experiments that run whole plans (the shape fit among them); ``accuracy`` runs EP1 alone
PLANNING = frozenset(EXPERIMENTS) - {"accuracy"}


def run(args: argparse.Namespace) -> int:
    # the fit's compiled kernels before the first plan (≈ 1.5 s from numba's cache; ≈ 11 s the
    # first time on a new install): an experiment plans many times, and its plan times count
    if args.experiment in PLANNING and not {"-h", "--help"} & set(args.options):
        kernels.load()
    module = importlib.import_module(EXPERIMENTS[args.experiment][0])
    return int(module.main(args.options))
