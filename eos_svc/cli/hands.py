"""``eos hands``: the registered hands, and the ``--hand NAME|FILE`` option other commands share.

eos hands                         # the shipped hands: fingers, joints, hand height, span
eos hands --hand my_hand.toml     # check a description file and show what it makes
eos hands --json
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from eos_svc.cli.common import fail

#: the hand a command uses when ``--hand`` is not given
DEFAULT_HAND = "hand3x3"


def add_hand_argument(
    group: argparse._ArgumentGroup | argparse.ArgumentParser, default: str = DEFAULT_HAND
) -> None:
    """``--hand NAME|FILE``: a registered hand (``eos hands``) or a description file (TOML)."""
    group.add_argument(
        "--hand",
        default=default,
        metavar="NAME|FILE",
        help=f"the hand: a registered name (eos hands) or a hand description file (.toml) ({default})",
    )


def load_or_fail(value: str) -> Any:
    """The hand ``--hand`` names (a :class:`~eos_svc.hands.DescribedHand`); exit 2 naming the
    option and the description's bad key."""
    from eos_svc.errors import ValidationError
    from eos_svc.hands import HandRegistry

    try:
        return HandRegistry().build(value)
    except ValidationError as exc:
        where = f"{value}: " if value.endswith(".toml") else ""
        fail(f"--hand: {where}{exc.field}: {exc.reason}")
        raise  # unreachable: fail() exits


def chosen_hand(args: argparse.Namespace) -> Any:
    """The hand of ``--hand``: ``None`` for the default hand (the planner's own, loaded once per
    process), else the described hand."""
    value = getattr(args, "hand", DEFAULT_HAND)
    return None if value == DEFAULT_HAND else load_or_fail(value)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--hand",
        action="append",
        metavar="FILE",
        default=[],
        help="also show (and check) this description file; repeatable",
    )
    parser.add_argument("--json", action="store_true", help="print the hands as JSON")


def hand_summary(hand: Any) -> dict[str, Any]:
    """What ``eos hands`` shows of a hand: derived from its model, nothing looked up."""
    from eos_svc.world.hand_context import hand_span

    return {
        "name": hand.name,
        "summary": hand.spec.summary,
        "source": str(hand.spec.source) if hand.spec.source else None,
        "fingers": {f: len(hand.description.finger(f).joints) for f in hand.finger_names},
        "opposing_finger": hand.opposing_finger,
        "joints": hand.nq,
        "hand_height_m": round(hand.hand_height, 4),
        "span_m": round(hand_span(hand), 4),
    }


def run(args: argparse.Namespace) -> int:
    from eos_svc.errors import ValidationError
    from eos_svc.hands import HandRegistry

    try:
        registry = HandRegistry()
        extra = [registry.add_file(path).name for path in args.hand]
    except ValidationError as exc:
        fail(f"--hand: {exc.field}: {exc.reason}")
        raise  # unreachable
    rows = []
    for name in registry.names:
        try:
            rows.append(hand_summary(registry.build(name)))
        except ValidationError as exc:
            fail(f"hand {name!r}: {exc.field}: {exc.reason}", code=1)
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    for row in rows:
        fingers = ", ".join(f"{f} ({n})" for f, n in row["fingers"].items())
        mark = " (from --hand)" if row["name"] in extra else ""
        print(f"{row['name']}{mark}: {row['summary']}")
        print(
            f"  fingers: {fingers}; opposing {row['opposing_finger']}; {row['joints']} joints; "
            f"hand height {row['hand_height_m'] * 1000:.1f} mm; span {row['span_m'] * 1000:.0f} mm"
        )
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(run(argparse.Namespace(hand=[], json=False)))
