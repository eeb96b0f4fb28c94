"""The wire protocol alone: keys, envelope, and a decoder that only ever raises RequestError."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.wire_json import dumps


def test_keys_are_versioned_and_namespaced():
    assert proto.prefix() == "eos/@v1"
    assert proto.prefix("lab-a") == "eos/@v1/lab-a"
    p = proto.prefix("lab-a")
    assert proto.plan_key(p, "i1") == "eos/@v1/lab-a/plan/i1"
    assert proto.instance_key(p) == "eos/@v1/lab-a/instance/*"
    assert proto.cycle_key(p, "g1") == "eos/@v1/lab-a/goal/g1/cycle"
    assert proto.status_key(p, "g1") == "eos/@v1/lab-a/goal/g1/status"
    assert proto.cancel_key(p, "g1") == "eos/@v1/lab-a/cancel/g1"
    with pytest.raises(proto.RequestError):
        proto.prefix("a/**")


def test_round_trip():
    req = PlanRequest(seed=9, max_cycles=77)
    goal, back = proto.decode_request(proto.encode_request("goal-9", req))
    assert goal == "goal-9" and back == req


@pytest.mark.parametrize("goal", ["", "-a", "a b", "a/b", "a*", "$x", "@v1", "x" * 65, "é"])
def test_bad_goal_ids(goal):
    with pytest.raises(proto.RequestError) as info:
        proto.decode_request(json.dumps({"schema": 1, "goal_id": goal}).encode())
    assert info.value.field == "goal_id" and info.value.code == proto.E_INVALID


def test_error_reply_round_trip():
    err = proto.RequestError(proto.E_INVALID, "object.radius", "must be > 0", "g1")
    back = proto.error_from_payload(dumps(err.to_dict()))
    assert (back.code, back.field, back.reason, back.goal_id) == (
        "invalid_request",
        "object.radius",
        "must be > 0",
        "g1",
    )
    assert proto.error_from_payload(b"\xff").code == proto.E_INTERNAL


def _decode_only_request_errors(payload: bytes) -> None:
    try:
        goal, req = proto.decode_request(payload)
    except proto.RequestError as err:
        assert err.code in proto.ERROR_CODES
        assert isinstance(err.field, str) and err.field
        assert isinstance(err.reason, str) and err.reason
        json.dumps(err.to_dict(), allow_nan=False)
    else:
        assert proto.ID_PATTERN.fullmatch(goal)
        assert isinstance(req, PlanRequest)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_bytes(payload):
    _decode_only_request_errors(payload)


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=10),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4)
    ),
    max_leaves=20,
)
FIELDS = ["object", "weights", "seed", "tactile_noise", "max_cycles", "deadline_s", "schema", "goal_id"]


@settings(max_examples=120, deadline=None)
@given(st.dictionaries(st.sampled_from(FIELDS) | st.text(max_size=6), json_values, max_size=6))
def test_fuzz_envelopes(fields):
    body = {"schema": 1, "goal_id": "g1", **fields}
    _decode_only_request_errors(json.dumps(body).encode())


shapes = st.sampled_from(["sphere", "ellipsoid", "cylinder", "box", "capsule", "torus", 3, None])
numbers = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False), st.integers(min_value=-(10**30), max_value=10**30)
)
objects = st.fixed_dictionaries(
    {"shape": shapes},
    optional={
        "radius": numbers | json_values,
        "radii": st.lists(numbers, max_size=4),
        "length": numbers,
        "size": st.lists(numbers, max_size=4) | json_values,
        "position": st.lists(numbers, max_size=4),
        "rpy": st.lists(numbers, max_size=3),
    },
)


@settings(max_examples=250, deadline=None)
@given(
    objects,
    st.fixed_dictionaries({}, optional={"default": numbers, "opportunistic": numbers, "learned": numbers}),
    st.fixed_dictionaries(
        {},
        optional={
            "seed": numbers | json_values,
            "max_cycles": numbers,
            "deadline_s": numbers | st.none(),
            "tactile_noise": numbers,
        },
    ),
)
def test_fuzz_near_valid_requests(obj, weights, rest):
    body = {"schema": 1, "goal_id": "g1", "object": obj, "weights": weights, **rest}
    _decode_only_request_errors(json.dumps(body).encode())


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=200))
def test_fuzz_text(text):
    _decode_only_request_errors(text.encode("utf-8", "surrogatepass"))


def test_id_and_token_forms():
    assert all(proto.is_id(v) for v in ("a", "a" * 64, "a-._", "0", "G-1.x_y"))
    assert not any(proto.is_id(v) for v in ("a" * 65, "-a", ".a", "_a", "", "a/b", "a*", "é", "a\n"))
    assert all(proto.is_token(v) for v in ("-" * 16, "_" * 128, "a" * 16, "a" * 128))
    assert not any(proto.is_token(v) for v in ("a" * 15, "a" * 129, "a" * 15 + ".", "ä" * 16))
