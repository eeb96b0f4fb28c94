"""Plan requests: what a caller asks the grasp planner for, validated at the edge.

Pure data and validation (no Pinocchio, no Zenoh), shared by the library call,
the ``eos plan`` command line and the Zenoh service. Every rejection is a
:class:`~eos_svc.errors.ValidationError` naming the field (dotted path) and the
reason.

JSON form (the service's wire format adds ``schema`` and ``goal_id``)::

    {"object": {"shape": "sphere", "radius": 0.03, "position": [0.22, 0.0, 0.0]},
     "weights": {"default": 0.5, "opportunistic": 0.5},
     "seed": 1, "tactile_noise": 0.0002, "max_cycles": 2000, "deadline_s": 10.0,
     "friction": 0.5}
"""

from __future__ import annotations

import math
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
    x, y, z = value
    if type(x) is float and type(y) is float and type(z) is float and math.isfinite(x + y + z):
        return (x, y, z)  # the common case, without building three field names
    x, y, z = (_number(v, f"{name}[{i}]") for i, v in enumerate(value))
    return (x, y, z)


def _integer(value: object, name: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise ValidationError(name, f"must be an integer, got {type(value).__name__}")
    if not lo <= value <= hi:
        raise ValidationError(name, f"must be in [{lo}, {hi}], got {value}")
    return value


def _check_keys(data: Mapping[str, Any], allowed: set[str], prefix: str) -> None:
    for key in data:
        if key not in allowed:
            where = f"{prefix}.{key}" if prefix else str(key)
            raise ValidationError(where, f"unknown field (allowed: {', '.join(sorted(allowed))})")


@dataclass(frozen=True)
class ObjectSpec:
    """The object to grasp: a primitive shape at a pose (metres, radians).

    Attributes:
        shape: one of :data:`SHAPE_SIZE_FIELDS`.
        size: the shape's size fields, e.g. ``{"radius": 0.03}`` or
            ``{"size": (0.05, 0.05, 0.05)}`` (box: full edge lengths).
        position: centre in the world frame (m).
        rpy: orientation as roll, pitch, yaw (rad).
    """

    shape: str = "sphere"
    size: Mapping[str, Any] = field(default_factory=lambda: {"radius": 0.03})
    position: tuple[float, float, float] = (0.21, 0.02, -0.015)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.shape not in SHAPE_SIZE_FIELDS:
            raise ValidationError(
                "object.shape", f"unknown shape {self.shape!r} (choose from {', '.join(SHAPE_SIZE_FIELDS)})"
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
        position = _vector3(self.position, "object.position")
        for i, v in enumerate(position):
            if abs(v) > MAX_POSITION:
                raise ValidationError(f"object.position[{i}]", f"must be within ±{MAX_POSITION} m, got {v}")
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "rpy", _vector3(self.rpy, "object.rpy"))

    @classmethod
    def from_checked(
        cls,
        shape: str,
        size: dict[str, Any],
        position: tuple[float, float, float],
        rpy: tuple[float, float, float],
    ) -> ObjectSpec:
        """Build from values already checked exactly as ``__post_init__`` checks them, without
        checking them again: ``size`` holds the shape's size fields in :data:`SHAPE_SIZE_FIELDS`
        order (floats; tuples of 3 floats for :data:`VECTOR_SIZE_FIELDS`), all floats finite and
        within the bounds. For a decoder that enforced those constraints itself (the service's
        typed wire decoder, :mod:`eos_svc.service.request_wire`); anyone else: the constructor."""
        spec = object.__new__(cls)
        spec.__dict__.update(shape=shape, size=size, position=position, rpy=rpy)  # frozen: no setattr
        return spec

    @property
    def diameter(self) -> float:
        """Characteristic diameter (m): the sphere's 2R, otherwise the largest extent across the grip."""
        s = self.size
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
        size_fields = set(SHAPE_SIZE_FIELDS.get(shape, ()))
        all_sizes = {k for v in SHAPE_SIZE_FIELDS.values() for k in v}
        _check_keys(data, {"shape", "position", "rpy"} | all_sizes, prefix)
        size = {k: data[k] for k in data if k in all_sizes}
        extra = set(size) - size_fields
        if shape in SHAPE_SIZE_FIELDS and extra:
            key = sorted(extra)[0]
            raise ValidationError(
                f"{prefix}.{key}", f"not a size of a {shape} (takes {', '.join(SHAPE_SIZE_FIELDS[shape])})"
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
            out[key] = list(value) if isinstance(value, tuple) else value
        out["position"] = list(self.position)
        out["rpy"] = list(self.rpy)
        return out


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
        friction: Coulomb friction coefficient μ of the fingertip contacts, in
            [0, :data:`MAX_FRICTION`]; the end agent's force-closure test and ε use it.
        world: where the hand acts, one of :data:`WORLDS`: ``"kinematic"`` (exact, the object
            fixed) or ``"drake"`` (the object a free body on a table; success needs the lift
            test). The JSON form carries it only when it is not ``"kinematic"``.
    """

    obj: ObjectSpec = field(default_factory=ObjectSpec)
    weights: Weights = field(default_factory=Weights)
    seed: int = 1
    tactile_noise: float = 2e-4
    max_cycles: int = 2000
    deadline_s: float | None = 10.0
    friction: float = DEFAULT_FRICTION
    world: str = "kinematic"

    def __post_init__(self) -> None:
        if not isinstance(self.obj, ObjectSpec):
            raise ValidationError("object", f"must be an ObjectSpec, got {type(self.obj).__name__}")
        if not isinstance(self.weights, Weights):
            raise ValidationError("weights", f"must be a Weights, got {type(self.weights).__name__}")
        object.__setattr__(self, "seed", _integer(self.seed, "seed", 0, 2**63 - 1))
        noise = _number(self.tactile_noise, "tactile_noise")
        if not 0.0 <= noise <= MAX_TACTILE_NOISE:
            raise ValidationError("tactile_noise", f"must be in [0, {MAX_TACTILE_NOISE}] m, got {noise}")
        object.__setattr__(self, "tactile_noise", noise)
        object.__setattr__(self, "max_cycles", _integer(self.max_cycles, "max_cycles", 1, MAX_CYCLES_LIMIT))
        if self.deadline_s is not None:
            object.__setattr__(self, "deadline_s", _positive(self.deadline_s, "deadline_s", MAX_DEADLINE_S))
        mu = _number(self.friction, "friction")
        if not 0.0 <= mu <= MAX_FRICTION:
            raise ValidationError("friction", f"must be in [0, {MAX_FRICTION}], got {mu}")
        object.__setattr__(self, "friction", mu)
        if self.world not in WORLDS:
            raise ValidationError("world", f"must be one of {', '.join(WORLDS)}, got {self.world!r}")

    @classmethod
    def from_checked(
        cls,
        obj: ObjectSpec,
        weights: Weights,
        seed: int,
        tactile_noise: float,
        max_cycles: int,
        deadline_s: float | None,
        friction: float,
    ) -> PlanRequest:
        """Build from values already checked exactly as ``__post_init__`` checks them (ints for
        ``seed`` and ``max_cycles``, floats otherwise, all within their bounds), without checking
        them again; see :meth:`ObjectSpec.from_checked`."""
        request = object.__new__(cls)
        request.__dict__.update(
            obj=obj,
            weights=weights,
            seed=seed,
            tactile_noise=tactile_noise,
            max_cycles=max_cycles,
            deadline_s=deadline_s,
            friction=friction,
        )
        return request

    @classmethod
    def from_dict(cls, data: object) -> PlanRequest:
        """Validate and build from the JSON form; missing fields take their defaults.

        Raises:
            ValidationError: naming the first offending field.
        """
        if not isinstance(data, Mapping):
            raise ValidationError("request", f"must be a JSON object, got {type(data).__name__}")
        _check_keys(
            data,
            {"object", "weights", "seed", "tactile_noise", "max_cycles", "deadline_s", "friction", "world"},
            "",
        )
        kwargs: dict[str, Any] = {}
        if "object" in data:
            kwargs["obj"] = ObjectSpec.from_dict(data["object"])
        if "weights" in data:
            kwargs["weights"] = Weights.from_dict(data["weights"])
        for key in ("seed", "tactile_noise", "max_cycles", "deadline_s", "friction", "world"):
            if key in data:
                kwargs[key] = data[key]
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (round-trips through :meth:`from_dict`)."""
        out = {
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
        return out
