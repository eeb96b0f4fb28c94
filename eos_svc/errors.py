"""Exceptions of eos_svc: one tree under :class:`EosError`.

Planning outcomes (stalled, cycle limit, ...) are never exceptions: they are a
:class:`~eos_svc.records.RunStatus`. Exceptions are for bad input, broken
contracts and failed computations. Every exception class of the package derives
from :class:`EosError` and keeps the standard base a caller would expect
(``ValueError`` for a bad value, ``TypeError`` for a value of the wrong kind,
``RuntimeError`` for a computation that failed), so both ``except EosError`` and
the usual ``except ValueError`` work. Those about one input name it: ``field``
(dotted name) and ``reason`` (words).
"""

from __future__ import annotations


class EosError(Exception):
    """Base class of every error raised by eos_svc."""


class FieldError(EosError):
    """An error about one named input.

    Attributes:
        field: dotted name of the offending field (``"weights.default"``).
        reason: why it is rejected, in words.
    """

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")

    def __str__(self) -> str:  # KeyError subclasses would repr() the message
        return f"{self.field}: {self.reason}"

    def to_dict(self) -> dict[str, str]:
        """JSON-friendly form (used by the CLI and the service's error replies)."""
        return {"field": self.field, "reason": self.reason}


class ValidationError(FieldError, ValueError):
    """A value given to eos_svc is not acceptable (``field``: what, ``reason``: why)."""


class ContractError(FieldError, TypeError):
    """A value of the wrong kind: an argument, or an object that breaks an interface's contract
    (e.g. an agent whose ``act`` does not return an ``ActionResult``)."""


class BoardAccessError(ContractError):
    """An agent read or wrote a board entry it does not declare (``Agent.reads`` /
    ``Agent.writes``); raised only when the controller checks board access
    (``Controller(..., check_access=True)``). Made by :meth:`undeclared`.

    Attributes:
        agent: the agent's name.
        key: the board entry.
        access: ``"read"`` or ``"write"``.
    """

    def __init__(self, field: str, reason: str, agent: str = "", key: str = "", access: str = "") -> None:
        super().__init__(field, reason)
        self.agent = agent
        self.key = key
        self.access = access

    @classmethod
    def undeclared(cls, agent: str, key: str, access: str, declared: frozenset[str]) -> BoardAccessError:
        """The error for ``agent`` reading (``access="read"``) or writing ``key`` undeclared."""
        attribute, verb = ("reads", "read") if access == "read" else ("writes", "wrote")
        return cls(
            f"agents.{agent}.{attribute}",
            f"agent {agent!r} {verb} board entry {key!r}, which is not in its {attribute} "
            f"(declared: {sorted(declared)})",
            agent,
            key,
            access,
        )


class BoardEntryError(ContractError):
    """A board entry written with a value that does not have the entry's declared type; raised
    only when the controller checks entries. ``field`` is the entry (``board.shape``) or the
    part of it at fault (``board.shape.confidence``).

    Attributes:
        agent: the agent that wrote it ("" when written outside a run).
        key: the board entry.
    """

    def __init__(self, field: str, reason: str, agent: str = "", key: str = "") -> None:
        super().__init__(field, reason)
        self.agent = agent
        self.key = key


class NotFoundError(FieldError, KeyError):
    """A name that is not there (an agent, a finger, a frame); ``field`` says which kind."""


class ComputationError(EosError, RuntimeError):
    """A computation that failed on acceptable input (a solver, a subprocess)."""


class AgentUnavailableError(EosError):
    """An agent that cannot take part in this cycle — a remote agent late, gone or answering
    nonsense. Raised from its precondition test, the agent rates 0 for the cycle and is skipped
    (the record says why); raised from its action, the cycle records that the action did not
    run and the plan carries on. Any other exception from an agent ends the run as ``error``."""
