"""A remote agent's cost per cycle vs a bare Zenoh get→reply of the same sizes, same run.

    .venv/bin/python benchmarks/bench_remote_agent.py [--n 400]

A second process serves post_shape as the remote agent ``remote_post_shape``
(:class:`eos_svc.remote_agents.AgentServer`) and, on the same session, a bare queryable that
answers every get from its own thread with a reply of the size asked for (the same queue and
worker the agent server uses, no JSON, no agent). This process takes the information stage's
board of a real plan (seed 1, after EP2's touches: the entries post_shape reads) and, interleaved
in one loop, times:

- ``rate``: ``RemoteAgent.opportunistic`` — what the controller pays every cycle the agent is
  allowed in (encode the context and the entries it reads, get, wait, parse, check);
- ``act``: ``RemoteAgent.act`` on a fresh board — a cycle in which it is chosen (its writes
  checked against its declared entries and types, then applied);
- a bare get→reply with the same query and reply sizes for each.

Medians over ``--n`` rounds (the first tenth dropped as warm-up); the ratio is the remote
agent's median over the bare one's. Goal: ≤ 2×.
"""

from __future__ import annotations

import argparse
import queue
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, ClassVar

import zenoh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome  # noqa: E402
from eos_svc.board import Board  # noqa: E402
from eos_svc.remote_agents import AgentServer, RemoteAgent, wire  # noqa: E402
from eos_svc.service.session import direct_callback, free_port, loopback, make_config  # noqa: E402

BARE = "eos/@v1/bench/bare"


def serve(port: int) -> None:
    """``--serve``: the remote agent and the bare queryable, until stdin closes."""
    from eos_svc.agents.planner import build_world
    from eos_svc.agents.post_shape import PostShapeAgent
    from eos_svc.schema.request import PlanRequest

    agent = PostShapeAgent(0.75, build_world(PlanRequest()))
    entries, ctx = information_board()
    board = Board(entries)
    board.begin_cycle()
    agent.act(board, ctx)
    writer = ShapeWriter({c.key: c.new for c in board.end_cycle()})
    session = zenoh.open(make_config(listen=[loopback(port)]))
    inbox: queue.SimpleQueue[zenoh.Query | None] = queue.SimpleQueue()

    def answer() -> None:
        while (query := inbox.get()) is not None:
            size = int(str(query.key_expr).rsplit("/", 1)[-1])
            query.reply(query.key_expr, b"x" * size)
            query.drop()

    threading.Thread(target=answer, daemon=True).start()
    bare = session.declare_queryable(f"{BARE}/*", direct_callback(inbox.put), complete=True)
    with AgentServer(session, agent, name="remote_post_shape"), AgentServer(session, writer):
        print("serving", flush=True)
        sys.stdin.read()
    bare.undeclare()
    inbox.put(None)
    session.close()


class ShapeWriter(Agent):
    """Writes what post_shape wrote on the benchmark's board, at once: post_shape's action
    without its fit (the mechanism's cost, not the agent's)."""

    reads: ClassVar[frozenset[str]] = frozenset(
        {"curvature", "ep1_contact", "approach", "ep2_touches", "ep2_free"}
    )
    writes: ClassVar[frozenset[str]] = frozenset({"shape", "d_over_h"})

    def __init__(self, values: dict[str, Any]) -> None:
        super().__init__("shape_writer", ["information"], 0.75)
        self.values = values

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        board.update(self.values)
        return ActionResult(Outcome.PROGRESS, "wrote the postulate")


class Snapshot(Agent):
    """A local plug-in that keeps the last information-stage board post_shape would read."""

    reads: ClassVar[frozenset[str]] = frozenset(
        {"curvature", "ep1_contact", "approach", "ep2_touches", "ep2_free"}
    )

    def __init__(self, world: Any) -> None:
        super().__init__("snapshot", ["information"], 0.0)
        self.kept: tuple[dict[str, Any], CycleContext] | None = None

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        if "ep2_touches" in board:
            self.kept = ({k: board[k] for k in self.reads if k in board}, ctx)
        return 0.0

    def act(self, board: Board, ctx: CycleContext) -> Any:  # never chosen (rated 0, default 0)
        raise AssertionError("not an acting agent")


def information_board() -> tuple[dict[str, Any], CycleContext]:
    """The entries post_shape reads, and the cycle context, late in a real plan's information stage."""
    from eos_svc.agents.planner import plan
    from eos_svc.schema.request import PlanRequest

    snapshot: dict[str, Snapshot] = {}

    def make(world: Any) -> Snapshot:
        snapshot["agent"] = Snapshot(world)
        return snapshot["agent"]

    plan(PlanRequest(seed=1), agents=[make])
    kept = snapshot["agent"].kept
    assert kept is not None
    return kept


def reply_size(session: zenoh.Session, key: str, payload: bytes) -> int:
    replies = [r for r in session.get(key, payload=payload, timeout=5) if r.ok is not None]
    return len(replies[0].ok.payload.to_bytes())  # type: ignore[union-attr]


def bare(session: zenoh.Session, query_bytes: int, reply_bytes: int) -> float:
    payload = b"x" * query_bytes
    t0 = time.perf_counter()
    replies = list(session.get(f"{BARE}/{reply_bytes}", payload=payload, timeout=5))
    dt = time.perf_counter() - t0
    assert len(replies) == 1 and replies[0].ok is not None
    return dt


def main(n: int) -> None:
    entries, ctx = information_board()
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, __file__, "--serve", str(port)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and proc.stdout.readline().strip() == "serving"
    session = zenoh.open(make_config(connect=[loopback(port)]))
    try:
        proxy = RemoteAgent.connect(session, "remote_post_shape", connect_timeout_s=5.0, timeout_s=1.0)
        writer = RemoteAgent.connect(session, "shape_writer", connect_timeout_s=5.0, timeout_s=1.0)
        query = wire.query_payload(ctx, entries)
        pfx = wire.prefix()
        rate_reply = reply_size(session, wire.agent_key(pfx, "remote_post_shape", "rate"), query)
        act_reply = reply_size(session, wire.agent_key(pfx, "shape_writer", "act"), query)
        times: dict[str, list[float]] = {"rate": [], "bare rate": [], "act": [], "bare act": [], "fit": []}
        for i in range(n):
            board = Board(entries)
            t0 = time.perf_counter()
            proxy.opportunistic(board, ctx)
            times["rate"].append(time.perf_counter() - t0)
            times["bare rate"].append(bare(session, len(query), rate_reply))
            board = Board(entries)
            t0 = time.perf_counter()
            writer.act(board, ctx)
            times["act"].append(time.perf_counter() - t0)
            times["bare act"].append(bare(session, len(query), act_reply))
            if i % 10 == 0:  # post_shape's own action, its fit included (for scale only)
                t0 = time.perf_counter()
                proxy.act(Board(entries), ctx)
                times["fit"].append(time.perf_counter() - t0)
        med = {k: statistics.median(v[len(v) // 10 :]) for k, v in times.items()}
        print(f"remote agents served in a second process, loopback, n={n}")
        print(
            f"query {len(query)} B (post_shape's entries); rate reply {rate_reply} B; act reply {act_reply} B"
        )
        print(f"{'what':<34}{'median':>10}{'ratio':>9}")
        for part in ("rate", "act"):
            base = "bare get->reply, same sizes (" + part + ")"
            print(f"{base:<34}{med['bare ' + part] * 1e3:>8.3f} ms{1.0:>8.2f}x")
            ratio = med[part] / med["bare " + part]
            label = "remote_post_shape rate" if part == "rate" else "shape_writer act (writes checked)"
            print(f"{label:<34}{med[part] * 1e3:>8.3f} ms{ratio:>8.2f}x")
        print(f"(post_shape's own act, its fit included, remote: {med['fit'] * 1e3:.2f} ms)")
        worst = max(med["rate"] / med["bare rate"], med["act"] / med["bare act"])
        verdict = "met" if worst <= 2.0 else "NOT met"
        print(f"goal: remote agent <= 2x bare get->reply -> {verdict} (worst {worst:.2f}x)")
        proxy.close()
        writer.close()
    finally:
        session.close()
        assert proc.stdin is not None
        proc.stdin.close()
        proc.wait(timeout=10)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--serve":
        serve(int(sys.argv[2]))
    else:
        parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
        parser.add_argument("--n", type=int, default=400, help="rounds (400)")
        main(parser.parse_args().n)
