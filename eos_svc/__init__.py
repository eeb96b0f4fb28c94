"""eos_svc — an Enhanced Opportunistic System (EOS) grasp planner.

The package root is the paper's Figure 1, domain-free (no Pinocchio, coal, Drake or Zenoh): the
:class:`Board`, the :class:`Agent` contract, the :class:`Weights` and the :class:`Controller`
with its cycle records. The grasping domain: :mod:`eos_svc.agents`; the service: :mod:`eos_svc.service`.
"""

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome
from eos_svc.board import Board, BoardChange
from eos_svc.board_access import BoardClient
from eos_svc.controller import CancelToken, Controller, CycleCallback, RepeatPolicy
from eos_svc.errors import AgentUnavailableError, BoardAccessError, EosError, ValidationError
from eos_svc.ratings import Weights, check_probability
from eos_svc.records import AgentRating, CycleRecord, RunResult, RunStatus, to_jsonable

__version__ = "0.1.0"

__all__ = [
    "ActionResult",
    "Agent",
    "AgentRating",
    "AgentUnavailableError",
    "Board",
    "BoardAccessError",
    "BoardChange",
    "BoardClient",
    "CancelToken",
    "Controller",
    "CycleCallback",
    "CycleContext",
    "CycleRecord",
    "EosError",
    "Outcome",
    "RepeatPolicy",
    "RunResult",
    "RunStatus",
    "ValidationError",
    "Weights",
    "__version__",
    "check_probability",
    "to_jsonable",
]
