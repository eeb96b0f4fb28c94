"""select_class's warm starts: a class refitted from its fit on fewer of the same touches ends
where its cold starts end, a warm start that does not explain the touches changes nothing, and a
class settled on fewer touches is only screened."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.shape import select_class, selection
from eos_svc.shape.fit import fit_class
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


def test_a_class_settled_on_fewer_touches_is_only_screened(monkeypatch):
    """A class whose χ² on fewer of the touches already exceeded the best by SETTLED gets one
    screening fit (its nearest start, QUICK_NFEV evaluations), not a sibling's refit either;
    the posterior is the full selection's to 1e-6."""
    obj = objects()["box"]
    fewer = touches_on(obj, np.random.default_rng(3), n=12)
    touches = touches_on(obj, np.random.default_rng(3), n=18)
    before = select_class(fewer)
    earlier, warm = before.evidence()["chi2"], {"box": (before.fits["box"].theta, before.fits["box"].r0)}
    full = select_class(touches, warm=warm)  # the box refitted from its warm start: the best so far
    settled = {k for k, chi2 in earlier.items() if chi2 > full.fits["box"].chi2 + selection.SETTLED}
    assert settled and "box" not in settled
    calls: list[tuple[str, int | None]] = []

    def recording(kind, touches, *args, **kw):
        calls.append((kind, kw.get("max_starts")))
        return fit_class(kind, touches, *args, **kw)

    monkeypatch.setattr(selection, "fit_class", recording)
    hot = select_class(touches, warm=warm, earlier=earlier)
    assert hot.kind == full.kind == "box"
    for kind in settled:
        assert [starts for k, starts in calls if k == kind] == [1]
    assert hot.probabilities == pytest.approx(full.probabilities, abs=1e-6)
    assert hot.confidence == pytest.approx(full.confidence, abs=1e-6)
