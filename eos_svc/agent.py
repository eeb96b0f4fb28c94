"""The agent contract (paper §2.1, §3): a name, the stages it may act in, a *default* sub-rating
fixed at creation, an *opportunistic* one set every cycle from the state (its precondition test,
:meth:`Agent.opportunistic`, or the previous action's :attr:`ActionResult.ratings`), a *learned*
one, and an action (:meth:`Agent.act`) that reports its outcome."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, ClassVar, NamedTuple

from eos_svc.errors import ValidationError
from eos_svc.ratings import check_probability

if TYPE_CHECKING:
    from eos_svc.board import Board, BoardChange


class Outcome(str, Enum):
    """What an action achieved."""

    PROGRESS = "progress"  #: it did something; the stage goes on
    STAGE_COMPLETE = "stage_complete"  #: the stage's goal is reached: the next stage (or the run completes)
    FINISHED = "finished"  #: the agent ends the run (:attr:`ActionResult.succeeded` says how)
    CANNOT_ACT = "cannot_act"  #: the agent does not know what to do: the run stalls (paper §5)


@dataclass(frozen=True, slots=True)
class ActionResult:
    """The report of one action: its :class:`Outcome`, what it did in words (``detail``), the
    opportunistic sub-ratings it sets for other agents in the stage's next cycle (``ratings``:
    name -> [0, 1]) and, with ``FINISHED``, whether the run's goal was met (``succeeded``)."""

    outcome: Outcome
    detail: str = ""
    ratings: Mapping[str, float] = field(default_factory=dict)
    succeeded: bool | None = None


class CycleContext(NamedTuple):
    """What an agent may know of the controller's state in this cycle: ``seq`` (1-based), the
    ``stage`` and ``stage_cycle`` (0 at its start), the board changes (``events``) and the agent
    (``last_agent``) of the stage's previous cycle, and how often each agent ``acted`` in it."""

    seq: int
    stage: str
    stage_cycle: int
    events: tuple[BoardChange, ...]
    last_agent: str | None
    acted: Mapping[str, int]

    def changed(self, key: str) -> bool:
        """Whether the previous cycle wrote board entry ``key``."""
        return any(change.key == key for change in self.events)


# name the module of the named tuple's generated __new__, so that pdoc resolves its annotations
CycleContext.__new__.__module__ = __name__


class Agent(ABC):
    """Base class of every agent: subclasses implement :meth:`act`, and usually :meth:`opportunistic`.

    A subclass declares the board entries it reads (:attr:`reads`) and writes (:attr:`writes`),
    as py_trees' blackboard clients do; ``Controller(check_access=True)`` holds it to them.
    ``name`` is unique in a controller; ``default`` P(A|B_d) and ``learned`` P(A|B_l) are in
    [0, 1] (a ValidationError otherwise, or for an empty name or no stages).
    """

    __slots__ = ("_default", "_learned", "name", "stages")

    #: where the agent runs: ``"local"`` (in the controller's process) or ``"remote"`` (its
    #: test and action answered by another process); the cycle records carry it
    location: ClassVar[str] = "local"
    #: board entries this agent reads (a write needs :attr:`writes`; reading one back needs both)
    reads: ClassVar[frozenset[str]] = frozenset()
    #: board entries this agent writes or deletes
    writes: ClassVar[frozenset[str]] = frozenset()

    def __init__(self, name: str, stages: Iterable[str], default: float, learned: float = 0.0) -> None:
        if not isinstance(name, str) or not name:
            raise ValidationError("agents.name", f"must be a non-empty str, got {name!r}")
        self.name = name
        self.stages = frozenset(stages)
        if not self.stages:
            raise ValidationError(f"agents.{name}.stages", "must name at least one stage")
        self._default = check_probability(default, f"agents.{name}.default")
        self._learned = check_probability(learned, f"agents.{name}.learned")

    @property
    def default(self) -> float:
        """Default sub-rating P(A|B_d): fixed at creation."""
        return self._default

    @property
    def learned(self) -> float:
        """Learned sub-rating P(A|B_l) (paper §7); updated between runs by a learner."""
        return self._learned

    @learned.setter
    def learned(self, value: float) -> None:
        self._learned = check_probability(value, f"agents.{self.name}.learned")

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        """Precondition test: the opportunistic sub-rating in [0, 1] from the state, every cycle.

        ``None``: no opinion (what the previous action set, else 0). Raise
        :class:`~eos_svc.errors.AgentUnavailableError` to be skipped in this cycle."""
        return None

    def learned_rating(self, board: Board, ctx: CycleContext) -> float:
        """Learned sub-rating for this cycle; defaults to :attr:`learned`."""
        return self._learned

    @abstractmethod
    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        """Run the agent's action against the board and report the outcome."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, default={self._default})"
