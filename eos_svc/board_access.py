"""Checked board access (``Controller(..., check_access=True)``): each agent sees the board through
a :class:`BoardClient` limited to its declared ``reads`` and ``writes``, as py_trees' blackboard
clients; :func:`access_map` lists, per entry, who writes and who reads it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any

from eos_svc.agent import Agent
from eos_svc.board import Board, BoardChange
from eos_svc.errors import BoardAccessError, BoardEntryError, ContractError

#: validates a value written to an entry: ``check(key, value)`` raises
#: :class:`~eos_svc.errors.ContractError` (``field``: which part, ``reason``: why) when it is wrong
EntryCheck = Callable[[str, Any], None]


class BoardClient(Board):
    """One agent's view of a :class:`~eos_svc.board.Board`, limited to its declared entries: a
    read outside ``reads`` or a write outside ``writes`` raises
    :class:`~eos_svc.errors.BoardAccessError`; writes go to the board (recorded as its changes),
    each value first passed to ``entry_check`` when given.
    """

    __slots__ = ("_board", "_check", "_name", "_reads", "_writes")

    def __init__(self, board: Board, agent: Agent, entry_check: EntryCheck | None = None) -> None:
        # no Board.__init__: every Board method is overridden to act on ``board``
        self._board = board
        self._name = agent.name
        self._reads = frozenset(agent.reads)
        self._writes = frozenset(agent.writes)
        self._check = entry_check

    def _readable(self, key: str) -> None:
        if key not in self._reads:
            raise BoardAccessError.undeclared(self._name, key, "read", self._reads)

    def _writable(self, key: str) -> None:
        if key not in self._writes:
            raise BoardAccessError.undeclared(self._name, key, "write", self._writes)

    # --- reads -------------------------------------------------------------------------
    def __getitem__(self, key: str) -> Any:
        self._readable(key)
        return self._board[key]

    def get(self, key: str, default: Any = None) -> Any:
        """The entry ``key`` (declared in ``reads``), or ``default`` when it does not exist."""
        self._readable(key)
        return self._board.get(key, default)

    def __contains__(self, key: object) -> bool:
        self._readable(str(key))
        return key in self._board

    def __iter__(self) -> Iterator[str]:
        return (key for key in self._board if key in self._reads)

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def snapshot(self) -> dict[str, Any]:
        """A shallow copy of the readable entries."""
        return {key: self._board[key] for key in self}

    # --- writes ------------------------------------------------------------------------
    def set(self, key: str, value: Any) -> None:
        """Write entry ``key`` (declared in ``writes``; its value checked when asked)."""
        self._writable(key)
        if self._check is not None:
            try:
                self._check(key, value)
            except ContractError as exc:
                raise BoardEntryError(
                    exc.field, f"{exc.reason} (written by agent {self._name!r})", self._name, key
                ) from None
        self._board.set(key, value)

    def delete(self, key: str) -> None:
        """Remove entry ``key`` (declared in ``writes``)."""
        self._writable(key)
        self._board.delete(key)

    # --- the controller's, not an agent's ----------------------------------------------
    def begin_cycle(self) -> None:
        """Not an agent's to call: raises :class:`~eos_svc.errors.ContractError`."""
        raise ContractError(f"agents.{self._name}", "an agent may not begin the board's cycle")

    def end_cycle(self) -> tuple[BoardChange, ...]:
        """Not an agent's to call: raises :class:`~eos_svc.errors.ContractError`."""
        raise ContractError(f"agents.{self._name}", "an agent may not end the board's cycle")

    def __repr__(self) -> str:
        return (
            f"BoardClient(agent={self._name!r}, reads={sorted(self._reads)}, writes={sorted(self._writes)})"
        )


def clients_for(
    board: Board, agents: Iterable[Agent], entry_check: EntryCheck | None = None
) -> dict[str, BoardClient]:
    """One :class:`BoardClient` per agent, by name."""
    return {agent.name: BoardClient(board, agent, entry_check) for agent in agents}


def access_map(agents: Iterable[Agent]) -> dict[str, tuple[list[str], list[str]]]:
    """Per board entry, sorted by name: (the agents that write it, those that read it), each
    in the agents' list order — from their declarations."""
    writers: dict[str, list[str]] = {}
    readers: dict[str, list[str]] = {}
    for agent in agents:
        for key in agent.writes:
            writers.setdefault(key, []).append(agent.name)
        for key in agent.reads:
            readers.setdefault(key, []).append(agent.name)
    return {key: (writers.get(key, []), readers.get(key, [])) for key in sorted({*writers, *readers})}


def undeclared_entries(agents: Iterable[Agent], entries: Mapping[str, Any]) -> list[str]:
    """The entries some agent declares that ``entries`` (name -> declared type) lacks."""
    return sorted(key for key in access_map(agents) if key not in entries)
