"""The typed fast path of plan-request decoding against the full, field-by-field path.

:func:`decode_fast` must take the requests the clients send, and for any payload either step
aside (``None``: the full path answers, with its exact error) or give exactly the request the
full path gives. Valid requests of every shape with random values, boundary values on both sides
of every bound, and payloads that msgspec alone would misread (a repeated key, a huge integer).
"""

from __future__ import annotations

import json
import random

import pytest

from eos_svc.ratings import Weights
from eos_svc.schema.request import (
    MAX_CYCLES_LIMIT,
    MAX_DEADLINE_S,
    MAX_FRICTION,
    MAX_OBJECT_SIZE,
    MAX_POSITION,
    MAX_TACTILE_NOISE,
    ObjectSpec,
    PlanRequest,
)
from eos_svc.service import protocol as proto
from eos_svc.service.request_wire import decode_fast


def fast(raw: bytes) -> tuple[str, PlanRequest, str | None, bool | None] | None:
    return decode_fast(raw)


def full(raw: bytes) -> tuple[str, PlanRequest, str | None, bool | None] | proto.RequestError:
    try:
        env = proto.decode_checked(raw)
    except proto.RequestError as err:
        return err
    return env.goal_id, env.request, env.cancel_token, env.watch


def agrees(raw: bytes) -> bool:
    """The fast path steps aside or gives the full path's request, of the same types."""
    got = fast(raw)
    if got is None:
        return False
    want = full(raw)
    assert not isinstance(want, proto.RequestError), (raw, want)
    assert got == want, raw
    assert repr(got) == repr(want), raw  # bit for bit: -0.0 and 0.0 apart
    g, w = got[1], want[1]
    for a, b in ((g, w), (g.obj, w.obj)):
        for name in a.__dataclass_fields__:
            assert type(getattr(a, name)) is type(getattr(b, name)), name
    for key, value in g.obj.size.items():
        assert type(value) is type(w.obj.size[key])
        if isinstance(value, tuple):
            assert [type(v) for v in value] == [type(v) for v in w.obj.size[key]]
    assert list(g.obj.size) == list(w.obj.size)
    return True


def random_request(rng: random.Random) -> PlanRequest:
    shape = rng.choice(["sphere", "ellipsoid", "cylinder", "box", "capsule"])
    size: dict[str, object] = {}
    for key in {"sphere": ("radius",), "ellipsoid": ("radii",), "cylinder": ("radius", "length"),
                "box": ("size",), "capsule": ("radius", "length")}[shape]:  # fmt: skip
        if key in ("radii", "size"):
            size[key] = [rng.uniform(0.005, 0.08) for _ in range(3)]
        else:
            size[key] = rng.uniform(0.005, 0.08)
    d = rng.random()
    return PlanRequest(
        obj=ObjectSpec(
            shape,
            size,
            tuple(rng.uniform(-0.3, 0.3) for _ in range(3)),  # type: ignore[arg-type]
            tuple(rng.uniform(-3.2, 3.2) for _ in range(3)),  # type: ignore[arg-type]
        ),
        weights=Weights(d, 1.0 - d, 0.0),
        seed=rng.randrange(2**63),
        tactile_noise=rng.uniform(0, MAX_TACTILE_NOISE),
        max_cycles=rng.randint(1, MAX_CYCLES_LIMIT),
        deadline_s=rng.choice([None, rng.uniform(0.1, 100.0)]),
        friction=rng.uniform(0, MAX_FRICTION),
    )


@pytest.mark.parametrize("seed", range(4))
def test_client_requests_take_the_fast_path_and_decode_as_the_full_path(seed: int) -> None:
    rng = random.Random(seed)
    for i in range(50):
        request = random_request(rng)
        token = proto.new_cancel_token() if i % 3 else None
        watch = (None, True, False)[i % 3 if seed % 2 else (i // 3) % 3]
        raw = proto.encode_request(f"g-{seed}-{i}", request, token, watch)
        assert agrees(raw), raw
        env = proto.decode_envelope(raw)
        assert tuple(env) == (f"g-{seed}-{i}", request, token, watch)


def _base() -> dict[str, object]:
    return json.loads(proto.encode_request("g-1", PlanRequest(), "t" * 22))


def _set(doc: dict[str, object], path: str, value: object) -> bytes:
    d = json.loads(json.dumps(doc))
    where = d
    *parents, last = path.split(".")
    for p in parents:
        where = where[p]
    where[last] = value
    return json.dumps(d).encode()


#: a default request as a client sends it, without a cancel token
PLAIN = proto.encode_request("g-1", PlanRequest(), None)
EPS = 1e-12
# (field, values the fast path takes, values it leaves to the full path: refused there, or in
# another form than the clients', e.g. an integral float for an integer)
BOUNDS = [
    ("object.radius", [MAX_OBJECT_SIZE, 1e-9, 1], [0.0, -0.01, MAX_OBJECT_SIZE + EPS, 2, True, "0.03", None]),
    (
        "object.position",
        [[MAX_POSITION, -MAX_POSITION, 0], [1, 2, 3]],
        [[MAX_POSITION + 1e-9, 0, 0], [0, 0], [0, 0, 0, 0], [0, 0, "1"], "x", [0, True, 0]],
    ),
    ("object.rpy", [[100.0, -1e18, 7], [0, 0, 0]], [[0, 0, None], [0, 0, False]]),
    ("seed", [0, 2**63 - 1, 12345], [-1, 2**63, 2**64, 3.0, True, "1", None]),
    ("tactile_noise", [0, 0.0, MAX_TACTILE_NOISE], [-1e-12, MAX_TACTILE_NOISE + 1e-12, None, False]),
    ("max_cycles", [1, MAX_CYCLES_LIMIT], [0, MAX_CYCLES_LIMIT + 1, 5.0, 5.5, None, True]),
    ("deadline_s", [None, MAX_DEADLINE_S, 1e-6, 3], [0, 0.0, -1, MAX_DEADLINE_S + 1e-9, "10", True]),
    ("friction", [0, MAX_FRICTION, 0.3], [-1e-12, MAX_FRICTION + 1e-9, None, True]),
    ("weights.default", [0.5], [0.6, -0.5, 1.5, None, True]),
    ("weights.learned", [0.0, 0], [0.1, None]),
    ("schema", [1], [1.0, 2, 0, True, "1", None]),
    ("goal_id", ["a", "A.b-c_9", "x" * 64], ["", "x" * 65, "a/b", "a*", "-a", 5, None, "a\n"]),
    ("cancel_token", [None, "A" * 16, "_-" * 64], ["short", "a" * 129, "a b" * 8, 5, False]),
    ("watch", [True, False, None], [1, 0, "true", [], {}]),
    ("object.shape", ["sphere"], ["cube", "Sphere", None, 1]),
]


@pytest.mark.parametrize(("path", "accepted", "refused"), BOUNDS, ids=[b[0] for b in BOUNDS])
def test_bounds_agree(path: str, accepted: list[object], refused: list[object]) -> None:
    doc = _base()
    for value in accepted:
        raw = _set(doc, path, value)
        assert agrees(raw), raw
    for value in refused:
        raw = _set(doc, path, value)
        assert fast(raw) is None, raw
        integral = type(value) is float and value.is_integer() and path in ("seed", "max_cycles")
        env = proto.decode_envelope(raw) if integral else None  # an integral float: accepted
        assert env is None or env.request == full(raw)[1]  # type: ignore[index]


@pytest.mark.parametrize(
    "raw",
    [
        # a repeated key: msgspec would keep the last value; the wire refuses it (full path)
        PLAIN[:-1] + b',"seed":5}',
        PLAIN[:-1] + b',"watch":true,"watch":false}',
        PLAIN.replace(b'"seed":1', b'"seed" :1,"seed":2'),
        PLAIN.replace(b'"radius"', b'"radius":0.02,"radius"'),
        # huge integers: named by the full path
        PLAIN.replace(b'"rpy":[0.0', b'"rpy":[' + b"9" * 25),
        PLAIN.replace(b'"rpy":[0.0', b'"rpy":[18446744073709551617'),
        PLAIN.replace(b'"seed":1', b'"seed":' + b"1" * 30),
        # unknown fields, not UTF-8 JSON, not an object: the full path names the cause
        PLAIN[:-1] + b',"extra":1}',
        b"\xef\xbb\xbf" + PLAIN,
        PLAIN.replace(b'"learned":0.0', b'"learned":NaN'),
        PLAIN + b"x",
        b"[]",
        b"",
        b"\xff",
    ],
)
def test_what_msgspec_alone_would_misread_goes_the_full_way(raw: bytes) -> None:
    assert fast(raw) is None
    want = full(raw)
    if not isinstance(want, proto.RequestError):  # the byte-order mark: ignored by the full path
        assert raw.startswith(b"\xef\xbb\xbf")
        env = proto.decode_envelope(raw)
        assert tuple(env) == want
        return
    with pytest.raises(proto.RequestError) as got:
        proto.decode_envelope(raw)
    assert got.value.to_dict() == want.to_dict()


def test_errors_are_the_full_paths() -> None:
    doc = _base()
    for path, _ok, refused in BOUNDS:
        for value in refused:
            raw = _set(doc, path, value)
            want = full(raw)
            if not isinstance(want, proto.RequestError):
                assert type(value) is float and value.is_integer()  # for an integer: the full path takes it
                continue
            with pytest.raises(proto.RequestError) as got:
                proto.decode_envelope(raw)
            assert got.value.to_dict() == want.to_dict()


def test_whitespace_and_key_order_are_still_fast() -> None:
    doc = _base()
    keys = list(doc)
    random.Random(5).shuffle(keys)
    raw = json.dumps({k: doc[k] for k in keys}, indent=2).encode()  # '": ' and newlines
    assert agrees(raw)


def test_missing_fields_take_their_defaults_on_the_full_path() -> None:
    raw = json.dumps({"schema": 1, "goal_id": "g", "seed": 7}).encode()
    assert fast(raw) is None
    assert proto.decode_envelope(raw).request == PlanRequest(seed=7)


@pytest.mark.parametrize("literal", [b"-0", b"-0.0", b"0", b"-0e0", b"-0E-5", b"1E-3", b"2", b"1.5e-2"])
def test_number_literals_decode_bit_for_bit(literal: bytes) -> None:
    for old in (b'"position":[0.21', b'"friction":0.5', b'"rpy":[0.0', b'"tactile_noise":0.0002'):
        raw = PLAIN.replace(old, old.split(b":")[0] + b":" + (b"[" if b"[" in old else b"") + literal)
        if b"tactile_noise" in old and literal in (b"2", b"1.5e-2"):
            assert fast(raw) is None  # out of range: the full path refuses it
            continue
        assert agrees(raw), raw


@pytest.mark.parametrize("watch", [None, True, False])
def test_the_watch_hint_is_written_only_when_given_and_read_back(watch: bool | None) -> None:
    raw = proto.encode_request("g-1", PlanRequest(), None, watch)
    assert (b'"watch"' in raw) is (watch is not None)
    assert fast(raw) == full(raw) == ("g-1", PlanRequest(), None, watch)


@pytest.mark.parametrize("value", [1, "false", [True]])
def test_a_watch_hint_that_is_not_a_boolean_is_named(value: object) -> None:
    """true or false; null is no hint, as an absent one (as a null cancel_token is no token)."""
    doc = json.loads(PLAIN)
    doc["watch"] = value
    with pytest.raises(proto.RequestError) as got:
        proto.decode_envelope(json.dumps(doc).encode())
    assert (got.value.code, got.value.field) == (proto.E_INVALID, "watch")
    assert "must be true, false or null" in got.value.reason


def test_a_null_watch_hint_is_no_hint() -> None:
    doc = json.loads(PLAIN)
    doc["watch"] = None
    raw = json.dumps(doc).encode()
    assert fast(raw) == full(raw) == ("g-1", PlanRequest(), None, None)
