"""select_class's warm starts: a class refitted from its fit on fewer of the same touches ends
where its cold starts end, and a warm start that does not explain the touches changes nothing."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.shape import select_class
from eos_svc.shape.starts import ClassStarts

from .synthetic import objects, touches_on


@pytest.mark.parametrize("kind", ["box", "cylinder"])
def test_warm_start_from_fewer_touches_matches_the_cold_fit(kind):
    obj = objects()[kind]
    fewer = touches_on(obj, np.random.default_rng(3), n=12)
    touches = touches_on(obj, np.random.default_rng(3), n=18)  # the same 12, then 6 more
    np.testing.assert_array_equal(touches.centres[:12], fewer.centres)
    earlier = select_class(fewer)
    warm = {k: (f.theta, f.r0) for k, f in earlier.fits.items()}
    cold, hot = select_class(touches), select_class(touches, warm=warm)
    assert hot.kind == cold.kind == kind
    # the true class's fit came from its warm start (added after its cold ones)
    assert hot.fits[kind].start == len(ClassStarts(touches).of(kind))
    np.testing.assert_allclose(hot.fits[kind].chi2, cold.fits[kind].chi2, rtol=0.05, atol=1.0)
    np.testing.assert_allclose(
        hot.fits[kind].geometry.half_extents(), cold.fits[kind].geometry.half_extents(), rtol=0.01
    )
    assert hot.confidence == pytest.approx(cold.confidence, abs=0.05)


def test_a_warm_start_that_does_not_explain_the_touches_is_dropped():
    obj = objects()["box"]
    touches = touches_on(obj, np.random.default_rng(5), n=18)
    cold = select_class(touches)
    far = cold.fits["box"].theta.copy()
    far[:3] += 0.05  # 5 cm off
    far[-3:] += np.log(3.0)  # three times too large
    hot = select_class(touches, warm={"box": (far, cold.fits["box"].r0)})
    assert hot.kind == cold.kind == "box"
    assert hot.fits["box"].chi2 == pytest.approx(cold.fits["box"].chi2)
    assert hot.probabilities == pytest.approx(cold.probabilities)
