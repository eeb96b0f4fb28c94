"""The service's encoders write what the plain to_dict -> to_jsonable -> JSON chain writes."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, fields, is_dataclass
from enum import Enum
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eos_svc.agent import Outcome
from eos_svc.ratings import Weights
from eos_svc.records import CycleRecord, to_jsonable
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.demo_planner import root_plan
from eos_svc.service.wire_json import dumps, encode_result, loads_strict


def reference_to_jsonable(value: Any) -> Any:
    """``to_jsonable`` as it was before its fast paths (the reference)."""
    from collections.abc import Mapping

    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Enum):
        return reference_to_jsonable(value.value)
    if hasattr(value, "to_dict"):
        return reference_to_jsonable(value.to_dict())
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: reference_to_jsonable(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, Mapping):
        return {str(k): reference_to_jsonable(v) for k, v in value.items()}
    if hasattr(value, "tolist"):
        return reference_to_jsonable(value.tolist())
    if isinstance(value, (list, tuple, set, frozenset)):
        return [reference_to_jsonable(v) for v in value]
    return repr(value)


def reference_record_json(record: CycleRecord) -> bytes:
    """What the service published before: ``to_dict`` then strict JSON, ``to_jsonable`` on failure."""
    d = record.to_dict()
    try:
        return dumps(d)
    except (TypeError, ValueError):
        return dumps(reference_to_jsonable(d))


class Colour(Enum):
    RED = "red"


@dataclass
class Point:
    x: float
    y: float


floats = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from([0.0, -0.0, 0.5, 1e-300, 1e300])
scalars = st.none() | st.booleans() | st.integers(-(2**70), 2**70) | floats | st.text(max_size=8)
keys = st.text(max_size=6) | st.integers(-5, 5) | st.booleans() | st.none() | st.sampled_from([0.5, -0.0])
values = st.recursive(
    scalars
    | st.sampled_from([Colour.RED, Outcome.PROGRESS, Point(1.0, float("nan"))])
    | st.builds(lambda xs: np.array(xs), st.lists(st.floats(-1, 1), max_size=3)),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.lists(inner, max_size=4).map(tuple)
        | st.dictionaries(keys, inner, max_size=4)
    ),
    max_leaves=20,
)


@settings(max_examples=400, deadline=None)
@given(values)
def test_to_jsonable_fast_paths_change_nothing(value):
    assert to_jsonable(value) == reference_to_jsonable(value)
    assert dumps(to_jsonable(value)) == dumps(reference_to_jsonable(value))


def _record(ratings, changes, **kw: Any) -> CycleRecord:
    base: dict[str, Any] = {
        "seq": 3,
        "stage": "search",
        "stage_cycle": 2,
        "ratings": tuple(ratings),
        "weights": Weights(0.5, 0.5, 0.0),
        "chosen": "a",
        "outcome": Outcome.PROGRESS,
        "detail": "moved 3 mm — ok",
        "changes": tuple(changes),
        "elapsed_s": 0.0123,
    }
    base.update(kw)
    return CycleRecord(**base)


rating_values = floats | st.integers(0, 2) | st.sampled_from([np.float64(0.25), np.float32(0.5), np.int64(1)])


def test_cycle_records_encoded_are_their_json_on_real_runs(grasp_planner):
    records: list[CycleRecord] = []
    for seed in range(3):
        root_plan(PlanRequest(seed=seed), on_cycle=records.append)
    grasp_planner(PlanRequest(seed=3), on_cycle=records.append)
    assert records
    for record in records:
        assert json.loads(encode_result(record.to_dict())) == json.loads(reference_record_json(record))


@pytest.mark.parametrize(
    "payload",
    [
        b'{"a": 1}',
        '{"a": "é"}'.encode("utf-16"),
        '{"a": "é"}'.encode("utf-32-le"),
        b'\xef\xbb\xbf{"a": 1}',
        b'{"a": NaN}',
        b'{"a": "\xed\xa0\x80"}',
        b"\xff\xfe",
        b"[1, 2",
    ],
)
def test_loads_strict_reads_what_json_loads_reads(payload):
    """What ``json.loads`` reads, except that only UTF-8 is read (UTF-16/32 and surrogate bytes refused)."""

    def reference(data: bytes) -> Any:
        def reject(name: str) -> Any:
            raise ValueError(name)

        data = data.removeprefix(b"\xef\xbb\xbf")
        return json.loads(data.decode("utf-8"), parse_constant=reject)

    try:
        expected: Any = reference(payload)
    except (ValueError, RecursionError) as exc:
        expected = type(exc)
    try:
        got: Any = loads_strict(payload)
    except (ValueError, RecursionError) as exc:
        got = type(exc)
    if isinstance(expected, type):
        assert isinstance(got, type) and issubclass(got, ValueError) == issubclass(expected, ValueError)
    else:
        assert got == expected


@pytest.mark.parametrize(
    "body",
    [PlanRequest(seed=3, max_cycles=1), {}, {"schema": 2, "a": 1}, {"goal_id": "z"}, {"a": [1.5, "ü", None]}],
)
def test_encode_request_is_the_merged_envelope(body):
    merged = body.to_dict() if isinstance(body, PlanRequest) else dict(body)
    encoded = proto.encode_request("g-1", body)
    if isinstance(body, PlanRequest):  # msgspec's float text: the same values, read back exactly
        assert loads_strict(encoded) == {"schema": 1, "goal_id": "g-1", **merged}
        assert proto.decode_request(encoded) == ("g-1", body)
    else:
        assert encoded == dumps({"schema": 1, "goal_id": "g-1", **merged})


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_encoded_plan_requests_read_back_exactly(seed):
    """Random requests (tiny and huge floats, -0.0): what the client writes, the service reads as sent."""
    import random

    rng = random.Random(seed)
    for _ in range(300):
        a = rng.random()
        req = PlanRequest.from_dict(
            {
                "object": {
                    "shape": "box",
                    "size": [rng.uniform(1e-9, 0.1) for _ in range(3)],
                    "position": [rng.uniform(-1, 1) * 10 ** rng.randint(-300, 1) for _ in range(3)],
                    "rpy": [rng.uniform(-3, 3), 0.0, -0.0],
                },
                "weights": {"default": a, "opportunistic": 1.0 - a},
                "seed": rng.randint(0, 2**63 - 1),
                "tactile_noise": rng.uniform(0, 0.01),
                "deadline_s": rng.choice([None, 1e-9, 3.0]),
            }
        )
        payload = proto.encode_request("g-2", req, proto.new_cancel_token())
        assert proto.decode_request(payload) == ("g-2", req)


def _plain(value: Any) -> bool:
    """Every node is a str, int, float, bool, None, dict (str keys), list or tuple."""
    if value is None or type(value) in (str, int, float, bool):
        return True
    if type(value) is dict:
        return all(type(k) is str and _plain(v) for k, v in value.items())
    if type(value) in (list, tuple):
        return all(_plain(v) for v in value)
    return False


def test_plan_results_encoded_as_held_are_their_to_dict_json():
    """The service encodes a PlanResult from ``to_dict(jsonable=False)`` (its members as held):
    the same bytes as from ``to_dict()``, on real plans of every shape, cut short or whole, and
    with the two members msgspec converts itself (a non-finite float, tuples)."""
    import dataclasses

    from eos_svc.agents.planner import plan
    from eos_svc.schema.request import ObjectSpec

    here = PlanRequest().obj.position
    requests = [
        PlanRequest(seed=3, max_cycles=1),
        PlanRequest(seed=3),
        PlanRequest(seed=8, tactile_noise=0.002),
        PlanRequest(
            obj=ObjectSpec("cylinder", {"radius": 0.02, "length": 0.08}, here, (0.4, -0.3, 0.9)), seed=1
        ),
        PlanRequest(obj=ObjectSpec("box", {"size": (0.07, 0.035, 0.045)}, here, (0.3, 0.6, -1.1)), seed=2),
        PlanRequest(obj=ObjectSpec("ellipsoid", {"radii": (0.035, 0.03, 0.025)}, here), seed=4),
        PlanRequest(obj=ObjectSpec("capsule", {"radius": 0.02, "length": 0.05}, here), seed=5, max_cycles=30),
    ]
    results = [plan(r, keep_trace=False) for r in requests]
    results.append(
        dataclasses.replace(
            results[1],
            epsilon=math.nan,
            d_over_h=math.inf,
            validation={"held": True, "directions": ("+x", "-x"), "drift": (0.001, -math.inf)},
        )
    )
    statuses = set()
    for result in results:
        held = result.to_dict(jsonable=False)
        assert _plain(held)
        assert encode_result(held) == encode_result(result.to_dict())
        assert json.loads(encode_result(held)) == result.to_dict()
        statuses.add(result.status)
    assert len(statuses) >= 2  # cut short and whole plans among them
