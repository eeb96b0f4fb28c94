"""The batch spec: a dataset run described in a TOML file (see ``docs/batch.md``).

Every field is checked when the file is read; a bad one raises
:class:`~eos_svc.errors.ValidationError` naming it in dotted form (``conditions.friction[1]``,
``objects.explicit[0].radius``, ``world``), before any plan runs. Condition values and explicit
objects are checked by the planner's own request validation (:meth:`PlanRequest.from_dict`).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from eos_svc.errors import ValidationError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10: the batch extra installs tomli
    import tomli as tomllib

#: suites ``objects.suite`` names (eos_svc.experiments.grasp_suite)
SUITES = ("fixed", "quick", "held_back")
#: worlds ``world`` accepts: the planner's kinematic world (Pinocchio + coal) and the Drake world
#: (:mod:`eos_svc.drivers.worlds`; its status ``success`` means the lift test held)
WORLDS = ("kinematic", "drake")
#: request fields a condition may vary, in the order they vary (the last fastest)
CONDITION_FIELDS = ("tactile_noise", "friction", "weights", "max_cycles", "deadline_s")
#: plans per Ray task by default: one with validation (≈ 1-2.5 s each), a chunk without
#: (a median plan is ≈ 30 ms, a task's round trip ≈ 2 ms; see benchmarks/bench_batch.py)
PLANS_PER_TASK_VALIDATED = 1
PLANS_PER_TASK_PLAN_ONLY = 8


@dataclass(frozen=True)
class DrawSpec:
    """A random draw (:func:`eos_svc.experiments.grasp_suite.random_draw`)."""

    count: int
    draw_seed: int
    sizes: tuple[float, float] = (0.15, 0.50)


@dataclass(frozen=True)
class ObjectsSpec:
    """Where the objects come from; all given sources are planned, in this order."""

    suites: tuple[str, ...] = ()
    held_back_per_class: int = 3
    draw: DrawSpec | None = None
    explicit: tuple[tuple[str, dict[str, Any]], ...] = ()  #: (label, object in the request's JSON form)


@dataclass(frozen=True)
class ValidateSpec:
    """The Drake validation of every planned grasp (:func:`eos_svc.validation.validate_grasp`)."""

    enabled: bool = False
    seconds: float = 1.5  #: load time per direction (s)
    directions: int = 6  #: how many of +x, -x, +y, -y, +z, -z


@dataclass(frozen=True)
class RunSpec:
    """How the batch runs (none of it changes a row)."""

    plans_per_task: int | None = None  #: None: by validation (PLANS_PER_TASK_*)
    rows_per_file: int = 1000  #: a Parquet file is written once this many rows are finished …
    flush_seconds: float = 30.0  #: … or this long after the last file (s), whichever first
    max_retries: int = 3  #: times a task is run again when its worker dies


@dataclass(frozen=True)
class BatchSpec:
    """A whole dataset run: objects × conditions × seeds × hands, each plan optionally validated."""

    name: str
    objects: ObjectsSpec
    seeds: tuple[int, ...] | None  #: None: a drawn object's own seed, 1 for the others
    conditions: dict[str, tuple[Any, ...]]  #: field -> the values it takes (one or more)
    hands: tuple[str, ...] = ("hand3x3",)
    world: str = "kinematic"
    validate: ValidateSpec = ValidateSpec()
    run: RunSpec = RunSpec()

    def plans_per_task(self) -> int:
        """Plans per Ray task: the run's choice, else by whether plans are validated."""
        if self.run.plans_per_task is not None:
            return self.run.plans_per_task
        return PLANS_PER_TASK_VALIDATED if self.validate.enabled else PLANS_PER_TASK_PLAN_ONLY


def load_spec(path: str | Path) -> BatchSpec:
    """Read and check a spec file (TOML).

    Raises:
        ValidationError: ``spec`` when the file cannot be read or is not TOML; else the field.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValidationError("spec", f"cannot read {str(path)!r}: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ValidationError("spec", f"{path}: not TOML: {exc}") from exc
    return spec_from_dict(data, default_name=path.stem)


def spec_from_dict(data: Mapping[str, Any], default_name: str = "batch") -> BatchSpec:
    """Check a parsed spec (the TOML file as a dict) and build it."""
    _keys(data, {"name", "world", "hands", "objects", "seeds", "conditions", "validate", "run"}, "")
    world = data.get("world", "kinematic")
    if world not in WORLDS:
        raise ValidationError("world", f"must be one of {', '.join(map(repr, WORLDS))}, got {world!r}")
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise ValidationError("name", f"must be a non-empty string, got {name!r}")
    validate = _validate(data.get("validate", {}))
    hands = _hands(data.get("hands", ["hand3x3"]))
    if "objects" not in data:
        raise ValidationError("objects", "missing: give a suite, a draw or explicit objects")
    return BatchSpec(
        name=name,
        objects=_objects(data["objects"]),
        seeds=_seeds(data["seeds"]) if "seeds" in data else None,
        conditions=_conditions(data.get("conditions", {})),
        hands=hands,
        world=world,
        validate=validate,
        run=_run(data.get("run", {})),
    )


def _keys(data: object, allowed: set[str], prefix: str) -> None:
    """``data`` is a table whose keys are all in ``allowed``."""
    if not isinstance(data, Mapping):
        raise ValidationError(prefix.rstrip(".") or "spec", f"must be a table, got {type(data).__name__}")
    for key in data:
        if key not in allowed:
            raise ValidationError(
                f"{prefix}{key}", f"unknown field; expected one of {', '.join(sorted(allowed))}"
            )


def _int(value: object, field: str, lo: int, hi: int = 2**63 - 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ValidationError(field, f"must be an integer in [{lo}, {hi}], got {value!r}")
    return value


def _float(value: object, field: str, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        raise ValidationError(field, f"must be a number in [{lo}, {hi}], got {value!r}")
    return float(value)


def _list(value: object, field: str) -> list[Any]:
    """A value or a list of values, as a non-empty list."""
    values = value if isinstance(value, list) else [value]
    if not values:
        raise ValidationError(field, "must not be empty")
    return values


def _hands(value: object) -> tuple[str, ...]:
    from eos_svc.hands import HandRegistry  # the registered hands (eos hands)

    known = HandRegistry().names
    hands = _list(value, "hands")
    for i, hand in enumerate(hands):
        if hand not in known:
            raise ValidationError(f"hands[{i}]", f"must be one of {', '.join(known)}, got {hand!r}")
    if len(set(hands)) != len(hands):
        raise ValidationError("hands", f"a hand named twice: {hands}")
    return tuple(hands)


def _objects(data: object) -> ObjectsSpec:
    _keys(data, {"suite", "per_class", "draw", "explicit"}, "objects.")
    assert isinstance(data, Mapping)
    suites = _list(data["suite"], "objects.suite") if "suite" in data else []
    for i, suite in enumerate(suites):
        if suite not in SUITES:
            raise ValidationError(f"objects.suite[{i}]", f"must be one of {', '.join(SUITES)}, got {suite!r}")
    per_class = _int(data.get("per_class", 3), "objects.per_class", 1, 10_000)
    draw = None
    if "draw" in data:
        d = data["draw"]
        _keys(d, {"count", "draw_seed", "sizes"}, "objects.draw.")
        for need in ("count", "draw_seed"):
            if need not in d:
                raise ValidationError(f"objects.draw.{need}", "missing")
        sizes = d.get("sizes", [0.15, 0.50])
        if not isinstance(sizes, list) or len(sizes) != 2:
            raise ValidationError("objects.draw.sizes", f"must be [low, high], got {sizes!r}")
        lo = _float(sizes[0], "objects.draw.sizes[0]", 1e-3, 1.0)
        hi = _float(sizes[1], "objects.draw.sizes[1]", lo, 1.0)
        draw = DrawSpec(
            _int(d["count"], "objects.draw.count", 1, 10_000_000),
            _int(d["draw_seed"], "objects.draw.draw_seed", 0),
            (lo, hi),
        )
    explicit = []
    for i, obj in enumerate(data.get("explicit", [])):
        field = f"objects.explicit[{i}]"
        if not isinstance(obj, Mapping):
            raise ValidationError(
                field, f"must be a table (an object in the request's JSON form), got {obj!r}"
            )
        body = {k: v for k, v in obj.items() if k != "label"}
        explicit.append((str(obj.get("label", f"explicit {i}")), _checked_object(body, field)))
    if not suites and draw is None and not explicit:
        raise ValidationError("objects", "give a suite, a draw or explicit objects")
    return ObjectsSpec(tuple(suites), per_class, draw, tuple(explicit))


def _checked_object(obj: dict[str, Any], field: str) -> dict[str, Any]:
    """The object in its canonical JSON form, checked by the planner's request validation."""
    from eos_svc.agents import PlanRequest

    try:
        request = PlanRequest.from_dict({"object": obj})
    except ValidationError as exc:
        raise ValidationError(field + exc.field.removeprefix("object"), exc.reason) from exc
    return request.obj.to_dict()


def _seeds(value: object) -> tuple[int, ...]:
    if isinstance(value, Mapping):
        _keys(value, {"first", "count"}, "seeds.")
        first = _int(value.get("first", 1), "seeds.first", 0)
        count = _int(value.get("count", 1), "seeds.count", 1, 10_000_000)
        return tuple(range(first, first + count))
    seeds = _list(value, "seeds")
    out = tuple(_int(s, f"seeds[{i}]", 0) for i, s in enumerate(seeds))
    if len(set(out)) != len(out):
        raise ValidationError("seeds", "a seed named twice")
    return out


def _conditions(data: object) -> dict[str, tuple[Any, ...]]:
    """Every condition field as the tuple of values it takes, each checked as a request field."""
    _keys(data, set(CONDITION_FIELDS), "conditions.")
    assert isinstance(data, Mapping)
    from eos_svc.agents import PlanRequest

    out: dict[str, tuple[Any, ...]] = {}
    for name in CONDITION_FIELDS:
        if name not in data:
            continue
        raw = data[name]
        values = [raw] if isinstance(raw, Mapping) else _list(raw, f"conditions.{name}")
        for i, value in enumerate(values):
            try:
                PlanRequest.from_dict({name: value})
            except ValidationError as exc:
                field = f"conditions.{name}" + (f"[{i}]" if len(values) > 1 else "")
                raise ValidationError(field + exc.field.removeprefix(name), exc.reason) from exc
        out[name] = tuple(dict(v) if isinstance(v, Mapping) else v for v in values)
    return out


def _validate(data: object) -> ValidateSpec:
    _keys(data, {"enabled", "seconds", "directions"}, "validate.")
    assert isinstance(data, Mapping)
    enabled = data.get("enabled", False)
    if not isinstance(enabled, bool):
        raise ValidationError("validate.enabled", f"must be true or false, got {enabled!r}")
    return ValidateSpec(
        enabled,
        _float(data.get("seconds", 1.5), "validate.seconds", 0.01, 60.0),
        _int(data.get("directions", 6), "validate.directions", 1, 6),
    )


def _run(data: object) -> RunSpec:
    _keys(data, {"plans_per_task", "rows_per_file", "flush_seconds", "max_retries"}, "run.")
    assert isinstance(data, Mapping)
    per_task = data.get("plans_per_task")
    return RunSpec(
        None if per_task is None else _int(per_task, "run.plans_per_task", 1, 10_000),
        _int(data.get("rows_per_file", 1000), "run.rows_per_file", 1, 10_000_000),
        _float(data.get("flush_seconds", 30.0), "run.flush_seconds", 0.0, 86_400.0),
        _int(data.get("max_retries", 3), "run.max_retries", 0, 100),
    )
