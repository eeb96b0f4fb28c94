"""The remote side: one agent served on Zenoh queryables (:mod:`~eos_svc.remote_agents.wire`).

The queryables' callbacks only put the query into a queue (they run in Zenoh's own thread and
must neither block nor call Zenoh); one worker thread of the server's takes each query, runs
the agent's test or action on a board made of the entries the query carries, and ends it with
exactly one ``reply`` or ``reply_err``. The agent sees only the entries it declares it reads;
what its action writes goes back in the reply, for the controller's side to check and apply.
"""

from __future__ import annotations

import json
import logging
import queue
import threading
from typing import Any

import zenoh

from eos_svc.agent import ActionResult, Agent
from eos_svc.board import Board
from eos_svc.ratings import check_probability
from eos_svc.remote_agents import wire
from eos_svc.service.session import direct_callback

log = logging.getLogger(__name__)

_JSON = zenoh.Encoding.APPLICATION_JSON


class AgentServer:
    """Serves ``agent`` under ``<prefix>/agent/<name>/...`` until :meth:`close`.

    Args:
        session: an open Zenoh session (not closed by :meth:`close`).
        agent: the agent to serve.
        namespace: optional namespace under ``eos/@v1``.
        name: the name it is served and rated under (default: ``agent.name``).
        default: the default sub-rating it declares (default: ``agent.default``).

    A context manager: ``with AgentServer(session, agent): ...``.
    """

    def __init__(
        self,
        session: zenoh.Session,
        agent: Agent,
        *,
        namespace: str | None = None,
        name: str | None = None,
        default: float | None = None,
    ) -> None:
        self.agent = agent
        self.name = wire.check_name(name if name is not None else agent.name)
        self.default = check_probability(agent.default if default is None else default, "default")
        self.prefix = wire.prefix(namespace)
        self._inbox: queue.SimpleQueue[zenoh.Query | None] = queue.SimpleQueue()
        self._entities: list[Any] = []
        self._worker = threading.Thread(target=self._serve, name=f"eos-agent-{self.name}", daemon=True)
        self._worker.start()
        #: this agent's keys -> the part each serves (a query on another key, e.g. a wildcard
        #: over several agents, is refused: it must name exactly one)
        self._parts = {wire.agent_key(self.prefix, self.name, part): part for part in wire.PARTS}
        for key in self._parts:
            self._entities.append(
                session.declare_queryable(key, direct_callback(self._inbox.put), complete=True)
            )
        # the token last: a proxy that sees it alive finds every queryable declared
        self._entities.append(
            session.liveliness().declare_token(wire.agent_key(self.prefix, self.name, wire.ALIVE))
        )
        self.served = 0  #: queries answered so far

    def describe(self) -> dict[str, Any]:
        """What ``describe`` replies: the agent's declarations."""
        return {
            "schema": wire.SCHEMA,
            "name": self.name,
            "stages": sorted(self.agent.stages),
            "default": self.default,
            "reads": sorted(self.agent.reads),
            "writes": sorted(self.agent.writes),
        }

    def close(self) -> None:
        """Undeclare the token and the queryables and stop the worker."""
        for entity in reversed(self._entities):
            try:
                entity.undeclare()
            except Exception:  # already gone with its session
                log.debug("undeclare failed", exc_info=True)
        self._entities.clear()
        self._inbox.put(None)
        self._worker.join(timeout=5.0)

    def __enter__(self) -> AgentServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the worker ------------------------------------------------------------------
    def _serve(self) -> None:
        while (query := self._inbox.get()) is not None:
            try:
                body = self._answer(query)
            except Exception as exc:
                reason = f"{type(exc).__name__}: {exc}"
                try:
                    query.reply_err(json.dumps({"reason": reason[:2000]}).encode(), encoding=_JSON)
                except Exception:
                    log.debug("reply_err failed", exc_info=True)
            else:
                try:
                    query.reply(query.key_expr, body, encoding=_JSON)
                except Exception:
                    log.debug("reply failed", exc_info=True)
            finally:
                self.served += 1
                query.drop()

    def _answer(self, query: zenoh.Query) -> bytes:
        """The reply's JSON bytes for one query (raises on anything wrong)."""
        part = self._parts.get(str(query.key_expr))
        if part is None:
            raise ValueError(f"a query must name exactly one agent's key, e.g. {next(iter(self._parts))}")
        if part == "describe":
            return wire.dumps(self.describe())
        payload = query.payload
        data = wire.loads(payload.to_bytes() if payload is not None else b"null")
        if not isinstance(data, dict) or data.get("schema") != wire.SCHEMA:
            raise ValueError(f"a query of schema {wire.SCHEMA} is expected")
        ctx = wire.ctx_from_json(data["ctx"])
        entries = data.get("board") or {}
        board = Board({k: v for k, v in entries.items() if k in self.agent.reads})
        if part == "rate":
            rating = self.agent.opportunistic(board, ctx)
            return wire.dumps({"rating": rating})
        if part == "act":
            board.begin_cycle()
            result = self.agent.act(board, ctx)
            changes = board.end_cycle()
            return wire.dumps(self._act_reply(result, changes))
        raise AssertionError(part)  # pragma: no cover - _parts holds the three parts only

    @staticmethod
    def _act_reply(result: ActionResult, changes: tuple) -> dict[str, Any]:
        return {
            "outcome": result.outcome.value,
            "detail": result.detail,
            "ratings": dict(result.ratings),
            "succeeded": result.succeeded,
            "writes": {c.key: c.new for c in changes if not c.removed},
            "deletes": [c.key for c in changes if c.removed],
        }
