"""The board contract: agents declare what they read and write; the debug mode enforces it."""

from __future__ import annotations

import pytest

from eos_svc import (
    ActionResult,
    Agent,
    Board,
    BoardAccessError,
    BoardClient,
    Controller,
    EosError,
    Outcome,
    RunStatus,
    ValidationError,
)
from eos_svc.board_access import access_map, undeclared_entries
from eos_svc.demo import STAGES, Bisect, Done, Scan, Secant, Widen, default_problem, solve_root
from eos_svc.errors import BoardEntryError, ContractError


class Counter(Agent):
    """Reads ``limit`` in its test; its action adds one to ``count`` and writes ``extra`` when
    asked to (by the board)."""

    reads = frozenset({"limit", "count"})
    writes = frozenset({"count"})

    def opportunistic(self, board, ctx):
        return 1.0 if board.get("count", 0) < board["limit"] else 0.0

    def act(self, board, ctx):
        board.set("count", board.get("count", 0) + 1)
        if board.get("count") == 2 and "limit" in board and board["limit"] > 5:
            board.set("extra", True)  # undeclared
        if board["count"] >= board["limit"]:
            return ActionResult(Outcome.FINISHED, "counted", succeeded=True)
        return ActionResult(Outcome.PROGRESS, "one more")


class Peeker(Agent):
    """Declares nothing, yet reads ``limit`` in its precondition test."""

    def opportunistic(self, board, ctx):
        return 0.1 if board.get("limit") is None else 0.0

    def act(self, board, ctx):  # pragma: no cover - never chosen
        return ActionResult(Outcome.PROGRESS)


def test_agent_declares_nothing_by_default():
    assert Peeker.reads == frozenset() and Peeker.writes == frozenset()
    assert Counter("c", ["s"], 0.5).reads == {"limit", "count"}


def test_client_allows_declared_entries_and_names_agent_and_key_otherwise():
    board = Board({"limit": 3, "secret": 1})
    client = BoardClient(board, Counter("counter", ["s"], 0.5))
    assert client["limit"] == 3 and client.get("count") is None and "limit" in client
    client.set("count", 1)
    assert board["count"] == 1  # written through to the board
    assert sorted(client) == ["count", "limit"] and len(client) == 2  # "secret" is not visible
    assert client.snapshot() == {"limit": 3, "count": 1}
    for read in (lambda: client["secret"], lambda: client.get("secret"), lambda: "secret" in client):
        with pytest.raises(BoardAccessError) as info:
            read()
        err = info.value
        assert (err.agent, err.key, err.access) == ("counter", "secret", "read")
        assert err.field == "agents.counter.reads"
        assert "'counter' read board entry 'secret'" in err.reason
        assert isinstance(err, ContractError) and isinstance(err, TypeError) and isinstance(err, EosError)
    for write in (
        lambda: client.set("limit", 4),
        lambda: client.update({"limit": 4}),
        lambda: client.delete("limit"),
    ):
        with pytest.raises(BoardAccessError) as info:
            write()
        assert (info.value.key, info.value.access, info.value.field) == (
            "limit",
            "write",
            "agents.counter.writes",
        )
    assert board["limit"] == 3  # nothing undeclared was written
    with pytest.raises(ContractError):
        client.begin_cycle()


def test_client_writes_are_recorded_as_the_boards_changes():
    board = Board({"limit": 3})
    client = BoardClient(board, Counter("counter", ["s"], 0.5))
    board.begin_cycle()
    client.set("count", 1)
    client.delete("count")
    client.set("count", 2)
    (change,) = board.end_cycle()
    assert (change.key, change.new, change.created) == ("count", 2, True)


def test_checked_run_ends_in_error_naming_the_agent_and_the_undeclared_write():
    counter = Counter("counter", ["s"], 0.5)
    ok = Controller([counter], ["s"], check_access=True).run(Board({"limit": 3}))
    assert ok.status is RunStatus.COMPLETED and ok.cycles == 3
    broken = Controller([Counter("counter", ["s"], 0.5)], ["s"], check_access=True).run(Board({"limit": 9}))
    assert broken.status is RunStatus.ERROR
    assert broken.cycles == 2
    assert "agent 'counter' raised BoardAccessError" in broken.reason
    assert "wrote board entry 'extra'" in broken.reason
    # off by default: the same agents run unchecked
    unchecked = Controller([Counter("counter", ["s"], 0.5)], ["s"], max_cycles=20).run(Board({"limit": 9}))
    assert unchecked.status is RunStatus.COMPLETED and unchecked.cycles == 9


def test_checked_run_catches_an_undeclared_read_in_a_precondition_test():
    agents = [Counter("counter", ["s"], 0.5), Peeker("peeker", ["s"], 0.1)]
    result = Controller(agents, ["s"], check_access=True).run(Board({"limit": 3}))
    assert result.status is RunStatus.ERROR and result.cycles == 1
    assert "agent 'peeker' failed its rating: BoardAccessError" in result.reason
    assert "read board entry 'limit'" in result.reason
    assert Controller(agents, ["s"]).run(Board({"limit": 3})).status is RunStatus.COMPLETED


def test_entry_check_sees_every_write_and_its_error_names_agent_and_field():
    seen = []

    def small(key, value):
        seen.append((key, value))
        if value > 2:
            raise ContractError(f"board.{key}", f"must be ≤ 2, got {value}")

    result = Controller([Counter("counter", ["s"], 0.5)], ["s"], check_access=True, entry_check=small).run(
        Board({"limit": 3})
    )
    assert seen == [("count", 1), ("count", 2), ("count", 3)]
    assert result.status is RunStatus.ERROR
    assert "BoardEntryError: board.count: must be ≤ 2, got 3 (written by agent 'counter')" in result.reason
    with pytest.raises(BoardEntryError) as info:
        BoardClient(Board(), Counter("c", ["s"], 0.5), small).set("count", 5)
    assert (info.value.agent, info.value.key, info.value.field) == ("c", "count", "board.count")
    with pytest.raises(ValidationError) as bad:
        Controller([Counter("c", ["s"], 0.5)], ["s"], entry_check=small)
    assert bad.value.field == "entry_check"
    with pytest.raises(ValidationError) as bad:
        Controller([Counter("c", ["s"], 0.5)], ["s"], check_access="yes")
    assert bad.value.field == "check_access" and "must be a bool" in bad.value.reason


def test_demo_declares_its_entries_and_runs_identically_checked():
    checked, board = solve_root(default_problem(), check_access=True)
    plain, _ = solve_root(default_problem())
    assert checked.status is RunStatus.COMPLETED
    assert [(r.chosen, r.detail, r.changes) for r in checked.trace] == [
        (r.chosen, r.detail, r.changes) for r in plain.trace
    ]
    assert abs(board["root"] - 0.7390851332151607) < 1e-9
    f, tol = default_problem().f, 1e-10
    agents = [Scan(f), Widen(f), Bisect(f, tol), Secant(f, tol), Done(tol)]
    assert STAGES == ("bracket", "refine")
    assert access_map(agents) == {
        "best": (["bisect", "secant"], ["bisect", "secant", "done"]),
        "bracket": (["scan", "widen", "bisect", "secant"], ["widen", "bisect", "secant", "done"]),
        "interval": (["widen"], ["scan", "widen"]),
        "root": (["done"], []),
        "secant_gain": (["secant"], ["secant"]),
    }
    assert undeclared_entries(agents, {"best": 1, "bracket": 1, "interval": 1}) == ["root", "secant_gain"]
