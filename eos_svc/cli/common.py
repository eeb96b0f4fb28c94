"""Argument helpers shared by the ``eos`` sub-commands."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import NoReturn

from eos_svc.errors import ValidationError
from eos_svc.ratings import Weights


def finite_float(text: str) -> float:
    """argparse type: a finite float (NaN and inf are rejected)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def float_in(low: float, high: float = math.inf, *, above: bool = False) -> Callable[[str], float]:
    """argparse type: a finite float ≥ ``low`` (> with ``above``) and ≤ ``high``."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if value < low or (above and value == low) or value > high:
            bound = f"{'>' if above else '≥'} {low:g}"
            if high < math.inf:
                bound = f"in {'(' if above else '['}{low:g}, {high:g}]"
            raise argparse.ArgumentTypeError(f"must be {bound}, got {text!r}")
        return value

    return parse


#: argparse type: a finite float > 0
positive_float = float_in(0.0, above=True)
#: argparse type: a finite float ≥ 0
non_negative_float = float_in(0.0)
#: argparse type: a float in [0, 1]
fraction = float_in(0.0, 1.0)


def int_at_least(minimum: int) -> Callable[[str], int]:
    """argparse type: an integer ≥ ``minimum`` (argparse names the option in its error)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be ≥ {minimum}, got {value}")
        return value

    return parse


def add_weight_arguments(parser: argparse.ArgumentParser) -> None:
    """--w-default / --w-opportunistic / --w-learned (must sum to 1)."""
    group = parser.add_argument_group("weights P(B_i) (each in [0, 1], summing to 1)")
    group.add_argument(
        "--w-default", type=finite_float, default=0.5, metavar="P", help="default weight (0.5)"
    )
    group.add_argument(
        "--w-opportunistic", type=finite_float, default=0.5, metavar="P", help="opportunistic weight (0.5)"
    )
    group.add_argument("--w-learned", type=finite_float, default=0.0, metavar="P", help="learned weight (0)")


def weights_from_args(args: argparse.Namespace) -> Weights:
    """Build the weights; a bad combination exits with status 2 and names the field."""
    try:
        return Weights(args.w_default, args.w_opportunistic, args.w_learned)
    except ValidationError as exc:
        fail(f"--w-*: {exc}")


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``eos: error: message`` to stderr and exit with ``code``."""
    print(f"eos: error: {message}", file=sys.stderr)
    raise SystemExit(code)
