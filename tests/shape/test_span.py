"""A postulate stays within the span of its touches: a fit grown far past them is no warm start."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.objects import Sphere
from eos_svc.shape import select_class
from eos_svc.shape.span import MIN_MARGIN, SPAN_MARGIN, within_span
from eos_svc.shape.starts import ClassStarts

from .synthetic import objects, placement, touches_on


def test_a_primitive_the_touches_span_is_within_it_and_a_much_larger_one_is_not():
    sphere = objects()["sphere"]  # radius 30 mm
    touches = touches_on(sphere, np.random.default_rng(2), n=18)
    assert within_span(sphere, touches)
    points = touches.surface_points
    span = float(np.max(points.max(axis=0) - points.min(axis=0)))
    margin = max(SPAN_MARGIN * span, MIN_MARGIN)
    # the largest sphere about the same centre within the widened bounds, in closed form
    lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    centre = np.asarray(sphere.placement.translation)
    largest = float(min(np.min(centre - lo), np.min(hi - centre)))
    assert largest > 0.03
    assert within_span(Sphere(largest - 1e-4, placement()), touches)
    assert not within_span(Sphere(largest + 1e-4, placement()), touches)
    assert not within_span(Sphere(10 * largest, placement()), touches)


@pytest.mark.parametrize("grow", [3.0, 10.0])
def test_a_warm_start_grown_past_the_touches_is_no_start(grow):
    obj = objects()["ellipsoid"]
    touches = touches_on(obj, np.random.default_rng(4), n=18)
    cold = select_class(touches)
    grown = cold.fits["ellipsoid"].theta.copy()
    grown[-3:] += np.log(grow)  # every semi-axis `grow` times the fit's
    hot = select_class(touches, warm={"ellipsoid": (grown, cold.fits["ellipsoid"].r0)})
    # the fit came from the class's cold starts (a warm start is added after them)
    assert hot.fits["ellipsoid"].start < len(ClassStarts(touches).of("ellipsoid"))
    assert hot.fits["ellipsoid"].chi2 == pytest.approx(cold.fits["ellipsoid"].chi2)
    assert hot.kind == cold.kind
