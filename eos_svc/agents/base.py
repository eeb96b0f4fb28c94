"""What every grasp agent shares: the hand driver it acts through and the run's ratios."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from typing import Any

from eos_svc.agent import Agent, CycleContext
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys

SEARCH, INFO, GRASP = "search", "information", "grasping"
STAGES = (SEARCH, INFO, GRASP)


#: an agent's precondition test, ``(self, board, ctx) -> sub-rating or None``
PreconditionTest = Callable[[Any, Board, CycleContext], "float | None"]


def zero_at_stage_start(test: PreconditionTest) -> PreconditionTest:
    """Wrap a precondition test to give 0 at a stage's first cycle (paper §5: "at the beginning of
    a new stage all opportunistic sub-ratings are zero")."""

    @functools.wraps(test)
    def opportunistic(self: Any, board: Board, ctx: CycleContext) -> float | None:
        if ctx.stage_cycle == 0:
            return 0.0
        return test(self, board, ctx)

    return opportunistic


class GraspAgent(Agent):
    """An agent of the grasp planner: a core :class:`~eos_svc.agent.Agent` acting only through a
    hand driver (:class:`~eos_svc.drivers.protocol.HandDriver`). Each subclass's
    :meth:`opportunistic` is wrapped with :func:`zero_at_stage_start` (paper §5; the §4.1
    ablation and Fig. 3 depend on it)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        own = cls.__dict__.get("opportunistic")
        if own is not None:
            cls.opportunistic = zero_at_stage_start(own)  # type: ignore[assignment,method-assign]

    def __init__(self, name: str, stages: Iterable[str], default: float, world: HandDriver) -> None:
        super().__init__(name, stages, default)
        self.world = world

    @staticmethod
    def d_over_h(board: Board) -> float:
        """The estimated diameter over the hand height (0 when not known yet)."""
        value = board.get(keys.D_OVER_H)
        return 0.0 if value is None else float(value)
