"""The controller's side of a remote agent: an :class:`~eos_svc.agent.Agent` whose test and
action are answered over Zenoh (:mod:`~eos_svc.remote_agents.wire`).

Every cycle the proxy sends the cycle's context and the board entries the agent declares it
reads, and waits at most ``timeout_s`` for the reply. When the agent cannot take part it raises
:class:`~eos_svc.errors.AgentUnavailableError` — the controller then rates it 0 and skips it in
that cycle, the reason in the cycle record (controller rule 5):

- **gone**: its liveliness token is dropped (its process died or closed its session) — known
  without a query;
- **gone**, too, when a query ends with no reply before its timeout (no queryable matches);
- **late**: no reply within ``timeout_s`` (a frozen or overloaded process);
- **misbehaving**: an error reply, a reply that is not the protocol's JSON, a rating outside
  [0, 1], an unknown outcome, or a board write outside its declared ``writes`` or of the wrong
  type (``entry_check``) — the writes are checked, all of them, before any is applied.

An agent whose *action* failed, or whose rating came late in :data:`LATE_LIMIT` cycles in a
row, sits out the rest of the plan (a plan's first cycle, ``seq`` 1, brings it back), so a broken
action cannot be chosen cycle after cycle nor a frozen process cost the deadline every cycle.
A proxy serves one plan at a time (plans run one after another may share it; concurrent plans
each need their own).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Mapping
from typing import Any

import zenoh

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome
from eos_svc.board import Board
from eos_svc.errors import AgentUnavailableError, ComputationError, ContractError, ValidationError
from eos_svc.ratings import check_probability
from eos_svc.remote_agents import wire
from eos_svc.schema.board_entries import check_entry

#: checks a value written to an entry (raises ContractError); the grasp planner's by default
EntryCheck = Callable[[str, Any], None]
#: the default wait for a remote agent's reply each cycle (s)
DEFAULT_TIMEOUT_S = 0.05
#: ratings late in this many cycles in a row bench the agent for the rest of the plan (a frozen
#: process holds its liveliness token until its lease ends: 10 s by default)
LATE_LIMIT = 3


class RemoteAgent(Agent):
    """A proxy for the agent served under ``<prefix>/agent/<name>``; made by :meth:`connect`.

    Args:
        session: an open Zenoh session that reaches the agent (not closed by :meth:`close`).
        description: the agent's ``describe`` reply (name, stages, default, reads, writes).
        namespace: optional namespace under ``eos/@v1``.
        timeout_s: the longest wait for a reply each cycle (s).
        entry_check: validates every value it writes before it is applied (default: the grasp
            planner's declared entry types, :func:`eos_svc.schema.board_entries.check_entry`);
            ``None``: the declared keys only.
    """

    location = "remote"

    def __init__(
        self,
        session: zenoh.Session,
        description: Mapping[str, Any],
        *,
        namespace: str | None = None,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        entry_check: EntryCheck | None = check_entry,
    ) -> None:
        name = wire.check_name(description.get("name"), "describe.name")
        stages = description.get("stages")
        if not isinstance(stages, list) or not all(isinstance(s, str) for s in stages):
            raise ValidationError(f"agents.{name}.stages", f"must be a list of stage names, got {stages!r}")
        super().__init__(name, stages, description.get("default"))  # type: ignore[arg-type]
        for kind in ("reads", "writes"):
            keys = description.get(kind)
            if not isinstance(keys, list) or not all(isinstance(k, str) and k for k in keys):
                raise ValidationError(f"agents.{name}.{kind}", f"must be a list of entry names, got {keys!r}")
            self.__dict__[kind] = frozenset(keys)  # this instance's declarations (the class has none)
        if not (isinstance(timeout_s, (int, float)) and 0.0 < timeout_s <= 60.0):
            raise ValidationError("timeout_s", f"must be in (0, 60] s, got {timeout_s!r}")
        self.timeout_s = float(timeout_s)
        self.entry_check = entry_check
        self.session = session
        pfx = wire.prefix(namespace)
        self._rate_key = wire.agent_key(pfx, name, "rate")
        self._act_key = wire.agent_key(pfx, name, "act")
        self._alive = True
        self._benched: str | None = None  # why it sits out the rest of the plan
        self._late = 0  # cycles in a row its rating came late
        self._token = session.liveliness().declare_subscriber(
            wire.agent_key(pfx, name, wire.ALIVE), history=True
        )
        self.last_act_s = 0.0  #: seconds its last action's round trip took

    @classmethod
    def connect(
        cls,
        session: zenoh.Session,
        name: str,
        *,
        namespace: str | None = None,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        connect_timeout_s: float = 2.0,
        entry_check: EntryCheck | None = check_entry,
    ) -> RemoteAgent:
        """Ask the agent served as ``name`` for its declarations and make its proxy.

        Raises:
            ComputationError: no agent of that name answers within ``connect_timeout_s``.
            ValidationError: its declarations are not valid (naming the field).
        """
        key = wire.agent_key(wire.prefix(namespace), name, "describe")
        give_up = time.monotonic() + connect_timeout_s
        # asked again until the deadline: a session just connected may not route the query yet
        while (left := give_up - time.monotonic()) > 0.0:
            for reply in session.get(key, timeout=left):
                if reply.ok is not None:
                    description = wire.loads(reply.ok.payload.to_bytes())
                    if not isinstance(description, dict) or description.get("schema") != wire.SCHEMA:
                        raise ValidationError(
                            "describe", f"agent {name!r} does not speak schema {wire.SCHEMA}"
                        )
                    if description.get("name") != name:
                        raise ValidationError(
                            "describe.name",
                            f"the agent served as {name!r} says it is {description.get('name')!r}",
                        )
                    return cls(
                        session,
                        description,
                        namespace=namespace,
                        timeout_s=timeout_s,
                        entry_check=entry_check,
                    )
            time.sleep(min(0.02, max(0.0, give_up - time.monotonic())))
        raise ComputationError(f"no remote agent {name!r} answers on {key} within {connect_timeout_s} s")

    def close(self) -> None:
        """Stop following its liveliness token."""
        self._token.undeclare()

    # --- the agent contract ------------------------------------------------------------
    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        if ctx.seq == 1:
            self._benched, self._late = None, 0  # a new plan
        self._check_alive()
        if self._benched is not None:
            raise AgentUnavailableError(self._benched)
        try:
            data = self._ask(self._rate_key, board, ctx)
        except AgentUnavailableError as exc:
            self._late = self._late + 1 if str(exc).startswith("late") else 0
            if self._late >= LATE_LIMIT:
                self._benched = f"late in {LATE_LIMIT} cycles in a row; it sits out the rest of the plan"
            raise
        self._late = 0
        rating = data.get("rating")
        if rating is None:
            return None
        try:
            return check_probability(rating, f"agents.{self.name}.opportunistic")
        except ValidationError as exc:
            raise AgentUnavailableError(f"misbehaving: its rating {exc.reason}") from None

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        started = time.perf_counter()
        try:
            self._check_alive()
            data = self._ask(self._act_key, board, ctx)
            result, writes, deletes = self._checked_action(data)
        except AgentUnavailableError as exc:
            self._benched = f"its action failed in cycle {ctx.seq} ({exc}); it sits out the rest of the plan"
            raise
        for key, value in writes.items():  # every write checked above: now applied
            board.set(key, value)
        for key in deletes:
            board.delete(key)
        self.last_act_s = time.perf_counter() - started
        detail = f"{result.detail} [remote, {self.last_act_s * 1000:.1f} ms]"
        return ActionResult(result.outcome, detail, result.ratings, result.succeeded)

    # --- the wire ----------------------------------------------------------------------
    def _check_alive(self) -> None:
        """Follow its liveliness token (non-blocking); raise when it is gone."""
        while (sample := self._token.try_recv()) is not None:
            self._alive = sample.kind == zenoh.SampleKind.PUT
        if not self._alive:
            raise AgentUnavailableError("gone: its liveliness token was dropped (process dead or closed)")

    def _ask(self, key: str, board: Board, ctx: CycleContext) -> dict[str, Any]:
        """Send a query with the cycle's context and the entries it reads; its reply's JSON."""
        entries = {k: board[k] for k in self.reads if k in board}
        payload = wire.query_payload(ctx, entries)
        part = key.rsplit("/", 1)[-1]
        started = time.perf_counter()
        for reply in self.session.get(key, payload=payload, timeout=self.timeout_s):
            if reply.err is not None:
                raw = reply.err.payload.to_bytes()
                if raw == b"Timeout":  # Zenoh's own error reply when the query times out
                    break
                raise AgentUnavailableError(f"misbehaving: its {part} failed: {_reason(raw)}")
            try:
                data = wire.loads(reply.ok.payload.to_bytes())
            except (ValueError, UnicodeDecodeError):
                raise AgentUnavailableError(f"misbehaving: its {part} reply is not JSON") from None
            if not isinstance(data, dict):
                raise AgentUnavailableError(f"misbehaving: its {part} reply is not a JSON object")
            return data
        waited = time.perf_counter() - started
        if waited < 0.9 * self.timeout_s:  # the query ended before its timeout: nobody serves it
            raise AgentUnavailableError(f"gone: nothing answers its {part} queries ({key})")
        raise AgentUnavailableError(f"late: no {part} reply within {self.timeout_s * 1000:.0f} ms")

    def _checked_action(self, data: dict[str, Any]) -> tuple[ActionResult, dict[str, Any], list[str]]:
        """The action's result and its writes, every part checked before anything is applied."""
        try:
            outcome = Outcome(data.get("outcome"))
        except ValueError:
            raise AgentUnavailableError(f"misbehaving: unknown outcome {data.get('outcome')!r}") from None
        detail = data.get("detail", "")
        ratings = data.get("ratings") or {}
        succeeded = data.get("succeeded")
        writes = data.get("writes") or {}
        deletes = data.get("deletes") or []
        if (
            not isinstance(detail, str)
            or not isinstance(ratings, dict)
            or succeeded not in (None, True, False)
        ):
            raise AgentUnavailableError("misbehaving: detail, ratings or succeeded of the wrong type")
        if not isinstance(writes, dict) or not isinstance(deletes, list):
            raise AgentUnavailableError("misbehaving: writes must be an object and deletes a list")
        undeclared = sorted(str(k) for k in [*writes, *deletes] if k not in self.writes)
        if undeclared:
            raise AgentUnavailableError(
                f"misbehaving: it wrote entries {undeclared} it does not declare "
                f"(writes: {sorted(self.writes)})"
            )
        if self.entry_check is not None:
            for key, value in writes.items():
                try:
                    self.entry_check(key, value)
                except ContractError as exc:
                    raise AgentUnavailableError(f"misbehaving: {exc.field}: {exc.reason}") from None
        try:
            checked = {t: check_probability(v, f"ratings.{t}") for t, v in ratings.items()}
        except ValidationError as exc:
            raise AgentUnavailableError(f"misbehaving: {exc.field}: {exc.reason}") from None
        return ActionResult(outcome, detail, checked, succeeded), writes, [str(k) for k in deletes]


def _reason(payload: bytes) -> str:
    """The ``reason`` of an error reply, or its first bytes."""
    try:
        data = json.loads(payload)
        if isinstance(data, dict) and isinstance(data.get("reason"), str):
            return str(data["reason"])[:500]
    except ValueError:
        pass
    return repr(payload[:200])
