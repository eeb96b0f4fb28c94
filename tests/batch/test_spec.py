"""The batch spec and its expansion into plan keys: every field checked and named, ids stable."""

from __future__ import annotations

from pathlib import Path

import pytest

from eos_svc.batch import expand, load_spec, plan_id, spec_from_dict
from eos_svc.batch.spec import ValidateSpec
from eos_svc.errors import ValidationError

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "batch-example.toml"


def test_the_example_spec_parses_and_expands_to_its_documented_count() -> None:
    spec = load_spec(EXAMPLE)
    assert spec.name == "example" and spec.world == "kinematic" and spec.validate.enabled
    keys = expand(spec)
    assert len(keys) == (5 + 4 + 1) * 4 * 2  # objects x (noise x friction) x seeds
    assert len({k.key for k in keys}) == len(keys)
    assert [k.key for k in expand(load_spec(EXAMPLE))] == [k.key for k in keys]  # deterministic
    first = keys[0]
    assert first.request["friction"] == 0.3 and first.request["tactile_noise"] == 2e-4 and first.seed == 1
    assert first.key == plan_id("kinematic", "hand3x3", first.request, spec.validate)


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"objects": {"suite": "quick"}, "world": "mujoco"}, "world"),
        ({"objects": {"suite": "quick"}, "colour": 1}, "colour"),
        ({"objects": {"suite": "nope"}}, "objects.suite[0]"),
        ({}, "objects"),
        ({"objects": {"suite": "quick"}, "conditions": {"friction": [0.5, -1.0]}}, "conditions.friction[1]"),
        ({"objects": {"suite": "quick"}, "conditions": {"tactile_noise": 1.0}}, "conditions.tactile_noise"),
        (
            {
                "objects": {"suite": "quick"},
                "conditions": {"weights": {"default": 0.9, "opportunistic": 0.9}},
            },
            "conditions.weights",
        ),
        ({"objects": {"explicit": [{"shape": "sphere", "radius": -1.0}]}}, "objects.explicit[0].radius"),
        ({"objects": {"draw": {"count": 3}}}, "objects.draw.draw_seed"),
        ({"objects": {"suite": "quick"}, "hands": ["hand3x3", "shadow"]}, "hands[1]"),
        ({"objects": {"suite": "quick"}, "seeds": [1, 1]}, "seeds"),
        ({"objects": {"suite": "quick"}, "run": {"plans_per_task": 0}}, "run.plans_per_task"),
    ],
)
def test_a_bad_field_is_refused_by_name(data: dict, field: str) -> None:
    with pytest.raises(ValidationError) as exc:
        spec_from_dict(data)
    assert exc.value.field.startswith(field), exc.value


def test_the_world_error_says_what_is_available() -> None:
    with pytest.raises(ValidationError, match="kinematic"):
        spec_from_dict({"objects": {"suite": "quick"}, "world": "mujoco"})


def test_a_drake_key_plans_in_the_drake_world() -> None:
    from eos_svc.batch.task import run_key

    spec = spec_from_dict(
        {
            "world": "drake",
            "objects": {"suite": "quick"},
            "seeds": [1],
            "conditions": {"max_cycles": 6, "deadline_s": 600.0},
        }
    )
    keys = expand(spec)
    kinematic = expand(spec_from_dict({"objects": {"suite": "quick"}, "seeds": [1]}))
    assert keys[0].world == "drake" and keys[0].key != kinematic[0].key  # the world is in the id
    row = run_key(keys[0])
    assert row["world"] == "drake" and row["status"] == "cycle_limit"  # six cycles of a Drake plan


def test_a_drawn_object_keeps_its_drawn_seed_unless_seeds_are_given() -> None:
    draw = {"objects": {"draw": {"count": 3, "draw_seed": 5}}}
    drawn = expand(spec_from_dict(draw))
    assert len({k.seed for k in drawn}) == 3 and all(k.seed != 1 for k in drawn)
    seeded = expand(spec_from_dict({**draw, "seeds": {"first": 7, "count": 2}}))
    assert [k.seed for k in seeded] == [7, 8] * 3


def test_an_id_depends_on_what_the_plan_depends_on_only() -> None:
    spec = spec_from_dict({"objects": {"suite": "quick"}, "hands": ["hand3x3", "allegro"]})
    keys = expand(spec)
    assert len(keys) == 10 and {k.hand for k in keys} == {"hand3x3", "allegro"}
    request = keys[0].request
    plain = plan_id("kinematic", "hand3x3", request, ValidateSpec())
    assert plain == keys[0].key
    assert plan_id("kinematic", "hand3x3", request, ValidateSpec(True, 1.0)) != plain
    assert plan_id("kinematic", "hand3x3", {**request, "seed": 2}, ValidateSpec()) != plain
    # the same plan named twice (a suite object listed again) is planned once
    again = {"shape": "sphere", "radius": 0.03, "position": [0.21, 0.02, -0.015]}
    twice = spec_from_dict({"objects": {"suite": "quick", "explicit": [again]}})
    assert len(expand(twice)) == 5
