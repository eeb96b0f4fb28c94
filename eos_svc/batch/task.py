"""The work of one batch task, as it runs in a worker: plan each key, validate it, make its row.

Plain functions of their arguments, without Ray: :mod:`eos_svc.batch.runner` runs
:func:`run_chunk` as a Ray task, and the tests run it in-process to compare. A plan that
admission refuses is a row with status ``refused`` naming the field; any other exception of a
plan or a validation is caught and written in the row (status ``error``, or
``validation_reason``), so one bad plan never stops a batch.
"""

from __future__ import annotations

import os
import socket
import time
from typing import Any

from eos_svc.batch import rows
from eos_svc.batch.expansion import PlanKey
from eos_svc.errors import EosError, ValidationError


def hand_model(name: str, loaded: dict[str, Any] | None = None) -> Any:
    """The hand ``name`` names (a registered hand, ``eos hands``): the planner's default hand
    for hand3x3, else built from its description, once per ``loaded`` dict (a chunk's)."""
    from eos_svc.agents import default_hand
    from eos_svc.hands import DEFAULT_HAND, load_hand_named

    if name == DEFAULT_HAND:
        return default_hand()
    if loaded is None:
        return load_hand_named(name)
    if name not in loaded:
        loaded[name] = load_hand_named(name)
    return loaded[name]


def run_key(key: PlanKey, worker: str = "", loaded: dict[str, Any] | None = None) -> dict[str, Any]:
    """Plan one key (and validate it when asked): its row (``loaded``: hands already built)."""
    from eos_svc.agents import PlanRequest, plan

    started = time.perf_counter()
    row = rows.key_columns(key, worker)
    hand = hand_model(key.hand, loaded)
    try:
        result = plan(PlanRequest.from_dict(key.request), hand=hand, keep_trace=False, world=key.world)
    except ValidationError as exc:  # admission: the planner cannot plan this object
        row.update(rows.empty_columns(rows.REFUSED, f"{exc.field}: {exc.reason}"))
    except Exception as exc:  # a bug or a failed computation: recorded, the batch goes on
        row.update(rows.empty_columns(rows.ERROR, f"{type(exc).__name__}: {exc}"))
    else:
        row.update(rows.result_columns(result, [int(i) for i in hand.wrist_q_index]))
        row.update(validated_columns(key, result, hand))
    row["task_s"] = time.perf_counter() - started
    return row


def validated_columns(key: PlanKey, result: Any, hand: Any = None) -> dict[str, Any]:
    """The validation columns of a planned key: not validated, the report, or why it failed."""
    if not key.validate.enabled:
        return rows.validation_columns(None, None)
    if result.q_final is None:
        return rows.validation_columns(None, "no final grasp to validate")
    from eos_svc.validation import validate_grasp

    try:
        report = validate_grasp(
            result, seconds=key.validate.seconds, directions=key.validate.directions, hand=hand
        )
    except EosError as exc:
        return rows.validation_columns(None, f"{type(exc).__name__}: {exc}")
    return rows.validation_columns(report, None)


def run_chunk(keys: list[PlanKey]) -> list[dict[str, Any]]:
    """Plan every key of a chunk, in order: their rows (each names this host and process)."""
    worker = f"{socket.gethostname()}:{os.getpid()}"
    loaded: dict[str, Any] = {}
    return [run_key(key, worker, loaded) for key in keys]
