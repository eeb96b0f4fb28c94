"""pybullet's test objects (the ``objects`` extra): read from the installed package, scaled to
widths the hand spans, set on the table; one planned end to end on the hull of its touches."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.errors import ValidationError
from eos_svc.experiments.pybullet_objects import (
    THIN_MAX,
    THIN_MIN,
    named_objects,
    parse_ids,
    random_objects,
    thinnest_width,
)
from eos_svc.grasp.postulate import make_object
from eos_svc.world.admission import check_default

pytest.importorskip("pybullet_data")  # the objects extra


def test_random_objects_are_scaled_turned_and_set_on_the_table():
    kept, left = random_objects(range(0, 8))
    assert len(kept) + len(left) == 8 and kept
    for obj in kept:
        assert THIN_MIN - 1e-9 <= thinnest_width(obj) <= THIN_MAX + 1e-9
        mesh = make_object(obj.spec)
        assert obj.table is not None
        assert mesh.centre[2] - mesh.depth_below_centre() == pytest.approx(obj.table.height, abs=1e-4)
        check_default(PlanRequest(obj=obj.spec, table=obj.table))  # the hand can span and reach it
        assert obj.spec.size["file"].endswith(".obj") and "pybullet_data" in obj.spec.size["file"]


def test_the_household_objects_load():
    names = [o.label for o in named_objects()]
    assert names == ["mug", "duck", "teddy"]


@pytest.mark.parametrize("text", ["5-2", "x", "0-1000", "-1"])
def test_bad_ids_are_refused(text):
    with pytest.raises(ValidationError) as err:
        parse_ids(text)
    assert err.value.field == "ids"
    assert list(parse_ids("3-5")) == [3, 4, 5]


def test_an_object_no_primitive_explains_is_grasped_on_the_hull_of_its_touches():
    (obj,), _ = random_objects(range(1, 2))
    result = plan(PlanRequest(obj=obj.spec, seed=1, table=obj.table))
    shape = result.shape
    assert shape is not None and shape["class"] == "hull" and shape["approximate"] is True
    assert shape["confidence"] <= 0.5  # says it is approximate
    assert shape["object"]["shape"] == "mesh"
    # the end agent judged the contacts the fingers made on the real mesh
    assert (result.status == "success") == result.good_grasp  # no success without a good grasp
    assert result.good_grasp == result.force_closure  # a mesh: force closure about its centre of mass
    assert np.isfinite(result.epsilon)


def test_a_grip_felt_not_to_close_is_let_go_and_planned_again():
    (obj,), _ = random_objects(range(502, 503))  # its first grips: links touch before the tips
    result = plan(PlanRequest(obj=obj.spec, seed=1, table=obj.table, deadline_s=None))
    details = [c.detail for c in result.trace if c.chosen == "end"]
    assert details[0].startswith("regrip 1: the fingertips felt 1 of 3 contacts, not in force closure")
    assert len(details) >= 2 and details[-1].startswith("precision grip")
    assert result.good_grasp and result.status == "success"  # a later grip closes


def test_a_regrip_with_no_untried_grasp_keeps_the_grip_it_let_go(monkeypatch):
    """When every remade grasp was tried already, the hand goes back to the grip it opened and
    the end agent judges that grip (not an open hand)."""
    from eos_svc.agents.regrip import Regrip

    (obj,), _ = random_objects(range(502, 503))
    request = PlanRequest(obj=obj.spec, seed=1, table=obj.table, deadline_s=None)
    monkeypatch.setattr(Regrip, "_was_tried", lambda self, cand: True)
    result = plan(request)
    end = [c.detail for c in result.trace if c.chosen == "end"]
    assert len(end) == 1  # no regrip was placed: the grip judged at once
    touching = [c["touching"] for c in result.contacts.values()]
    assert any(touching)  # the grip it had (one tip felt the object), not the opened hand
    assert not result.good_grasp and result.status != "success"
