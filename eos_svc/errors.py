"""Exceptions of eos_svc: one tree under :class:`EosError`, each keeping the standard base a caller
expects (``ValueError``, ``TypeError``, ``RuntimeError``); those about one input name its
``field`` and the ``reason``. Planning outcomes are never exceptions: they are a
:class:`~eos_svc.records.RunStatus`.
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
    """An agent read or wrote a board entry it does not declare (``Agent.reads`` / ``writes``),
    under ``Controller(..., check_access=True)``. Made by :meth:`undeclared`.

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
    """A board entry written with a value not of its declared type (when entries are checked);
    ``field``: the entry or the part at fault (``board.shape.confidence``).

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
    """An agent that cannot take part in this cycle (a remote agent late, gone or answering
    nonsense): it is skipped, or its action does not run, and the plan carries on."""
