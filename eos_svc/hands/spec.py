"""A hand description file (TOML), read into plain checked data.

Every key is checked as it is read; a bad one raises
:class:`~eos_svc.kinematics.errors.HandDescriptionError` whose ``field`` is the key's path in
the file (``fingers[2].tip.radius``) and whose ``reason`` says what is wrong. The format is
documented key by key in ``docs/hands.md``. Units are SI (m, rad; a prismatic joint's
coordinate in m).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from eos_svc.kinematics.errors import HandDescriptionError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = [
    "CollisionSpec",
    "FingerSpec",
    "HandSpec",
    "PartSpec",
    "TipSpec",
    "UrdfSource",
    "WristSpec",
    "parse_hand",
    "read_hand_file",
]

#: the ways a description names its URDF (exactly one per ``urdf`` table)
URDF_SOURCE_KINDS = ("data", "example_robot_data", "path")
#: collision primitives a description may add (sizes in m)
COLLISION_SHAPES = {"sphere": ("radius",), "box": ("size",), "cylinder": ("radius", "length")}
#: the world parameters a description may set (see :class:`~eos_svc.world.parameters.WorldParameters`)
WORLD_KEYS = {
    "search_box_lo": 3,
    "search_box_hi": 3,
    "grasp_centre": 3,
    "hand_bound": 0,
    "envelope_radius": 0,
    "approach_distance": 0,
    "finger_step": 0,
    "wrist_step": 0,
    "clearance": 0,
    "landing_tolerance": 0,
    "contact_patch_radius": 0,
}
#: the Drake validation's physical settings a description may set
DRAKE_KEYS = ("kp", "kd", "squeeze")
#: the six joints of an added floating wrist, in order, with their default (lower, upper,
#: effort, velocity): x, y, z prismatic (m, N, m/s), then roll, pitch, yaw revolute (rad, N·m, rad/s)
WRIST_AXES: dict[str, tuple[float, float, float, float]] = {
    "x": (-0.5, 0.5, 50.0, 0.5),
    "y": (-0.5, 0.5, 50.0, 0.5),
    "z": (-0.5, 0.5, 50.0, 0.5),
    "roll": (-math.pi, math.pi, 5.0, 2.0),
    "pitch": (-math.pi / 2, math.pi / 2, 5.0, 2.0),
    "yaw": (-math.pi / 2, math.pi / 2, 5.0, 2.0),
}


@dataclass(frozen=True)
class UrdfSource:
    """Where a URDF is: ``data`` (a file shipped with eos_svc), ``example_robot_data`` (a file
    of the installed example-robot-data, relative to its ``share/example-robot-data``) or
    ``path`` (a file, relative to the description file's directory)."""

    kind: str
    name: str
    base_dir: Path | None = None


@dataclass(frozen=True)
class PartSpec:
    """One URDF placed on the palm: its links and joints prefixed with ``prefix``, its
    ``root_link`` fixed to the palm at ``xyz`` (m) / ``rpy`` (rad)."""

    urdf: UrdfSource
    root_link: str
    prefix: str = ""
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    where: str = ""  # its key in the description: "parts[1]", or "" for the top-level keys


@dataclass(frozen=True)
class TipSpec:
    """A fingertip sphere: either the URDF's own (``frame`` at its centre, ``geometry`` its
    collision name) or added on ``link`` at ``xyz`` (m) by the builder."""

    radius: float
    frame: str | None = None
    geometry: str | None = None
    link: str | None = None
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class FingerSpec:
    """A finger: its joints palm outward, each joint's closing direction (+1 or −1), its tip."""

    name: str
    joints: tuple[str, ...]
    closing: tuple[int, ...]
    tip: TipSpec


@dataclass(frozen=True)
class WristSpec:
    """The wrist: the URDF's own six 1-DoF joints (``joints``, ``palm_frame``) or, when
    ``floating``, six joints ``wrist_x`` … ``wrist_yaw`` and a ``palm`` link added in front of
    the parts, each with its (lower, upper, effort, velocity) in ``limits``."""

    floating: bool
    joints: tuple[str, ...] = ()
    palm_frame: str = "palm"
    limits: dict[str, tuple[float, float, float, float]] = field(default_factory=lambda: dict(WRIST_AXES))


@dataclass(frozen=True)
class CollisionSpec:
    """A collision primitive added to ``link`` (after the URDF's own on that link are removed
    when the link is listed in ``collision.replace``)."""

    link: str
    shape: str
    size: dict[str, Any]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class HandSpec:
    """A whole hand description (see ``docs/hands.md`` for every key)."""

    name: str
    summary: str
    parts: tuple[PartSpec, ...]
    wrist: WristSpec
    fingers: tuple[FingerSpec, ...]
    opposing_finger: str
    preshape: dict[str, float] = field(default_factory=dict)
    limits: dict[str, dict[str, float]] = field(default_factory=dict)
    collision_replace: tuple[str, ...] = ()
    collision_add: tuple[CollisionSpec, ...] = ()
    world: dict[str, Any] = field(default_factory=dict)
    drake: dict[str, float] = field(default_factory=dict)
    source: Path | None = None

    @property
    def finger_names(self) -> tuple[str, ...]:
        """Finger names in description order."""
        return tuple(f.name for f in self.fingers)


# -- reading helpers: each names the key it reads
def _fail(key: str, reason: str) -> HandDescriptionError:
    return HandDescriptionError(key, reason)


def _table(data: Mapping[str, Any], key: str, where: str, required: bool = False) -> dict[str, Any]:
    value = data.get(key)
    if value is None:
        if required:
            raise _fail(where, "is required (a table)")
        return {}
    if not isinstance(value, Mapping):
        raise _fail(where, f"must be a table, got {type(value).__name__}")
    return dict(value)


def _str(data: Mapping[str, Any], key: str, where: str, default: str | None = None) -> str:
    value = data.get(key, default)
    if value is None:
        raise _fail(where, "is required (a string)")
    if not isinstance(value, str) or not value:
        raise _fail(where, f"must be a non-empty string, got {value!r}")
    return value


def _number(value: Any, where: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
        raise _fail(where, f"must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise _fail(where, f"must be > 0, got {value!r}")
    return float(value)


def _vector(value: Any, where: str, n: int = 3) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise _fail(where, f"must be a list of {n} numbers, got {value!r}")
    return tuple(_number(v, f"{where}[{i}]") for i, v in enumerate(value))


def _names(value: Any, where: str) -> tuple[str, ...]:
    if not isinstance(value, (list, tuple)) or not value:
        raise _fail(where, f"must be a non-empty list of names, got {value!r}")
    for i, v in enumerate(value):
        if not isinstance(v, str) or not v:
            raise _fail(f"{where}[{i}]", f"must be a non-empty string, got {v!r}")
    if len(set(value)) != len(value):
        raise _fail(where, f"repeats a name: {list(value)}")
    return tuple(value)


def _unknown(data: Mapping[str, Any], known: tuple[str, ...], where: str) -> None:
    for key in data:
        if key not in known:
            prefix = f"{where}." if where else ""
            raise _fail(f"{prefix}{key}", f"is not a known key (known: {', '.join(known)})")


# -- the parts of a description
def _urdf_source(value: Any, where: str, base_dir: Path | None) -> UrdfSource:
    if not isinstance(value, Mapping):
        raise _fail(where, "must be a table with one of: " + ", ".join(URDF_SOURCE_KINDS))
    _unknown(value, URDF_SOURCE_KINDS, where)
    kinds = [k for k in URDF_SOURCE_KINDS if k in value]
    if len(kinds) != 1:
        raise _fail(where, "must give exactly one of: " + ", ".join(URDF_SOURCE_KINDS))
    return UrdfSource(kinds[0], _str(value, kinds[0], f"{where}.{kinds[0]}"), base_dir)


def _part(data: Mapping[str, Any], where: str, base_dir: Path | None) -> PartSpec:
    """One URDF and its mount (``where``: ``parts[i]``, or ``""`` for the top-level keys)."""
    key = (lambda name: f"{where}.{name}") if where else (lambda name: name)
    _unknown(data, ("urdf", "root_link", "prefix", "mount"), where)
    if "urdf" not in data:
        raise _fail(key("urdf"), "is required: a table with one of " + ", ".join(URDF_SOURCE_KINDS))
    mount = _table(data, "mount", key("mount"))
    _unknown(mount, ("xyz", "rpy"), key("mount"))
    prefix = data.get("prefix", "")
    if not isinstance(prefix, str):
        raise _fail(key("prefix"), f"must be a string, got {prefix!r}")
    return PartSpec(
        urdf=_urdf_source(data["urdf"], key("urdf"), base_dir),
        root_link=_str(data, "root_link", key("root_link"), default="") if "root_link" in data else "",
        prefix=prefix,
        xyz=_vector(mount.get("xyz", [0, 0, 0]), key("mount.xyz")),  # type: ignore[arg-type]
        rpy=_vector(mount.get("rpy", [0, 0, 0]), key("mount.rpy")),  # type: ignore[arg-type]
        where=where,
    )


def _limits4(value: Any, where: str) -> tuple[float, float, float, float]:
    lo, hi, effort, velocity = _vector(value, where, 4)
    if not lo < hi or effort <= 0 or velocity <= 0:
        raise _fail(
            where, "must be [lower, upper, effort, velocity] with lower < upper, effort and velocity > 0"
        )
    return lo, hi, effort, velocity


def _wrist(data: Mapping[str, Any]) -> WristSpec:
    _unknown(data, ("floating", "joints", "palm_frame", *WRIST_AXES), "wrist")
    floating = data.get("floating", False)
    if not isinstance(floating, bool):
        raise _fail("wrist.floating", f"must be true or false, got {floating!r}")
    if floating:
        if "joints" in data:
            raise _fail(
                "wrist.joints", "a floating wrist adds its own joints: give joints or floating, not both"
            )
        limits = {axis: _limits4(data.get(axis, list(d)), f"wrist.{axis}") for axis, d in WRIST_AXES.items()}
        return WristSpec(floating=True, joints=tuple(f"wrist_{a}" for a in WRIST_AXES), limits=limits)
    for axis in WRIST_AXES:
        if axis in data:
            raise _fail(f"wrist.{axis}", "only a floating wrist's limits are set here (else: the URDF's)")
    if "joints" not in data:
        raise _fail("wrist", "needs floating = true or the URDF's six wrist joints (joints = [...])")
    joints = _names(data["joints"], "wrist.joints")
    if len(joints) != 6:
        raise _fail(
            "wrist.joints", f"must name six 1-DoF joints (x, y, z, roll, pitch, yaw), got {len(joints)}"
        )
    return WristSpec(floating=False, joints=joints, palm_frame=_str(data, "palm_frame", "wrist.palm_frame"))


def _tip(data: Mapping[str, Any], where: str) -> TipSpec:
    _unknown(data, ("radius", "frame", "geometry", "link", "xyz"), where)
    radius = _number(data.get("radius"), f"{where}.radius", positive=True)
    if ("frame" in data) == ("link" in data):
        raise _fail(where, "must give either frame (the URDF's tip sphere) or link (a sphere added there)")
    if "frame" in data:
        geometry = data.get("geometry")
        if geometry is not None and (not isinstance(geometry, str) or not geometry):
            raise _fail(f"{where}.geometry", f"must be a non-empty string, got {geometry!r}")
        return TipSpec(radius, frame=_str(data, "frame", f"{where}.frame"), geometry=geometry)
    if "geometry" in data:
        raise _fail(f"{where}.geometry", "an added tip (link = ...) makes its own geometry")
    xyz = _vector(data.get("xyz", [0, 0, 0]), f"{where}.xyz")
    return TipSpec(radius, link=_str(data, "link", f"{where}.link"), xyz=xyz)  # type: ignore[arg-type]


def _finger(data: Any, where: str) -> FingerSpec:
    if not isinstance(data, Mapping):
        raise _fail(where, f"must be a table, got {type(data).__name__}")
    _unknown(data, ("name", "joints", "closing", "tip"), where)
    joints = _names(data.get("joints"), f"{where}.joints")
    closing_raw = data.get("closing", [1] * len(joints))
    if not isinstance(closing_raw, list) or len(closing_raw) != len(joints):
        raise _fail(f"{where}.closing", f"must list one direction (1 or -1) per joint ({len(joints)})")
    closing = []
    for i, c in enumerate(closing_raw):
        if isinstance(c, bool) or c not in (1, -1):
            raise _fail(f"{where}.closing[{i}]", f"must be 1 or -1, got {c!r}")
        closing.append(int(c))
    return FingerSpec(
        name=_str(data, "name", f"{where}.name"),
        joints=joints,
        closing=tuple(closing),
        tip=_tip(_table(data, "tip", f"{where}.tip", required=True), f"{where}.tip"),
    )


def _collision_add(data: Any, where: str) -> CollisionSpec:
    if not isinstance(data, Mapping):
        raise _fail(where, f"must be a table, got {type(data).__name__}")
    _unknown(data, ("link", "shape", "radius", "length", "size", "xyz", "rpy"), where)
    shape = _str(data, "shape", f"{where}.shape")
    if shape not in COLLISION_SHAPES:
        raise _fail(f"{where}.shape", f"must be one of {', '.join(COLLISION_SHAPES)}, got {shape!r}")
    size: dict[str, Any] = {}
    for key in COLLISION_SHAPES[shape]:
        if key == "size":
            size[key] = _vector(data.get(key), f"{where}.size")
            if min(size[key]) <= 0:
                raise _fail(f"{where}.size", "every edge must be > 0 m")
        else:
            size[key] = _number(data.get(key), f"{where}.{key}", positive=True)
    return CollisionSpec(
        link=_str(data, "link", f"{where}.link"),
        shape=shape,
        size=size,
        xyz=_vector(data.get("xyz", [0, 0, 0]), f"{where}.xyz"),  # type: ignore[arg-type]
        rpy=_vector(data.get("rpy", [0, 0, 0]), f"{where}.rpy"),  # type: ignore[arg-type]
    )


def _numbers_table(data: Mapping[str, Any], where: str) -> dict[str, float]:
    return {str(k): _number(v, f"{where}.{k}") for k, v in data.items()}


def _world(data: Mapping[str, Any]) -> dict[str, Any]:
    _unknown(data, tuple(WORLD_KEYS), "world")
    out: dict[str, Any] = {}
    for key, value in data.items():
        n = WORLD_KEYS[key]
        out[key] = _vector(value, f"world.{key}", n) if n else _number(value, f"world.{key}", positive=True)
    return out


def parse_hand(data: Mapping[str, Any], source: Path | None = None) -> HandSpec:
    """A :class:`HandSpec` from a parsed TOML table (``source``: the file, for relative paths).

    Raises:
        HandDescriptionError: naming the first bad key (``fingers[1].joints``, ``wrist``, …).
    """
    known = (
        "name",
        "summary",
        "urdf",
        "root_link",
        "mount",
        "parts",
        "wrist",
        "fingers",
        "opposing_finger",
        "preshape",
        "limits",
        "collision",
        "world",
        "drake",
    )
    _unknown(data, known, "")
    base_dir = source.parent if source is not None else None
    if "parts" in data:
        if "urdf" in data or "root_link" in data or "mount" in data:
            raise _fail(
                "urdf", "give the URDF either at the top (urdf, root_link, mount) or in [[parts]], not both"
            )
        raw_parts = data["parts"]
        if not isinstance(raw_parts, list) or not raw_parts:
            raise _fail("parts", "must be a non-empty array of tables ([[parts]])")
        parts = tuple(_part(p, f"parts[{i}]", base_dir) for i, p in enumerate(raw_parts))
    else:
        parts = (_part({k: data[k] for k in ("urdf", "root_link", "mount") if k in data}, "", base_dir),)
    wrist = _wrist(_table(data, "wrist", "wrist", required=True))
    for i, p in enumerate(parts):
        if wrist.floating and not p.root_link:
            raise _fail(
                f"parts[{i}].root_link" if "parts" in data else "root_link",
                "is required: a floating wrist needs the link each URDF is fixed to the palm by",
            )
    if not wrist.floating and (len(parts) != 1 or parts[0].prefix or parts[0].xyz != (0.0, 0.0, 0.0)):
        raise _fail("parts", "a hand with its own wrist joints is one URDF, unprefixed and unmoved")
    raw_fingers = data.get("fingers")
    if not isinstance(raw_fingers, list) or len(raw_fingers) < 2:
        raise _fail("fingers", "must be an array of at least two tables ([[fingers]])")
    fingers = tuple(_finger(f, f"fingers[{i}]") for i, f in enumerate(raw_fingers))
    names = [f.name for f in fingers]
    if len(set(names)) != len(names):
        raise _fail("fingers", f"repeats a finger name: {names}")
    opposing = _str(data, "opposing_finger", "opposing_finger")
    if opposing not in names:
        raise _fail("opposing_finger", f"{opposing!r} is not one of the fingers {names}")
    limits: dict[str, dict[str, float]] = {}
    for joint, table in _table(data, "limits", "limits").items():
        where = f"limits.{joint}"
        if not isinstance(table, Mapping):
            raise _fail(where, "must be a table of lower, upper, effort, velocity")
        _unknown(table, ("lower", "upper", "effort", "velocity"), where)
        limits[joint] = {
            k: _number(v, f"{where}.{k}", positive=k in ("effort", "velocity")) for k, v in table.items()
        }
        if limits[joint].get("lower", -math.inf) >= limits[joint].get("upper", math.inf):
            raise _fail(where, "lower must be < upper")
    collision = _table(data, "collision", "collision")
    _unknown(collision, ("replace", "add"), "collision")
    replace = _names(collision["replace"], "collision.replace") if "replace" in collision else ()
    adds = collision.get("add", [])
    if not isinstance(adds, list):
        raise _fail("collision.add", "must be an array of tables ([[collision.add]])")
    drake = _numbers_table(_table(data, "drake", "drake"), "drake")
    _unknown(drake, DRAKE_KEYS, "drake")
    return HandSpec(
        name=_str(data, "name", "name"),
        summary=str(data.get("summary", "")),
        parts=parts,
        wrist=wrist,
        fingers=fingers,
        opposing_finger=opposing,
        preshape=_numbers_table(_table(data, "preshape", "preshape"), "preshape"),
        limits=limits,
        collision_replace=replace,
        collision_add=tuple(_collision_add(c, f"collision.add[{i}]") for i, c in enumerate(adds)),
        world=_world(_table(data, "world", "world")),
        drake=drake,
        source=source,
    )


def read_hand_file(path: str | Path) -> HandSpec:
    """Read and check a hand description file.

    Raises:
        HandDescriptionError: ``file`` when it cannot be read or is not TOML; else the bad key.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise _fail("file", f"cannot read {p}: {exc.strerror or exc}") from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _fail("file", f"{p} is not valid TOML: {exc}") from exc
    return parse_hand(data, source=p.resolve())
