"""Hostile traffic against a running service instance, with what each probe should get back.

Each probe sends real queries on an open Zenoh session and counts the replies (big payloads,
mutated requests, a wildcard plan query, a stranger's cancel, unplannable objects, a squatter of
goal ids: ``docs/service.md``, "Reliability runs"); ``reliability.py abuse`` runs them.
"""

from __future__ import annotations

import random
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import zenoh

from eos_svc.errors import EosError
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import EosClient


@dataclass
class Probe:
    """What one probe sent and got back.

    Attributes:
        name: what was sent, in words.
        sent: queries sent.
        answered_once: queries that got exactly one reply.
        codes: reply codes (``ok`` for a plan result) and how many of each.
        ok: whether every reply was the expected one.
        detail: a short note (memory, fields named, ...).
    """

    name: str
    sent: int = 0
    answered_once: int = 0
    codes: Counter[str] = field(default_factory=Counter)
    ok: bool = False
    detail: str = ""


def rss_mb(pid: int) -> float:
    """Resident set size of process ``pid`` (MB, from /proc)."""
    with open(f"/proc/{pid}/status", encoding="ascii") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise EosError(f"no VmRSS for pid {pid}")


def _ask(session: zenoh.Session, key: str, payload: bytes, timeout: float = 10.0) -> list[str]:
    """Send one query; the code of every reply (``ok`` for a success)."""
    codes = []
    for reply in session.get(key, payload=payload, timeout=timeout):
        if reply.ok is not None:
            codes.append("ok")
        else:
            codes.append(proto.error_from_payload(reply.err.payload.to_bytes()).code)
    return codes


def big_payloads(session: zenoh.Session, key: str, count: int = 100, size: int = 10_000_000) -> Probe:
    """``count`` requests of ``size`` bytes each: every one refused ``payload_too_large``."""
    probe = Probe(f"{count} x {size / 1e6:g} MB payloads")
    junk = b'{"schema":1,"goal_id":"big","pad":"' + b"x" * size + b'"}'
    for _ in range(count):
        codes = _ask(session, key, junk)
        probe.sent += 1
        probe.answered_once += len(codes) == 1
        probe.codes.update(codes)
    probe.ok = probe.answered_once == count and probe.codes == Counter({proto.E_TOO_LARGE: count})
    return probe


def mutated_requests(session: zenoh.Session, key: str, count: int = 10_000, seed: int = 1) -> Probe:
    """``count`` copies of a valid request with 1-4 random bytes overwritten (fixed seed).

    A mutation may leave the request valid: then it plans (a short plan, ``max_cycles`` 5).
    Expected: one reply each, never ``internal_error``.
    """
    probe = Probe(f"{count} mutated requests")
    base = proto.encode_request(
        "m0",
        {"object": {"shape": "sphere", "radius": 0.03, "position": [0.21, 0.02, -0.015]}, "max_cycles": 5},
    )
    rng = random.Random(seed)
    for i in range(count):
        data = bytearray(base)
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        data[23:25] = b"%02d" % (i % 100)  # goal id "m0" -> "mNN": mutants rarely collide as duplicates
        codes = _ask(session, key, bytes(data))
        probe.sent += 1
        probe.answered_once += len(codes) == 1
        probe.codes.update(codes)
    probe.ok = probe.answered_once == count and probe.codes[proto.E_INTERNAL] == 0
    return probe


def wildcard_plan(session: zenoh.Session, prefix: str, instances: int) -> Probe:
    """A valid plan query on ``P/plan/*`` and ``P/plan/**`` with the default and the ALL targets:
    one ``invalid_request`` each (naming the keys to use), no plan run."""
    probe = Probe(f"plan query on {prefix}/plan/* ({instances} instances)")
    payload = proto.encode_request("wild", PlanRequest(max_cycles=3))
    for suffix in ("*", "**"):
        for target in (zenoh.QueryTarget.BEST_MATCHING, zenoh.QueryTarget.ALL):
            codes = []
            for reply in session.get(
                f"{prefix}/plan/{suffix}",
                payload=payload,
                target=target,
                consolidation=zenoh.ConsolidationMode.NONE,
                timeout=5,
            ):
                codes.append(
                    "ok"
                    if reply.ok is not None
                    else proto.error_from_payload(reply.err.payload.to_bytes()).code
                )
            probe.sent += 1
            probe.answered_once += len(codes) == 1
            probe.codes.update(codes)
    probe.ok = probe.answered_once == probe.sent and probe.codes == Counter({proto.E_INVALID: probe.sent})
    return probe


def stranger_cancel(owner: EosClient, stranger: EosClient, instance: str | None = None) -> Probe:
    """The owner runs a long plan; the stranger reads its goal id from the status topic and tries
    to cancel it without and with a guessed token (``forbidden`` both times); the owner's cancel
    then ends it (``cancelled``)."""
    probe = Probe("stranger cancels a running goal")
    learned: list[str] = []
    sub = stranger.watch(
        lambda kind, msg: learned.append(msg.get("goal_id", "")) if kind == "status" else None
    )
    box: dict[str, Any] = {}
    started = threading.Event()

    def run() -> None:
        box["out"] = owner.plan(
            PlanRequest(max_cycles=100_000, deadline_s=60.0),
            instance=instance,
            on_cycle=lambda m: started.set() if m["seq"] >= 2 else None,
        )

    t = threading.Thread(target=run, daemon=True)
    t.start()
    started.wait(30)
    deadline = time.monotonic() + 5
    while not learned and time.monotonic() < deadline:
        time.sleep(0.01)
    goal = learned[0] if learned else ""
    for token in (None, proto.new_cancel_token()):
        probe.sent += 1
        try:
            code = "ok" if stranger.cancel(goal, cancel_token=token) else "not_found"
        except proto.RequestError as err:
            code = err.code
        probe.codes[code] += 1
        probe.answered_once += 1
    sub.undeclare()
    owner_ok = owner.cancel(goal)
    t.join(15)
    status = box["out"].status if "out" in box else "no answer"
    probe.ok = probe.codes == Counter({proto.E_FORBIDDEN: 2}) and owner_ok and status == "cancelled"
    probe.detail = f"goal id read from the status topic; owner's cancel -> {status}"
    return probe


def squatter(owner: EosClient, squatter: EosClient, instance: str, plans: int = 3) -> Probe:
    """The squatter watches the statuses, learns the owner's goal id and sends long plans under the
    ids that would follow it were ids a counter (``g-<hex>-<n+1>``, ...; for any other form, the id
    with ``1``, ``2``, ... appended) to ``instance``; then the owner plans ``plans`` times there:
    expected, every plan answered with a result (no ``duplicate_goal``)."""
    probe = Probe(f"squatter holds the guessed next {plans} goal ids")
    learned: list[str] = []
    sub = squatter.watch(lambda kind, msg: learned.append(msg["goal_id"]) if kind == "status" else None)
    first = owner.plan(PlanRequest(max_cycles=2), instance=instance).goal_id
    deadline = time.monotonic() + 5
    while first not in learned and time.monotonic() < deadline:
        time.sleep(0.01)
    stem, _, number = first.rpartition("-")
    guesses = [
        f"{stem}-{int(number) + i}" if number.isdigit() else f"{first}{i}" for i in range(1, plans + 1)
    ]
    held = [
        threading.Thread(
            target=lambda g=g: squatter.plan(PlanRequest(max_cycles=40), goal_id=g, instance=instance),
            daemon=True,
        )
        for g in guesses
    ]
    for t in held:
        t.start()
    time.sleep(0.3)  # held: running or queued
    for _ in range(plans):
        probe.sent += 1
        try:
            probe.codes[owner.plan(PlanRequest(max_cycles=2), instance=instance, timeout=30).status] += 1
        except proto.RequestError as err:
            probe.codes[err.code] += 1
        probe.answered_once += 1
    sub.undeclare()
    for t in held:
        t.join(30)
    probe.ok = sum(probe.codes[c] for c in proto.ERROR_CODES) == 0
    probe.detail = f"the owner's first id {first} read from the status topic; failed plans: " + str(
        sum(probe.codes[c] for c in proto.ERROR_CODES)
    )
    return probe


#: requests the planner cannot plan, and the field each refusal must name
UNPLANNABLE: tuple[tuple[dict[str, Any], str], ...] = (
    ({"shape": "sphere", "radius": 0.03, "position": [9.0, 9.0, 9.0]}, "object.position"),
    ({"shape": "sphere", "radius": 0.03, "position": [0.21, 0.0, 0.3]}, "object.position"),
    ({"shape": "sphere", "radius": 0.03, "position": [0.0, 0.0, 0.0]}, "object.position"),
    ({"shape": "sphere", "radius": 0.2, "position": [0.4, 0.0, 0.0]}, "object.radius"),
)


def unplannable(session: zenoh.Session, key: str) -> Probe:
    """Objects out of reach, above the reach, inside the hand, too large: ``invalid_request``
    naming the field, no plan run."""
    probe = Probe("unplannable objects (reach, overlap, size)")
    named = []
    for i, (obj, wanted) in enumerate(UNPLANNABLE):
        payload = proto.encode_request(f"u{i}", {"object": obj}, proto.new_cancel_token())
        replies = list(session.get(key, payload=payload, timeout=10.0))
        probe.sent += 1
        probe.answered_once += len(replies) == 1
        for reply in replies:
            if reply.ok is not None:
                probe.codes["ok"] += 1
            else:
                err = proto.error_from_payload(reply.err.payload.to_bytes())
                probe.codes[err.code] += 1
                named.append(err.field.startswith(wanted))
    probe.ok = probe.codes == Counter({proto.E_INVALID: len(UNPLANNABLE)}) and all(named)
    probe.detail = "fields named: " + ("yes" if all(named) and named else "no")
    return probe
