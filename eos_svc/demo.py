"""A small non-grasping problem solved by the EOS core: find a root of f(x).

How another planner embeds the controller: stage ``bracket`` (``scan``, ``widen``), stage
``refine`` (``bisect``, ``secant``, ``done``), each agent declaring its ``reads`` / ``writes``
(``solve_root(..., check_access=True)`` holds them to it). The standard library and the core only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome
from eos_svc.board import Board
from eos_svc.controller import Controller, CycleCallback
from eos_svc.ratings import Weights
from eos_svc.records import RunResult

Function = Callable[[float], float]
STAGES = ("bracket", "refine")


class Scan(Agent):
    """Samples the interval on a grid once, looking for a sign change."""

    reads = frozenset({"interval"})
    writes = frozenset({"bracket"})

    def __init__(self, f: Function, samples: int = 8) -> None:
        super().__init__("scan", ["bracket"], default=0.9)
        self.f, self.samples = f, samples

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        lo, hi = board["interval"]
        xs = [lo + (hi - lo) * i / self.samples for i in range(self.samples + 1)]
        for a, b in pairwise(xs):
            if self.f(a) * self.f(b) <= 0.0:
                board.set("bracket", (a, b))
                return ActionResult(Outcome.STAGE_COMPLETE, f"sign change in [{a:.4g}, {b:.4g}]")
        return ActionResult(Outcome.PROGRESS, f"no sign change on {self.samples} samples")


class Widen(Agent):
    """Doubles the interval about its centre while no bracket is known."""

    reads = frozenset({"interval", "bracket"})
    writes = frozenset({"interval", "bracket"})

    def __init__(self, f: Function) -> None:
        super().__init__("widen", ["bracket"], default=0.5)
        self.f = f

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        # wanted once a scan of this stage has found no sign change, until one is found
        return 1.0 if ctx.acted.get("scan") and "bracket" not in board else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        lo, hi = board["interval"]
        mid, half = 0.5 * (lo + hi), hi - lo
        new_lo, new_hi = mid - half, mid + half
        board.set("interval", (new_lo, new_hi))
        if self.f(new_lo) * self.f(lo) <= 0.0:
            board.set("bracket", (new_lo, lo))
        elif self.f(hi) * self.f(new_hi) <= 0.0:
            board.set("bracket", (hi, new_hi))
        if "bracket" in board:
            return ActionResult(Outcome.STAGE_COMPLETE, f"bracket {board['bracket']}")
        return ActionResult(Outcome.PROGRESS, f"interval now [{new_lo:.4g}, {new_hi:.4g}]")


def converged(board: Board, tolerance: float) -> bool:
    """Whether the bracket is narrower than ``tolerance`` or a zero of f was hit."""
    a, b = board["bracket"]
    best = board.get("best")
    return (b - a) <= tolerance or (best is not None and best[1] == 0.0)


def _shrink(board: Board, f: Function, x: float) -> None:
    a, b = board["bracket"]
    fx = f(x)
    board.set("best", (x, fx))
    board.set("bracket", (a, x) if f(a) * fx <= 0.0 else (x, b))


class Bisect(Agent):
    """Halves the bracket: slow and sure."""

    reads = frozenset({"bracket", "best"})
    writes = frozenset({"bracket", "best"})

    def __init__(self, f: Function, tolerance: float) -> None:
        super().__init__("bisect", ["refine"], default=0.6)
        self.f, self.tolerance = f, tolerance

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 0.0 if converged(board, self.tolerance) else 0.5

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        a, b = board["bracket"]
        _shrink(board, self.f, 0.5 * (a + b))
        return ActionResult(Outcome.PROGRESS, f"bisected to {board['bracket']}")


class Secant(Agent):
    """Jumps to the secant root of the bracket; rated by its last gain."""

    reads = frozenset({"bracket", "best", "secant_gain"})
    writes = frozenset({"bracket", "best", "secant_gain"})

    def __init__(self, f: Function, tolerance: float) -> None:
        super().__init__("secant", ["refine"], default=0.4)
        self.f, self.tolerance = f, tolerance

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 0.0 if converged(board, self.tolerance) else board.get("secant_gain", 0.9)

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        a, b = board["bracket"]
        fa, fb = self.f(a), self.f(b)
        x = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        before = min(abs(fa), abs(fb))
        _shrink(board, self.f, x)
        after = abs(board["best"][1])
        gain = 1.0 if before == 0.0 else max(0.0, min(1.0, 1.0 - after / before))
        board.set("secant_gain", gain)
        return ActionResult(Outcome.PROGRESS, f"secant step to x={x:.6g}, |f| shrank by {gain:.0%}")


class Done(Agent):
    """Finishes the run once the bracket is narrower than the tolerance."""

    reads = frozenset({"bracket", "best"})
    writes = frozenset({"root"})

    def __init__(self, tolerance: float) -> None:
        super().__init__("done", ["refine"], default=0.1)
        self.tolerance = tolerance

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 1.0 if converged(board, self.tolerance) else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        a, b = board["bracket"]
        if not converged(board, self.tolerance):
            return ActionResult(
                Outcome.FINISHED, f"bracket {b - a:.3g} wider than tolerance", succeeded=False
            )
        x = board["best"][0] if "best" in board else 0.5 * (a + b)
        board.set("root", x)
        return ActionResult(Outcome.FINISHED, f"root at x={x:.10g}", succeeded=True)


@dataclass(frozen=True)
class RootProblem:
    """Find x with f(x) = 0 starting from ``interval``, to ``tolerance``."""

    f: Function
    interval: tuple[float, float] = (0.0, 1.0)
    tolerance: float = 1e-9


def solve_root(
    problem: RootProblem,
    weights: Weights | None = None,
    max_cycles: int = 200,
    callbacks: tuple[CycleCallback, ...] = (),
    check_access: bool = False,
) -> tuple[RunResult, Board]:
    """Solve ``problem`` with the EOS controller; returns the run result and the board
    (``check_access``: every agent touches only the board entries it declares)."""
    f = problem.f
    tol = problem.tolerance
    agents = [Scan(f), Widen(f), Bisect(f, tol), Secant(f, tol), Done(tol)]
    controller = Controller(
        agents,
        STAGES,
        weights or Weights(0.5, 0.5),
        max_cycles=max_cycles,
        callbacks=callbacks,
        check_access=check_access,
    )
    board = Board({"interval": problem.interval})
    return controller.run(board), board


def default_problem() -> RootProblem:
    """cos(x) = x on [2, 3] — the root (≈0.739) lies outside the first interval."""
    return RootProblem(lambda x: math.cos(x) - x, (2.0, 3.0), 1e-10)
