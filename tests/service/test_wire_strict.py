"""The wire format is strict and bounded: UTF-8 JSON only, no duplicate keys, huge integers named
by their field, every error reply under 4 KiB (the pure decoder, then through a real service)."""

from __future__ import annotations

import json

import pytest

from eos_svc.service import protocol as proto
from eos_svc.service.wire_json import dumps, loads_strict

VALID = {"schema": 1, "goal_id": "g1", "seed": 3}


def refusal(payload: bytes) -> proto.RequestError:
    with pytest.raises(proto.RequestError) as info:
        proto.decode_request(payload)
    return info.value


def text(obj: dict) -> str:
    return json.dumps(obj)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "utf-32", "utf-32-le"])
def test_utf16_and_utf32_are_refused(encoding):
    err = refusal(text(VALID).encode(encoding))
    assert err.code == proto.E_NOT_JSON and err.field == "request"
    assert "UTF-8" in err.reason


@pytest.mark.parametrize(
    "bad",
    [b"\xed\xa0\x80", b"\xed\xbf\xbf", b"\xc0\xaf", b"\xff", b"\xe2\x82"],
    ids=["high surrogate", "low surrogate", "overlong", "ff", "truncated"],
)
def test_invalid_utf8_bytes_are_refused(bad):
    payload = b'{"schema": 1, "goal_id": "g1", "object": {"shape": "sphere' + bad + b'"}}'
    err = refusal(payload)
    assert err.code == proto.E_NOT_JSON and "not UTF-8" in err.reason


def test_a_utf8_byte_order_mark_is_ignored():
    goal, request = proto.decode_request(b"\xef\xbb\xbf" + text(VALID).encode())
    assert (goal, request.seed) == ("g1", 3)


@pytest.mark.parametrize(
    ("payload", "field"),
    [
        (b'{"schema": 1, "goal_id": "g1", "seed": 1, "seed": 2}', "seed"),
        (b'{"schema": 1, "schema": 1, "goal_id": "g1"}', "schema"),
        (
            b'{"schema": 1, "goal_id": "g1", "object": {"shape": "sphere", "radius": 0.03, "radius": 9}}',
            "radius",
        ),
    ],
)
def test_duplicate_keys_are_refused_naming_the_key(payload, field):
    err = refusal(payload)
    assert err.code == proto.E_NOT_JSON and err.field == field and "duplicate" in err.reason


@pytest.mark.parametrize(
    ("literal", "field"),
    [
        (b'"seed": ' + b"7" * 5000, "seed"),
        (b'"seed": -' + b"7" * 5000, "seed"),
        (b'"max_cycles": 100000000000000000000000', "max_cycles"),
        (
            b'"object": {"shape": "sphere", "radius": 0.03, "position": [0.2, ' + b"9" * 300 + b", 0]}",
            "object.position[1]",
        ),
    ],
    ids=["5000-digit seed", "negative", "23 digits", "nested"],
)
def test_huge_integers_are_named_by_their_field(literal, field):
    err = refusal(b'{"schema": 1, "goal_id": "g1", ' + literal + b"}")
    assert err.code == proto.E_INVALID and err.field == field and "too large" in err.reason
    assert err.goal_id == "g1"


def test_integers_up_to_2_64_are_read_as_integers():
    err = refusal(
        b'{"schema": 1, "goal_id": "g1", "seed": 18446744073709551616}'
    )  # 2**64: in range on the wire
    assert err.field == "seed" and "must be in" in err.reason  # refused by the field's own bound


@pytest.mark.parametrize(
    "name", ["x" * 60_000, "😀" * 15_000, "\u0001" * 9_000], ids=["ascii", "emoji", "control"]
)
def test_error_replies_are_bounded(name):
    payload = json.dumps({"schema": 1, "goal_id": "g1", name: 1}, ensure_ascii=False).encode()
    err = refusal(payload)
    assert err.code == proto.E_INVALID and err.field.startswith(name[:10])
    reply = dumps(err.to_dict())
    assert len(reply) <= 4096
    back = proto.error_from_payload(reply)
    assert back.field == err.field and back.reason == err.reason


def test_clip_keeps_short_text_and_bounds_long_text():
    assert proto.clip("seed", 256) == "seed"
    for s in ["a" * 1000, "😀" * 1000, '"\\' * 1000]:
        c = proto.clip(s, 256)
        assert len(dumps(c)) <= 256 and c.endswith("…") and s.startswith(c[:-1])


def test_loads_strict_names_a_huge_integer_instead_of_returning_it():
    with pytest.raises(ValueError, match=r"object\.position\[1\]: integer too large"):
        loads_strict('{"object": {"position": [0.2, ' + "9" * 40 + ", 0]}}")
    assert loads_strict(b'{"seed": 18446744073709551616}') == {"seed": 2**64}


def test_cli_request_file_with_a_huge_integer_exits_2_naming_it(tmp_path, capsys):
    from eos_svc.cli import main

    path = tmp_path / "request.json"
    path.write_text('{"seed": ' + "7" * 5000 + "}")
    with pytest.raises(SystemExit) as info:
        main(["client", "plan", "--request", str(path)])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--request" in err and "seed" in err and len(err) < 500
