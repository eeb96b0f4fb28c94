"""A spec expanded into plan keys: one :class:`PlanKey` per plan, in a fixed order, each with a
stable id.

The order is objects (suites, then the draw, then explicit objects, each in its own order) ×
conditions (the product of every condition field's values, the last field fastest) × seeds ×
hands. A key's id is a hash of what the plan depends on (world, hand, the request in its
canonical JSON form, the validation settings), so the same plan has the same id in every run,
on every machine and in every spec that contains it: a rerun recognises the rows already
written by id alone.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass
from typing import Any

from eos_svc.batch.spec import CONDITION_FIELDS, BatchSpec, ValidateSpec

#: characters of the hex SHA-256 kept as a key's id (64 bits: collisions unlikely below 10^9 plans)
KEY_LENGTH = 16


@dataclass(frozen=True)
class PlanKey:
    """One plan of a batch.

    Attributes:
        key: stable id (hex), see :func:`plan_id`.
        label: the object's label (suite label, ``draw S:i class`` or the explicit label).
        condition: index of the condition combination (0-based, in expansion order).
        hand: a registered hand's name (``eos hands``).
        seed: the request's seed.
        request: the request in its JSON form (:meth:`PlanRequest.to_dict`).
        world: the world the plan runs in.
        validate: the validation settings (``enabled`` False: plan only).
    """

    key: str
    label: str
    condition: int
    hand: str
    seed: int
    request: dict[str, Any]
    world: str
    validate: ValidateSpec


def plan_id(world: str, hand: str, request: dict[str, Any], validate: ValidateSpec) -> str:
    """The stable id of a plan: a hash of its canonical JSON description."""
    what = {
        "world": world,
        "hand": hand,
        "request": request,
        "validate": {"seconds": validate.seconds, "directions": validate.directions}
        if validate.enabled
        else None,
    }
    text = json.dumps(what, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_LENGTH]


def spec_objects(spec: BatchSpec) -> list[tuple[str, dict[str, Any], int | None]]:
    """The spec's objects in order: (label, object in JSON form, drawn seed or None)."""
    from eos_svc.experiments import grasp_suite

    out: list[tuple[str, dict[str, Any], int | None]] = []
    for suite in spec.objects.suites:
        if suite == "fixed":
            members = grasp_suite.fixed_suite()
        elif suite == "quick":
            members = grasp_suite.quick_suite()
        else:
            members = grasp_suite.held_back_suite(spec.objects.held_back_per_class)
        out.extend((m.label, m.spec.to_dict(), None) for m in members)
    draw = spec.objects.draw
    if draw is not None:
        drawn = grasp_suite.random_draw(draw.count, draw.draw_seed, draw.sizes)
        out.extend((d.label, d.spec.to_dict(), d.seed) for d in drawn)
    out.extend((label, obj, None) for label, obj in spec.objects.explicit)
    return out


def condition_combinations(spec: BatchSpec) -> list[dict[str, Any]]:
    """Every combination of the condition values (request fields), the last field fastest."""
    names = [n for n in CONDITION_FIELDS if n in spec.conditions]
    return [
        dict(zip(names, values, strict=True))
        for values in itertools.product(*(spec.conditions[n] for n in names))
    ]


def expand(spec: BatchSpec) -> list[PlanKey]:
    """The spec's plans in order, each once (a plan the spec names twice is kept at its first place)."""
    from eos_svc.agents import PlanRequest

    keys: list[PlanKey] = []
    seen: set[str] = set()
    for label, obj, drawn_seed in spec_objects(spec):
        seeds = spec.seeds if spec.seeds is not None else (drawn_seed if drawn_seed is not None else 1,)
        for index, condition in enumerate(condition_combinations(spec)):
            for seed in seeds:
                request = PlanRequest.from_dict({"object": obj, "seed": seed, **condition}).to_dict()
                for hand in spec.hands:
                    key = plan_id(spec.world, hand, request, spec.validate)
                    if key in seen:
                        continue
                    seen.add(key)
                    keys.append(PlanKey(key, label, index, hand, seed, request, spec.world, spec.validate))
    return keys


def chunks(keys: list[PlanKey], size: int) -> list[list[PlanKey]]:
    """``keys`` in consecutive groups of ``size`` (the last may be shorter)."""
    return [keys[i : i + size] for i in range(0, len(keys), size)]
