"""Plan requests, validated at the edge: pure data shared by the library, ``eos plan`` and the
service; every rejection a :class:`~eos_svc.errors.ValidationError` naming the field and the
reason. The JSON form: ``docs/service.md`` (the wire adds ``schema`` and ``goal_id``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from eos_svc.errors import ValidationError
from eos_svc.ratings import Weights

#: object shapes and the size fields each one takes (SI units: metres)
SHAPE_SIZE_FIELDS: dict[str, tuple[str, ...]] = {
    "sphere": ("radius",),
    "ellipsoid": ("radii",),
    "cylinder": ("radius", "length"),
    "box": ("size",),
    "capsule": ("radius", "length"),
}
#: the mesh kind (:mod:`eos_svc.objects.mesh`): a file, or vertices and faces inline, and a scale
MESH = "mesh"
MESH_FIELDS = ("file", "vertices", "faces", "scale")
MESH_FILE_TYPES = (".obj", ".stl", ".ply")
#: the most vertices and triangles an inline mesh may have (a request stays small)
MAX_MESH_VERTICES = 5000
MAX_MESH_FACES = 10000
#: the scale bounds of a mesh (its file's units to metres: 1e-3 for millimetres)
MAX_MESH_SCALE = 1000.0
#: size fields holding three numbers
VECTOR_SIZE_FIELDS = frozenset({"radii", "size"})
#: largest object dimension accepted (m); anything bigger is not a hand-held object
MAX_OBJECT_SIZE = 1.0
#: largest |coordinate| of an object position accepted (m)
MAX_POSITION = 10.0
MAX_CYCLES_LIMIT = 100_000
MAX_DEADLINE_S = 3600.0
#: the worlds a plan can run in (:mod:`eos_svc.drivers.worlds`)
WORLDS = ("kinematic", "drake")
MAX_TACTILE_NOISE = 0.01
#: default and largest Coulomb friction coefficient μ at the fingertip contacts (grasp quality)
DEFAULT_FRICTION = 0.5
MAX_FRICTION = 10.0
#: largest joint-encoder noise σ a request may ask for (rad)
MAX_ENCODER_NOISE = 0.05
#: largest link-length calibration error σ a request may ask for (m)
MAX_LINK_ERROR = 0.005

#: most plug-in agents a request may name
MAX_PLUGINS = 16
#: longest plug-in name accepted (characters)
MAX_PLUGIN_NAME = 200

DEFAULT_OBJECT: dict[str, Any] = {"shape": "sphere", "radius": 0.03, "position": [0.21, 0.02, -0.015]}


def _number(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValidationError(name, f"must be a number, got {type(value).__name__}")
    v = float(value)
    if not math.isfinite(v):
        raise ValidationError(name, f"must be finite, got {v!r}")
    return v


def _positive(value: object, name: str, upper: float) -> float:
    v = _number(value, name)
    if v <= 0.0:
        raise ValidationError(name, f"must be > 0, got {v!r}")
    if v > upper:
        raise ValidationError(name, f"must be ≤ {upper}, got {v!r}")
    return v


def _vector3(value: object, name: str) -> tuple[float, float, float]:
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise ValidationError(name, f"must be a list of 3 numbers, got {type(value).__name__}")
    if len(value) != 3:
        raise ValidationError(name, f"must have 3 numbers, got {len(value)}")
    x, y, z = (_number(v, f"{name}[{i}]") for i, v in enumerate(value))
    return (x, y, z)


def _integer(value: object, name: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):  # 1e5 or 5.0 too: integers are integers
        raise ValidationError(name, f"must be an integer, got {type(value).__name__}")
    if not lo <= value <= hi:
        raise ValidationError(name, f"must be in [{lo}, {hi}], got {value}")
    return value


def _check_keys(data: Mapping[str, Any], allowed: set[str], prefix: str) -> None:
    for key in data:
        if key not in allowed:
            where = f"{prefix}.{key}" if prefix else str(key)
            raise ValidationError(where, f"unknown field (allowed: {', '.join(sorted(allowed))})")


def _plugin_names(value: object) -> tuple[str, ...]:
    """The request's plug-in names, checked: a list of distinct non-empty strings."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise ValidationError("agents", f"must be a list of plug-in names, got {type(value).__name__}")
    if len(value) > MAX_PLUGINS:
        raise ValidationError("agents", f"names at most {MAX_PLUGINS} plug-ins, got {len(value)}")
    for i, name in enumerate(value):
        if not isinstance(name, str) or not name or len(name) > MAX_PLUGIN_NAME:
            raise ValidationError(
                f"agents[{i}]", f"must be a plug-in name of 1 to {MAX_PLUGIN_NAME} characters"
            )
        if name in value[:i]:
            raise ValidationError(f"agents[{i}]", f"plug-in {name!r} is named twice")
    return tuple(value)


def mesh_size(size: Mapping[str, Any]) -> dict[str, Any]:
    """A mesh's size fields checked: ``file`` (an .obj, .stl or .ply path) or ``vertices`` and
    ``faces`` inline (at most :data:`MAX_MESH_VERTICES` / :data:`MAX_MESH_FACES`), and ``scale``
    (> 0, default 1). Errors name the field (``object.vertices[12][1]``) and the reason."""
    for key in size:
        if key not in MESH_FIELDS:
            raise ValidationError(f"object.{key}", f"not a field of a mesh (takes {', '.join(MESH_FIELDS)})")
    scale = _positive(size.get("scale", 1.0), "object.scale", MAX_MESH_SCALE)
    inline = "vertices" in size or "faces" in size
    if ("file" in size) == inline:
        raise ValidationError("object.file", "a mesh takes either a file or vertices and faces inline")
    if not inline:
        file = size["file"]
        if not isinstance(file, str) or not file.lower().endswith(MESH_FILE_TYPES):
            raise ValidationError("object.file", f"must be a path ending in {', '.join(MESH_FILE_TYPES)}")
        return {"file": file, "scale": scale}
    for key in ("vertices", "faces"):
        if key not in size:
            raise ValidationError(f"object.{key}", "is required with an inline mesh")
    vertices, faces = size["vertices"], size["faces"]
    for key, rows, limit in (("vertices", vertices, MAX_MESH_VERTICES), ("faces", faces, MAX_MESH_FACES)):
        if not isinstance(rows, (list, tuple)) or len(rows) < 4:
            raise ValidationError(f"object.{key}", "must be a list of at least 4 triples")
        if len(rows) > limit:
            raise ValidationError(f"object.{key}", f"{len(rows)} {key} exceed the limit of {limit}")
    V = tuple(_vector3(v, f"object.vertices[{i}]") for i, v in enumerate(vertices))
    F = []
    for i, f in enumerate(faces):
        if not isinstance(f, (list, tuple)) or len(f) != 3:
            raise ValidationError(f"object.faces[{i}]", "must be 3 vertex indices")
        F.append(tuple(_integer(k, f"object.faces[{i}][{j}]", 0, len(V) - 1) for j, k in enumerate(f)))
    extent = max(max(v[a] for v in V) - min(v[a] for v in V) for a in range(3)) * scale
    if extent > MAX_OBJECT_SIZE:
        raise ValidationError("object.vertices", f"the mesh spans {extent:.3f} m > {MAX_OBJECT_SIZE} m")
    return {"vertices": V, "faces": tuple(F), "scale": scale}


@dataclass(frozen=True)
class ObjectSpec:
    """The object to grasp: a ``shape`` of :data:`SHAPE_SIZE_FIELDS` or :data:`MESH`
    (:func:`mesh_size`), its ``size`` fields (m; e.g. ``{"radius": 0.03}``, a box's full edge
    lengths ``{"size": (0.05, 0.05, 0.05)}``), its centre's world ``position`` (m) and ``rpy`` (rad).
    """

    shape: str = "sphere"
    size: Mapping[str, Any] = field(default_factory=lambda: {"radius": 0.03})
    position: tuple[float, float, float] = (0.21, 0.02, -0.015)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.shape == MESH:
            object.__setattr__(self, "size", mesh_size(self.size))
            self._check_pose()
            return
        if self.shape not in SHAPE_SIZE_FIELDS:
            raise ValidationError(
                "object.shape",
                f"unknown shape {self.shape!r} (choose from {', '.join((*SHAPE_SIZE_FIELDS, MESH))})",
            )
        wanted = SHAPE_SIZE_FIELDS[self.shape]
        clean: dict[str, Any] = {}
        for key in wanted:
            if key not in self.size:
                raise ValidationError(f"object.{key}", f"is required for a {self.shape}")
            value = self.size[key]
            if key in VECTOR_SIZE_FIELDS:
                vec = _vector3(value, f"object.{key}")
                for i, v in enumerate(vec):
                    _positive(v, f"object.{key}[{i}]", MAX_OBJECT_SIZE)
                clean[key] = vec
            else:
                clean[key] = _positive(value, f"object.{key}", MAX_OBJECT_SIZE)
        for key in self.size:
            if key not in wanted:
                raise ValidationError(
                    f"object.{key}", f"not a size of a {self.shape} (takes {', '.join(wanted)})"
                )
        object.__setattr__(self, "size", clean)
        self._check_pose()

    def _check_pose(self) -> None:
        position = _vector3(self.position, "object.position")
        for i, v in enumerate(position):
            if abs(v) > MAX_POSITION:
                raise ValidationError(f"object.position[{i}]", f"must be within ±{MAX_POSITION} m, got {v}")
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "rpy", _vector3(self.rpy, "object.rpy"))

    @property
    def diameter(self) -> float:
        """Characteristic diameter (m): the sphere's 2R, otherwise the largest extent across the grip."""
        s = self.size
        if self.shape == MESH:  # the mesh's own: it must be read
            from eos_svc.objects import make

            return make(self.shape, s, self.position, self.rpy).diameter
        if self.shape == "sphere":
            return 2.0 * s["radius"]
        if self.shape == "ellipsoid":
            return 2.0 * max(s["radii"])
        if self.shape in ("cylinder", "capsule"):
            return 2.0 * s["radius"]
        return float(max(s["size"]))

    @classmethod
    def from_dict(cls, data: object, prefix: str = "object") -> ObjectSpec:
        """Validate and build from the JSON form."""
        if not isinstance(data, Mapping):
            raise ValidationError(prefix, f"must be an object, got {type(data).__name__}")
        if "shape" not in data:
            raise ValidationError(f"{prefix}.shape", "is required")
        shape = data["shape"]
        if not isinstance(shape, str):
            raise ValidationError(f"{prefix}.shape", f"must be a string, got {type(shape).__name__}")
        sizes = set(MESH_FIELDS) if shape == MESH else {k for v in SHAPE_SIZE_FIELDS.values() for k in v}
        _check_keys(data, {"shape", "position", "rpy", *sizes}, prefix)
        size = {k: data[k] for k in data if k in sizes}
        extra = sorted(set(size) - set(SHAPE_SIZE_FIELDS.get(shape, size)))
        if extra:
            raise ValidationError(
                f"{prefix}.{extra[0]}",
                f"not a size of a {shape} (takes {', '.join(SHAPE_SIZE_FIELDS[shape])})",
            )
        return cls(
            shape=shape,
            size=size,
            position=data.get("position", DEFAULT_OBJECT["position"]),
            rpy=data.get("rpy", (0.0, 0.0, 0.0)),
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        out: dict[str, Any] = {"shape": self.shape}
        for key, value in self.size.items():
            if key in ("vertices", "faces"):
                out[key] = [list(row) for row in value]
            else:
                out[key] = list(value) if isinstance(value, tuple) else value
        out["position"] = list(self.position)
        out["rpy"] = list(self.rpy)
        return out


#: the request's fields taken from the JSON form as they are (checked by ``PlanRequest``)
_PLAIN_FIELDS = (
    "seed",
    "tactile_noise",
    "max_cycles",
    "deadline_s",
    "friction",
    "encoder_noise",
    "link_error",
    "agents",
    "hand",
    "world",
)

#: a hand name a request may give (the registered hands' names are of this form)
_HAND_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")


@dataclass(frozen=True)
class Table:
    """A horizontal support surface under the object, its top at world z = ``height`` (m): no hand
    motion, probe or grasp goes below it."""

    height: float

    def __post_init__(self) -> None:
        z = _number(self.height, "table.height")
        if abs(z) > MAX_POSITION:
            raise ValidationError("table.height", f"must be within ±{MAX_POSITION} m, got {z}")
        object.__setattr__(self, "height", z)

    @classmethod
    def from_dict(cls, data: object) -> Table:
        """Validate and build from ``{"height": z}``."""
        if not isinstance(data, Mapping):
            raise ValidationError("table", f'must be an object {{"height": z}}, got {type(data).__name__}')
        _check_keys(data, {"height"}, "table")
        if "height" not in data:
            raise ValidationError("table.height", "is required")
        return cls(data["height"])

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"height": self.height}


@dataclass(frozen=True)
class PlanRequest:
    """A grasp-plan request.

    Attributes:
        obj: the object to grasp (``"object"`` in the JSON form).
        weights: weights of the sub-ratings.
        seed: seed of the run's random generator (search moves, tactile noise).
        tactile_noise: standard deviation of the tactile contact location (m).
        max_cycles: cycle limit of the run.
        deadline_s: wall-clock budget of the run (s), or ``None``.
        friction: Coulomb μ of the fingertip contacts, in [0, :data:`MAX_FRICTION`].
        world: one of :data:`WORLDS`: ``"kinematic"`` (exact, the object fixed) or ``"drake"``
            (the object a free body; success needs the lift test).
        agents: names of plug-in agents to add (an ``eos_svc.agents`` entry point or
            ``module:attr``), at most :data:`MAX_PLUGINS`, no name twice.
        encoder_noise: σ of every finger joint encoder's reading (rad), in [0, :data:`MAX_ENCODER_NOISE`].
        link_error: σ of every finger link's length error (m), in [0, :data:`MAX_LINK_ERROR`]
            (:mod:`eos_svc.world.joint_sensing`).
        hand: the name of a registered hand (``eos hands``), or ``None`` for the default hand.
        table: the support surface the object rests on, or ``None`` (the paper's scene).
    The JSON form leaves out ``world`` when kinematic and the others at their defaults.
    """

    obj: ObjectSpec = field(default_factory=ObjectSpec)
    weights: Weights = field(default_factory=Weights)
    seed: int = 1
    tactile_noise: float = 2e-4
    max_cycles: int = 2000
    deadline_s: float | None = 10.0
    friction: float = DEFAULT_FRICTION
    world: str = "kinematic"
    agents: tuple[str, ...] = ()
    encoder_noise: float = 0.0
    link_error: float = 0.0
    hand: str | None = None
    table: Table | None = None

    def __post_init__(self) -> None:
        if self.table is not None and not isinstance(self.table, Table):
            raise ValidationError("table", f"must be a Table or None, got {type(self.table).__name__}")
        if self.hand is not None and not (isinstance(self.hand, str) and _HAND_NAME.fullmatch(self.hand)):
            raise ValidationError(
                "hand", f"must be a hand name of 1-64 characters A-Z a-z 0-9 _ . -, got {self.hand!r}"
            )
        if not isinstance(self.obj, ObjectSpec):
            raise ValidationError("object", f"must be an ObjectSpec, got {type(self.obj).__name__}")
        if not isinstance(self.weights, Weights):
            raise ValidationError("weights", f"must be a Weights, got {type(self.weights).__name__}")
        object.__setattr__(self, "seed", _integer(self.seed, "seed", 0, 2**63 - 1))
        object.__setattr__(self, "max_cycles", _integer(self.max_cycles, "max_cycles", 1, MAX_CYCLES_LIMIT))
        if self.deadline_s is not None:
            object.__setattr__(self, "deadline_s", _positive(self.deadline_s, "deadline_s", MAX_DEADLINE_S))
        for name, upper, unit in (
            ("tactile_noise", MAX_TACTILE_NOISE, " m"),
            ("friction", MAX_FRICTION, ""),
            ("encoder_noise", MAX_ENCODER_NOISE, " rad"),
            ("link_error", MAX_LINK_ERROR, " m"),
        ):
            value = _number(getattr(self, name), name)
            if not 0.0 <= value <= upper:
                raise ValidationError(name, f"must be in [0, {upper}]{unit}, got {value}")
            object.__setattr__(self, name, value)
        if self.world not in WORLDS:
            raise ValidationError("world", f"must be one of {', '.join(WORLDS)}, got {self.world!r}")
        if self.agents:
            object.__setattr__(self, "agents", _plugin_names(self.agents))

    @classmethod
    def from_dict(cls, data: object) -> PlanRequest:
        """Validate and build from the JSON form (defaults for missing fields; a ValidationError
        naming the first offending field)."""
        if not isinstance(data, Mapping):
            raise ValidationError("request", f"must be a JSON object, got {type(data).__name__}")
        _check_keys(
            data,
            {"object", "weights", "table", *_PLAIN_FIELDS},
            "",
        )
        kwargs: dict[str, Any] = {}
        if data.get("table") is not None:
            kwargs["table"] = Table.from_dict(data["table"])
        if "object" in data:
            kwargs["obj"] = ObjectSpec.from_dict(data["object"])
        if "weights" in data:
            kwargs["weights"] = Weights.from_dict(data["weights"])
        for key in _PLAIN_FIELDS:
            if key in data:
                kwargs[key] = data[key]
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (round-trips through :meth:`from_dict`); ``encoder_noise`` and
        ``link_error`` only when not 0 (the exact kinematics, their default); ``table`` only when set."""
        out: dict[str, Any] = {
            "object": self.obj.to_dict(),
            "weights": self.weights.to_dict(),
            "seed": self.seed,
            "tactile_noise": self.tactile_noise,
            "max_cycles": self.max_cycles,
            "deadline_s": self.deadline_s,
            "friction": self.friction,
        }
        if self.world != "kinematic":
            out["world"] = self.world
        if self.agents:
            out["agents"] = list(self.agents)
        if self.encoder_noise:
            out["encoder_noise"] = self.encoder_noise
        if self.link_error:
            out["link_error"] = self.link_error
        if self.hand is not None:
            out["hand"] = self.hand
        if self.table is not None:  # absent in the paper's scene: the JSON form stays as it was
            out["table"] = self.table.to_dict()
        return out
