"""Admission's verdicts: the same through every entry point (check_plannable, the default check,
an explicit context), and a function of the object, the hand and the parameters alone."""

from __future__ import annotations

import dataclasses
import random

import pytest

from eos_svc.errors import ValidationError
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world.admission import check_plannable, default_check, plannable_verdict
from eos_svc.world.hand_context import default_context

CONTEXT = default_context()
HAND, PARAMS = CONTEXT.hand, CONTEXT.params


def verdict_of(request: PlanRequest, **kw: object) -> tuple[str, ...]:
    try:
        check_plannable(request, **kw)  # type: ignore[arg-type]
    except ValidationError as exc:
        return exc.field, exc.reason
    return ()


def verdict_of_default(spec: ObjectSpec) -> tuple[str, ...]:
    try:
        default_check()(PlanRequest(obj=spec))
    except ValidationError as exc:
        return exc.field, exc.reason
    return ()


def random_spec(rng: random.Random) -> ObjectSpec:
    shape = rng.choice(["sphere", "ellipsoid", "cylinder", "box", "capsule"])
    size: dict[str, object] = {}
    for key in {"sphere": ("radius",), "ellipsoid": ("radii",), "cylinder": ("radius", "length"),
                "box": ("size",), "capsule": ("radius", "length")}[shape]:  # fmt: skip
        vector = key in ("radii", "size")
        size[key] = [rng.uniform(0.01, 0.09) for _ in range(3)] if vector else rng.uniform(0.01, 0.09)
    position = (rng.uniform(0.05, 0.4), rng.uniform(-0.15, 0.15), rng.uniform(-0.15, 0.15))
    rpy = (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3))
    return ObjectSpec(shape, size, position, rpy)


@pytest.mark.parametrize("seed", [0, 1])
def test_every_entry_point_gives_the_same_verdict(seed: int) -> None:
    rng = random.Random(seed)
    kinds = set()
    for spec in [random_spec(rng) for _ in range(40)]:
        fresh = plannable_verdict(spec, CONTEXT)
        assert verdict_of(PlanRequest(obj=spec)) == fresh, spec
        assert verdict_of(PlanRequest(obj=spec, seed=rng.randrange(1000)), hand=HAND, params=PARAMS) == fresh
        assert verdict_of(PlanRequest(obj=spec), context=CONTEXT) == fresh
        assert default_check() is default_check() and verdict_of_default(spec) == fresh
        kinds.add(fresh[0] if fresh else "plannable")
    assert "plannable" in kinds and len(kinds) >= 2  # both answers were exercised


def test_signed_zero_and_other_parameters() -> None:
    # -0.0 == 0.0, but a reason prints them as written
    far = [ObjectSpec("sphere", {"radius": 0.02}, (1.5, z, 0.0)) for z in (0.0, -0.0)]
    got = [verdict_of(PlanRequest(obj=s)) for s in far]
    assert got[0][1] != got[1][1] and "-0.000" in got[1][1]
    # the same object under parameters with a 20 cm clearance: refused there, still plannable here
    spec = ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.02, -0.015))
    tight = dataclasses.replace(PARAMS, clearance=0.2)
    assert verdict_of(PlanRequest(obj=spec)) == ()
    refused = verdict_of(PlanRequest(obj=spec), hand=HAND, params=tight)
    assert refused == plannable_verdict(spec, CONTEXT.with_params(tight)) != ()
    assert verdict_of(PlanRequest(obj=spec)) == ()
