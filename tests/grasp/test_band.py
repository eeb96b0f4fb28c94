"""The band of heights the touches measured, and grasp synthesis raising its grip into it."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from eos_svc.agents import ObjectSpec
from eos_svc.grasp.band import AT_TABLE, GRIP_FRACTION, LOW_QUANTILE, MIN_RAISE, MIN_TOUCHES, TouchBand
from eos_svc.grasp.synthesis import GraspSynthesis
from tests.grasp.scenes import HERE, synthesis

TABLE = -0.05


def _points(z: np.ndarray) -> np.ndarray:
    return np.column_stack([np.zeros_like(z), np.zeros_like(z), z])


def test_the_band_spans_the_touches_above_the_table_from_a_low_quantile_to_the_top():
    side = np.linspace(-0.02, 0.01, 31)
    on_table = np.full(5, TABLE + 0.5 * AT_TABLE)  # the table's plane: not the object's side
    band = TouchBand.of(_points(np.concatenate([side, on_table])), TABLE)
    assert band is not None
    assert band.low == pytest.approx(-0.02 + LOW_QUANTILE * 0.03)
    assert band.high == pytest.approx(0.01)
    assert TouchBand.of(_points(np.linspace(0.0, 0.01, MIN_TOUCHES - 1)), TABLE) is None


def test_the_grip_is_raised_into_the_band_only_from_below_it():
    band = TouchBand(low=-0.01, high=0.03)
    raised = -0.01 + GRIP_FRACTION * 0.04
    assert band.grip_height(-0.03) == pytest.approx(raised)
    assert band.grip_height(raised - 0.5 * MIN_RAISE) is None  # the centre's own grip
    assert band.grip_height(0.02) is None


def _tall_box() -> tuple[GraspSynthesis, np.ndarray]:
    """Synthesis on a 50 x 40 x 70 mm box's mesh standing on a table, and its centre (m)."""
    box = trimesh.creation.box(extents=[0.05, 0.04, 0.07])
    size = {"vertices": box.vertices.tolist(), "faces": box.faces.tolist(), "scale": 1.0}
    free = synthesis(ObjectSpec("mesh", size, HERE))
    return _with_band(free, None), np.asarray(free.obj.placement.translation, dtype=float)


def _with_band(plain: GraspSynthesis, band: TouchBand | None) -> GraspSynthesis:
    table = float(plain.obj.placement.translation[2]) - 0.035 - 1e-4
    return GraspSynthesis(
        plain.hand, plain.sweeps, plain.params, plain.obj, plain.friction, table_height=table, band=band
    )


def test_synthesis_closes_the_hand_through_the_raised_grip():
    plain, centre = _tall_box()
    band = TouchBand(low=float(centre[2]), high=float(centre[2]) + 0.03)  # the upper half
    raised = band.grip_height(float(centre[2]))
    assert raised is not None
    at_centre, in_band = plain.candidates(), _with_band(plain, band).candidates()
    assert at_centre and in_band
    for ranked, z in ((at_centre, centre[2]), (in_band, raised)):
        for cand in ranked:
            # the closing axis passes through the grip point: the contacts lie about its height
            # (closing across vertical faces, about it within the fingers' spread)
            assert float((cand.wrist + cand.depth * cand.approach)[2]) == pytest.approx(z, abs=1e-9)
            heights = [float(hit.point[2]) for hit in cand.landings.values()]
            assert np.mean(heights) == pytest.approx(z, abs=0.005)


def test_synthesis_keeps_the_centre_when_no_grip_in_the_band_is_reachable():
    plain, centre = _tall_box()
    top = float(centre[2]) + 0.035
    band = TouchBand(low=top + 0.02, high=top + 0.06)  # above the object: every fingertip misses
    at_centre = plain.candidates()
    fallback = _with_band(plain, band).candidates()
    assert [(c.label, c.depth) for c in fallback] == [(c.label, c.depth) for c in at_centre]
    assert all(np.allclose(a.wrist, b.wrist) for a, b in zip(fallback, at_centre, strict=True))
