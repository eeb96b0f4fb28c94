"""Admission's size rule: an object fits between the fingertips along some axis, as the grasp
synthesis finds grasps on the true object."""

from __future__ import annotations

import itertools

import pytest

from eos_svc.grasp.postulate import make_object
from eos_svc.grasp.synthesis import MAX_D_OVER_H, GraspSynthesis
from eos_svc.schema.request import ObjectSpec
from eos_svc.world.admission import plannable_verdict
from eos_svc.world.fingertip_fit import DEPTHS, fit_refusal, grip_axes
from eos_svc.world.hand_context import default_context

POSITION = (0.24, 0.0, 0.0)


def grasped(spec: ObjectSpec) -> bool:
    """Whether the synthesis finds a collision-free grasp about the centre of the true object."""
    ctx = default_context()
    found = GraspSynthesis(ctx.hand, ctx.sweeps, ctx.params, make_object(spec), 0.5).candidates()
    return bool(found) and found[0].about_centre


def test_the_openings_of_hand3x3():
    ctx = default_context()
    opening = ctx.opening
    h = ctx.hand.hand_height
    # curved: the tips reach past h/2 when the fingers open, so the planner's d/h < 1 binds
    assert opening.curved == pytest.approx(MAX_D_OVER_H * h)
    # flat: a straight finger's tip (r_f 10 mm, at h/2 = 60 mm) touches a face 50 mm from the
    # mid-plane before its links (radius 8 mm) do; deeper faces meet the links sooner
    assert opening.flat_at(DEPTHS[-1]) == pytest.approx(h - 2 * 0.01, abs=1e-6)
    widths = [opening.flat_at(d) for d in DEPTHS]
    assert all(a >= b for a, b in itertools.pairwise(widths))
    assert opening.palm_front == pytest.approx(0.01, abs=1e-6)  # the palm box's front face
    assert ctx.span > 1.9 * opening.curved  # the span is not what fits between the tips


@pytest.mark.parametrize(("inside", "outside"), [(0.104, 0.11), (0.1, 0.112)])
def test_flat_limit_agrees_with_the_synthesis(inside, outside):
    # cubes: every grip across flat faces as deep as it is wide
    opening = default_context().opening
    small = ObjectSpec("box", {"size": (inside, inside, inside)}, POSITION)
    large = ObjectSpec("box", {"size": (outside, outside, outside)}, POSITION)
    assert fit_refusal(small, opening, 0.002) is None and grasped(small)
    assert fit_refusal(large, opening, 0.002) is not None and not grasped(large)


def test_curved_limit_agrees_with_the_synthesis():
    limit = default_context().opening.curved
    assert grasped(ObjectSpec("sphere", {"radius": 0.5 * limit - 0.002}, POSITION))
    big = ObjectSpec("sphere", {"radius": 0.5 * limit + 0.001}, (0.3, 0.0, 0.0))
    assert not grasped(big)
    field, reason = plannable_verdict(big, default_context())
    assert field == "object.radius"
    assert "fits between the fingertips along no axis" in reason and f"{limit * 1000:.1f} mm" in reason


@pytest.mark.parametrize(
    ("spec", "fits"),
    [
        # a long box: thin across one pair of faces
        (ObjectSpec("box", {"size": (0.06, 0.2, 0.06)}, POSITION), True),
        # a cube too wide across every pair of faces
        (ObjectSpec("box", {"size": (0.115, 0.115, 0.115)}, POSITION), False),
        # a short fat cylinder: gripped on its end faces
        (ObjectSpec("cylinder", {"radius": 0.08, "length": 0.05}, POSITION), True),
        # a long fat cylinder: neither across nor along
        (ObjectSpec("cylinder", {"radius": 0.07, "length": 0.2}, POSITION), False),
        # an ellipsoid flat along one axis
        (ObjectSpec("ellipsoid", {"radii": (0.1, 0.1, 0.04)}, POSITION), True),
    ],
)
def test_fits_along_some_axis(spec, fits):
    refusal = fit_refusal(spec, default_context().opening, 0.002)
    assert (refusal is None) == fits
    if not fits:
        assert refusal is not None and refusal[0] == grip_axes(spec)[0].field


def test_room_behind_the_contacts():
    # a plate 6 cm thin but 30 cm deep along every approach across it reaches the palm
    opening = default_context().opening
    room = opening.room(0.06)
    assert 0.1 < room < 0.13
    deep = ObjectSpec("box", {"size": (0.3, 0.3, 0.06)}, (0.4, 0.0, 0.0))
    refusal = fit_refusal(deep, opening, 0.002)
    assert refusal is not None and refusal[0] == "object.size"


def test_a_sphere_narrower_than_the_side_by_side_fingertips_is_refused_and_indeed_missed():
    """G1 Dex3's index and middle close in planes 57 mm apart: a sphere whose radius is below
    their tips' inner distance from the mid-plane (side_reach) is missed by a fingertip at every
    candidate, and admission refuses it naming the radius; one just wider is grasped."""
    from eos_svc.hands import load_hand_named
    from eos_svc.world.hand_context import HandContext

    ctx = HandContext.build(load_hand_named("g1_dex3"))
    reach = ctx.opening.side_reach
    tip = ctx.hand.tip_radius("index")
    assert reach == pytest.approx(0.0285 - tip, abs=1e-3)  # the fingers' planes at ±28.5 mm

    def found(spec: ObjectSpec) -> bool:
        synthesis = GraspSynthesis(ctx.hand, ctx.sweeps, ctx.params, make_object(spec), 0.5)
        return any(c.about_centre for c in synthesis.candidates())

    narrow = ObjectSpec("sphere", {"radius": reach - 0.002}, POSITION)
    assert not found(narrow)
    field, reason = plannable_verdict(narrow, ctx)
    assert field == "object.radius" and "across the fingers" in reason
    wide = ObjectSpec("sphere", {"radius": reach + 0.002}, POSITION)
    assert plannable_verdict(wide, ctx) == () and found(wide)
