"""The hand driver's Zenoh protocol: key expressions and the JSON form of every result.

Under the service's versioned prefix, one served hand per name::

    eos/@v1/hand/<name>/open   payload {"request": <plan request JSON>, "world": "kinematic"|"drake"}
                               → {"q": [...], "tactile_noise": σ, "seed": s}: a new world for the
                               request (its object stays in the serving process)
    eos/@v1/hand/<name>/call   payload {"method": <protocol method>, "args": {...}}
                               → {"result": <JSON form below>, "q": [...]}: the hand's joint values
                               after the call ride along with every reply

A refused call is a ``reply_err`` with ``{"error": "<field>: <reason>"}``. Arrays cross as lists
of floats (m, rad, N), results as the dicts :func:`encode` writes and :func:`decode` reads.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from eos_svc.drivers.protocol import FingerStep, TactileReading, Touch, WristMove
from eos_svc.kinematics.curvature import CurvatureSample
from eos_svc.world.probing import ProbeOutcome

#: the key-expression prefix of served hands
PREFIX = "eos/@v1/hand"


def open_key(name: str) -> str:
    """Where a world is opened for a plan."""
    return f"{PREFIX}/{name}/open"


def call_key(name: str) -> str:
    """Where the protocol's calls go."""
    return f"{PREFIX}/{name}/call"


def _array(value: Any) -> list[float] | None:
    return None if value is None else [float(x) for x in np.asarray(value, dtype=float).ravel()]


def _vector(value: Any) -> np.ndarray | None:
    return None if value is None else np.asarray(value, dtype=float)


def encode(value: Any) -> Any:
    """The JSON form of a protocol result."""
    if isinstance(value, WristMove):
        return {"kind": "wrist", "moved": value.moved, "blocked": value.blocked, "left": value.left,
                "contact_point": _array(value.contact_point)}  # fmt: skip
    if isinstance(value, Touch):
        return {"kind": "touch", "finger": value.finger, "point": _array(value.point),
                "normal": _array(value.normal), "force": value.force}  # fmt: skip
    if isinstance(value, FingerStep):
        return {"kind": "finger", "event": value.event, "angle": value.angle,
                "touch": None if value.touch is None else encode(value.touch)}  # fmt: skip
    if isinstance(value, TactileReading):
        return {"kind": "tactile", "finger": value.finger, "in_contact": value.in_contact,
                "point": _array(value.point), "normal": _array(value.normal),
                "point_tip": _array(value.point_tip), "force": value.force}  # fmt: skip
    if isinstance(value, ProbeOutcome):
        free = None if value.free is None else np.asarray(value.free).tolist()
        return {"kind": "probe", "event": value.event, "finger": value.finger, "centre": _array(value.centre),
                "normal": _array(value.normal), "free": free, "travelled": value.travelled,
                "why": value.why}  # fmt: skip
    if isinstance(value, np.ndarray):
        return _array(value)
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, tuple):
        return [encode(v) for v in value]
    return value


def decode(data: Any) -> Any:
    """A protocol result from its JSON form (lists stay lists unless the kind says otherwise)."""
    if not isinstance(data, dict) or "kind" not in data:
        return data
    kind = data["kind"]
    if kind == "wrist":
        return WristMove(data["moved"], data["blocked"], data["left"], _vector(data["contact_point"]))
    if kind == "touch":
        return Touch(data["finger"], _vector(data["point"]), _vector(data["normal"]), data["force"])  # type: ignore[arg-type]
    if kind == "finger":
        return FingerStep(
            data["event"], data["angle"], None if data["touch"] is None else decode(data["touch"])
        )
    if kind == "tactile":
        return TactileReading(data["finger"], data["in_contact"], _vector(data["point"]),  # type: ignore[arg-type]
                              _vector(data["normal"]), _vector(data["point_tip"]), data["force"])  # type: ignore[arg-type]  # fmt: skip
    if kind == "probe":
        return ProbeOutcome(data["event"], data["finger"], _vector(data["centre"]), _vector(data["normal"]),
                            _vector(data["free"]), data["travelled"], data["why"])  # fmt: skip
    raise ValueError(f"unknown result kind {kind!r}")


def encode_samples(samples: tuple[CurvatureSample, ...]) -> list[dict[str, list[float] | None]]:
    """EP1's curvature samples as JSON."""
    return [
        {"omega_xy": _array(s.omega_xy), "u": _array(s.contact_velocity), "K_f": _array(s.K_f)}
        for s in samples
    ]
