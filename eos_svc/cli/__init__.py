"""The ``eos`` command line: one module per sub-command (``add_arguments(parser)``, ``run(args) -> int``),
imported only when its command runs (a fast ``--help``; one broken optional dependency breaks one command).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

#: command name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "plan": ("eos_svc.cli.plan", "plan one grasp on a scene and print the cycle trace"),
    "hands": ("eos_svc.cli.hands", "list the registered hands (and check hand description files)"),
    "replay": ("eos_svc.cli.replay", "replay a recorded plan and check it is deterministic"),
    "validate": ("eos_svc.cli.validate", "simulate a planned grasp in Drake: does it hold the object?"),
    "ep1": ("eos_svc.cli.ep1", "run EP1 alone: roll a fingertip and estimate curvature"),
    "experiment": ("eos_svc.cli.experiment", "run one of the paper's experiments"),
    "serve": ("eos_svc.cli.serve", "run the planner as a Zenoh service"),
    "client": ("eos_svc.cli.client", "request a plan from a running service"),
    "demo": ("eos_svc.cli.demo", "the domain-free controller on a small example"),
    "batch": ("eos_svc.cli.batch", "plan a dataset as Ray tasks, rows streamed to Parquet"),
}


def build_parser() -> argparse.ArgumentParser:
    """Top-level parser with one sub-parser per command (arguments added lazily)."""
    parser = argparse.ArgumentParser(prog="eos", description="Enhanced Opportunistic System grasp planner")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_module, help_text) in COMMANDS.items():
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``eos`` console script; returns the process exit code."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in {"-h", "--help"} or args[0] not in COMMANDS:
        parser = build_parser()
        if args and args[0] not in {"-h", "--help"}:
            parser.error(f"unknown command {args[0]!r}; choose from {', '.join(COMMANDS)}")
        parser.print_help()
        return 0 if args else 2
    name = args[0]
    module_name, help_text = COMMANDS[name]
    module = importlib.import_module(module_name)
    parser = argparse.ArgumentParser(prog=f"eos {name}", description=help_text)
    module.add_arguments(parser)
    parsed = parser.parse_args(args[1:])
    try:
        return int(module.run(parsed))
    except BrokenPipeError:  # output piped into e.g. `head`: stop quietly
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - swallow the flush at exit
        return 0
    except KeyboardInterrupt:
        print("eos: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
