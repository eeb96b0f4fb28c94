"""Admission's kept verdicts: the same answers as the geometric queries computed afresh."""

from __future__ import annotations

import dataclasses
import random

import pytest

from eos_svc.agents.planner import default_hand, parameters_for
from eos_svc.errors import ValidationError
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world import admission
from eos_svc.world.admission import (
    VERDICTS_KEPT,
    PlannableCheck,
    check_plannable,
    default_check,
    plannable_verdict,
)

HAND = default_hand()
PARAMS = parameters_for(HAND)


def verdict_of(request: PlanRequest, **kw: object) -> tuple[str, ...]:
    try:
        check_plannable(request, **kw)  # type: ignore[arg-type]
    except ValidationError as exc:
        return exc.field, exc.reason
    return ()


def verdict_of_check(check: PlannableCheck, spec: ObjectSpec) -> tuple[str, ...]:
    try:
        check(PlanRequest(obj=spec))
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
def test_kept_verdicts_equal_fresh_ones(seed: int) -> None:
    rng = random.Random(seed)
    specs = [random_spec(rng) for _ in range(40)]
    kinds = set()
    for spec in specs:
        fresh = plannable_verdict(spec, HAND, PARAMS)
        first = verdict_of(PlanRequest(obj=spec))
        again = verdict_of(PlanRequest(obj=spec, seed=rng.randrange(1000)))  # another seed: kept
        assert first == fresh == again, spec
        assert verdict_of_check(default_check(), spec) == fresh
        assert verdict_of_check(PlannableCheck(HAND, PARAMS), spec) == fresh
        kinds.add(fresh[0] if fresh else "plannable")
    assert "plannable" in kinds and len(kinds) >= 2  # both answers were exercised


def test_a_kept_verdict_skips_the_geometric_queries(monkeypatch: pytest.MonkeyPatch) -> None:
    spec = ObjectSpec("sphere", {"radius": 0.0312}, (0.2, 0.011, -0.013))
    verdict_of(PlanRequest(obj=spec))
    calls = []
    real = admission._check_object
    monkeypatch.setattr(admission, "_check_object", lambda *a: calls.append(a) or real(*a))
    assert verdict_of(PlanRequest(obj=spec, seed=9)) == ()
    assert calls == []
    moved = ObjectSpec("sphere", {"radius": 0.0312}, (0.2, 0.011, -0.0131))
    verdict_of(PlanRequest(obj=moved))
    assert len(calls) == 1


def test_signed_zero_and_other_parameters_are_other_keys() -> None:
    # -0.0 == 0.0, but a reason prints them differently: each gets its own verdict
    far = [ObjectSpec("sphere", {"radius": 0.02}, (1.5, z, 0.0)) for z in (0.0, -0.0)]
    got = [verdict_of(PlanRequest(obj=s)) for s in far]
    assert got == [plannable_verdict(s, HAND, PARAMS) for s in far]
    assert got[0][1] != got[1][1] and "-0.000" in got[1][1]
    # the same object under parameters with a 20 cm clearance: refused there, still plannable here
    spec = ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.02, -0.015))
    tight = dataclasses.replace(PARAMS, clearance=0.2)
    assert verdict_of(PlanRequest(obj=spec)) == ()
    refused = verdict_of(PlanRequest(obj=spec), hand=HAND, params=tight)
    assert refused == plannable_verdict(spec, HAND, tight) != ()
    assert verdict_of(PlanRequest(obj=spec)) == ()


def test_kept_verdicts_are_bounded() -> None:
    kept = admission._VERDICTS.get((HAND, PARAMS), admission._Verdicts)
    for i in range(VERDICTS_KEPT + 20):
        verdict_of(PlanRequest(obj=ObjectSpec("sphere", {"radius": 0.02 + i * 1e-6}, (0.21, 0.02, -0.015))))
    assert len(kept) == VERDICTS_KEPT
