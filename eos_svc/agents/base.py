"""What every grasp agent shares: the world it acts on and the run's ratios."""

from __future__ import annotations

from collections.abc import Iterable

from eos_svc.agent import Agent
from eos_svc.agents import keys
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board

SEARCH, INFO, GRASP = "search", "information", "grasping"
STAGES = (SEARCH, INFO, GRASP)


class GraspAgent(Agent):
    """An agent of the grasp planner: a core :class:`~eos_svc.agent.Agent` bound to a world."""

    def __init__(self, name: str, stages: Iterable[str], default: float, world: GraspWorld) -> None:
        super().__init__(name, stages, default)
        self.world = world

    @staticmethod
    def d_over_h(board: Board) -> float:
        """The estimated diameter over the hand height (0 when not known yet)."""
        value = board.get(keys.D_OVER_H)
        return 0.0 if value is None else float(value)
