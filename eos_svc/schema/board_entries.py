"""The grasp planner's board entries: each one's type (JSON-able values, shapes as ``TypedDict``s)
and meaning in :data:`ENTRIES` (the table in ``docs/planner.md``); ``plan(..., check_board=True)``
checks every value written with :func:`check_entry`.
"""

import functools
import sys
import types
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, Union, get_args, get_origin

from eos_svc.errors import ContractError
from eos_svc.schema import keys

if sys.version_info >= (3, 11):
    from typing import NotRequired, TypedDict, get_type_hints, is_typeddict
else:  # pragma: no cover - Python 3.10: PEP 655's backport
    from typing_extensions import NotRequired, TypedDict, get_type_hints, is_typeddict

#: a point or a direction in the world frame (m; unit for a direction)
Vector = list[float]
#: what a finger is doing in the grasping stage
FingerState = Literal["open", "closing", "touching", "missed", "link"]


class CurvatureEntry(TypedDict):
    """EP1's curvature estimate of one side (``CurvatureEstimate.to_dict`` and where it rolled).

    Curvatures in 1/m, radii in m (``None`` for a flat direction or an unknown σ)."""

    form: list[list[float]]
    principal_curvatures: list[float]
    sigma_curvatures: list[float | None]
    radii: list[float | None]
    mean_curvature: float
    sigma_mean_curvature: float | None
    mean_radius: float | None
    relative_error: float | None
    rating: float
    flat: list[bool]
    n_samples: int
    residual_rms: float
    finger: str
    side: Literal["top", "bottom"]
    max_slip_speed: float


class SensedContact(TypedDict):
    """A contact EP1 sensed (world, m): which finger, the point, the object's outward normal."""

    finger: str
    point: Vector
    normal: Vector


class ApproachEntry(TypedDict):
    """The object's surface point nearest the hand and the unit direction from the hand to it."""

    point: Vector
    direction: Vector


# "class" cannot be a field name in the class syntax: the functional form declares the postulate.
ShapeEntry = TypedDict(
    "ShapeEntry",
    {
        "class": str,
        "grasp_radius": float | None,
        "diameter": float | None,
        "centre": list[float] | None,
        "confidence": float,
        "principal_curvatures": list[float],
        "curvature_radius": float | None,
        "needs": str | None,
        "object": NotRequired[dict[str, Any] | None],
        "pose_known": NotRequired[bool],
        "evidence": NotRequired[dict[str, Any]],
        "bounds": NotRequired[list[Vector] | None],
        "open_faces": NotRequired[list[dict[str, Any]]],
        "candidates": NotRequired[list[dict[str, Any]]],
        "approximate": NotRequired[bool],
        "located": NotRequired[dict[str, Any]],
        "relocations": NotRequired[int],
    },
)
ShapeEntry.__doc__ = """post_shape's postulate.

``class``, ``grasp_radius`` (vertical half-extent, m) and ``diameter`` (m; ``None`` until
sized), ``centre`` (world, m), ``confidence`` in [0, 1], the top's ``principal_curvatures``
(1/m) and ``curvature_radius`` (m, ``None`` when flat), ``needs`` (what post_shape asks for
next, or ``None``); optional: ``object`` (request form), ``pose_known``, ``evidence``,
``bounds`` ([lo, hi], m), ``open_faces`` (:mod:`eos_svc.shape.open_faces`), ``candidates``
(:mod:`eos_svc.shape.probe_information`), ``approximate`` (the touches' convex hull, or a fit
below the threshold after EP2's last round: planned on as it is); where the object can move,
``located`` and ``relocations`` (:mod:`eos_svc.agents.relocate`).
"""


class EP2Touch(TypedDict):
    """A contact an EP2 probe made (world, m): the face probed (``front``, ``top``, ``slide``, …),
    the finger, its tip centre, the sensed outward normal and the tip radius."""

    face: str
    finger: str
    centre: Vector
    normal: Vector
    radius: float


class LandingEntry(TypedDict):
    """Where a closing fingertip lands: its joint angle (rad), the point and the outward normal
    (world, m)."""

    angle: float
    point: Vector
    normal: Vector


class TargetEntry(TypedDict):
    """grasp_points' target (world, m, rad; the angle across the centre in deg): the grasp, each
    finger's chosen contact, the postulated object; ``repredicted`` once the wrist re-predicted."""

    wrist: Vector
    wrist_rpy: list[float]
    pregrasp: Vector
    centre: Vector
    approach: Vector
    closing: Vector
    grasp: str
    epsilon: float
    angle_deg: float
    contacts: dict[str, LandingEntry]
    object: dict[str, Any]
    pose_assumed_upright: bool
    postulate: str
    repredicted: NotRequired[bool]


class FingertipContact(TypedDict):
    """One fingertip as the end agent judged it: touching, distance (m), contact point and the
    object's outward normal there (world)."""

    touching: bool
    distance: float
    point: Vector
    normal: Vector


class OutcomeEntry(TypedDict):
    """The end agent's verdict (:func:`eos_svc.drivers.grip_verdict.grasp_geometry`; the angle
    across the centre in deg, ``None`` unless all touch; ``centre_rule``: ``"diameter"``, or
    ``"force closure"`` for a mesh)."""

    contacts: dict[str, FingertipContact]
    all_touching: bool
    good: bool
    about_diameter: bool
    centre_rule: str
    diameter_angle_deg: float | None
    quality: dict[str, Any]
    q_final: list[float]


@dataclass(frozen=True)
class Entry:
    """A board entry's declared type and meaning (SI units)."""

    type: Any
    meaning: str


#: every board entry of the grasp planner: name -> declared type and meaning
ENTRIES: dict[str, Entry] = {
    keys.LOCATED: Entry(bool, "the object is within the hand's envelope"),
    keys.GAP: Entry(float, "object surface to the grasp centre (m)"),
    keys.SEARCH_MOVES: Entry(int, "random search moves made"),
    keys.CURVATURE: Entry(CurvatureEntry, "EP1's curvature estimate of the object's top"),
    keys.CURVATURE_BOTTOM: Entry(CurvatureEntry, "the same on the object's bottom, when explored"),
    keys.EP1_RUNS: Entry(int, "EP1 runs so far"),
    keys.EP1_CONTACT: Entry(dict[str, SensedContact], "side (top, bottom) -> the contact EP1 sensed"),
    keys.EP2_TOUCHES: Entry(list[EP2Touch], "EP2's contacts"),
    keys.EP2_FREE: Entry(
        list[list[float]], "tip-centre samples [x, y, z, tip radius] of EP2 probes that touched nothing (m)"
    ),
    keys.EP2_RUNS: Entry(int, "EP2 rounds over the whole surface so far (active-touch rounds not counted)"),
    keys.HAND_Q: Entry(list[float], "the hand's configuration after the cycle (m, rad)"),
    keys.OBJECT_POSE: Entry(
        list[float],
        "a moving world's object pose after the cycle: x, y, z (m), quaternion w, x, y, z (viewers)",
    ),
    keys.HAND_PATH: Entry(
        list[list[float]], "the hand's configurations during an EP1 roll, sampled (for viewers)"
    ),
    keys.APPROACH: Entry(ApproachEntry, "the object's point nearest the hand, the direction to it"),
    keys.SHAPE: Entry(ShapeEntry, "post_shape's postulate"),
    keys.D_OVER_H: Entry(float, "estimated object diameter over hand height"),
    keys.TARGET: Entry(TargetEntry, "grasp_points' target"),
    keys.AT_TARGET: Entry(bool, "the wrist reached its grasp position"),
    keys.WRIST_LEFT: Entry(float, "distance left to the wrist's grasp position (m)"),
    keys.FINGER_STATE: Entry(dict[str, FingerState], "finger -> what it is doing"),
    keys.FINGER_ANGLE: Entry(dict[str, float], "finger -> its joints' angle (rad)"),
    keys.OUTCOME: Entry(OutcomeEntry, "the end agent's verdict"),
    keys.FRICTION: Entry(float, "Coulomb μ of the fingertip contacts (the request's)"),
    keys.RECALLED: Entry(str, "the grasp-memory key recall applied"),
}

#: entries written by others than the agents: entry -> who (the planner before the first cycle,
#: from the request)
OUTSIDE_WRITERS: dict[str, str] = {
    keys.FRICTION: "plan set-up",
    keys.HAND_Q: "PoseBoard, every cycle",
    keys.OBJECT_POSE: "PoseBoard, every cycle of a world whose object moves (Drake)",
}
#: entries the planner reads after the run, for its result and the grasp memory
AFTER_RUN: frozenset[str] = frozenset(
    {
        keys.OUTCOME,
        keys.SHAPE,
        keys.CURVATURE,
        keys.D_OVER_H,
        keys.EP1_RUNS,
        keys.TARGET,
        keys.EP1_CONTACT,
        keys.EP2_TOUCHES,
    }
)


# --- the runtime check --------------------------------------------------------------------
def check_entry(key: str, value: Any, extra: Mapping[str, Entry] | None = None) -> None:
    """Check ``value`` against entry ``key``'s declared type (in :data:`ENTRIES` or ``extra``, the
    plug-ins' own); a ContractError names the entry or the part at fault (``board.shape.confidence``)."""
    entry = ENTRIES.get(key)
    if entry is None and extra:
        entry = extra.get(key)
    if entry is None:
        raise ContractError(
            f"board.{key}", "no type is declared for this entry in eos_svc.schema.board_entries"
        )
    _check(value, entry.type, f"board.{key}")


@functools.cache
def _fields(typed: type) -> tuple[dict[str, Any], frozenset[str]]:
    """A TypedDict's field types and required keys."""
    return get_type_hints(typed), frozenset(typed.__required_keys__)  # type: ignore[attr-defined]


def _check(value: Any, tp: Any, field: str) -> None:
    if tp is Any:
        return
    if is_typeddict(tp):
        if not isinstance(value, dict):
            raise ContractError(field, f"must be a {tp.__name__} dict, got {type(value).__name__}")
        hints, required = _fields(tp)
        missing = sorted(required - value.keys())
        if missing:
            raise ContractError(field, f"missing required field(s) {missing} of {tp.__name__}")
        unknown = sorted(set(value) - hints.keys())
        if unknown:
            raise ContractError(field, f"field(s) {unknown} not declared in {tp.__name__}")
        for name, item in value.items():
            _check(item, hints[name], f"{field}.{name}")
        return
    origin = get_origin(tp)
    if origin is Union or origin is types.UnionType:
        for option in get_args(tp):
            try:
                _check(value, option, field)
                return
            except ContractError:
                continue
        raise ContractError(field, f"must be {type_name(tp)}, got {value!r:.60}")
    if origin is Literal:
        if value not in get_args(tp):
            raise ContractError(field, f"must be one of {list(get_args(tp))}, got {value!r}")
        return
    if origin is list:
        if not isinstance(value, (list, tuple)):
            raise ContractError(field, f"must be a list, got {type(value).__name__}")
        (item_type,) = get_args(tp)
        for i, item in enumerate(value):
            _check(item, item_type, f"{field}[{i}]")
        return
    if origin is dict:
        if not isinstance(value, dict):
            raise ContractError(field, f"must be a dict, got {type(value).__name__}")
        key_type, item_type = get_args(tp)
        for name, item in value.items():
            if not isinstance(name, key_type):
                raise ContractError(field, f"key {name!r} must be a {key_type.__name__}")
            _check(item, item_type, f"{field}.{name}")
        return
    if tp is None or tp is type(None):
        if value is not None:
            raise ContractError(field, f"must be None, got {value!r:.60}")
        return
    if tp is float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    elif tp is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
    else:
        ok = isinstance(value, tp)
    if not ok:
        name = type_name(tp)
        article = "an" if name[0] in "aeiou" else "a"
        raise ContractError(field, f"must be {article} {name}, got {type(value).__name__} {value!r:.60}")


# --- how a declared type reads ----------------------------------------------------------------
def type_name(tp: Any) -> str:
    """A declared type as the table and the errors print it (``FingerState`` by name)."""
    if tp == FingerState:  # an alias printed by name (``Vector`` is any ``list[float]``)
        return "FingerState"
    if tp is type(None) or tp is None:
        return "None"
    origin = get_origin(tp)
    if origin is Union or origin is types.UnionType:
        return " | ".join(type_name(a) for a in get_args(tp))
    if origin in (list, dict):
        return f"{origin.__name__}[{', '.join(type_name(a) for a in get_args(tp))}]"
    return getattr(tp, "__name__", str(tp))
