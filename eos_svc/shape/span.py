"""Whether a fitted primitive stays within the span of the touches it was fitted to.

A primitive that explains a few touches on one side of an object may do so at any size: a
near-flat patch is as well explained by an ellipsoid 800 mm across as by one 80 mm across (on
pybullet's random object 509, each refit from the previous one grew it further, 120 mm to
800 mm over ten refits on the same 21 touches, and EP2 then probed where that ellipsoid said).
A postulate must explain the touches within the noise *and* stay near them: its axis-aligned
bounds may pass the touches' bounds by at most :data:`SPAN_MARGIN` of their largest extent,
and never less than :data:`MIN_MARGIN`, on each side. SI units (m).
"""

from __future__ import annotations

import numpy as np

from eos_svc.objects import SurfaceObject
from eos_svc.shape.touches import Touches

#: how far past the touches' bounds a postulate may reach, as a fraction of their largest extent
SPAN_MARGIN = 0.5
#: ... and at least this far (m): a few touches span little
MIN_MARGIN = 0.01


def within_span(obj: SurfaceObject, touches: Touches) -> bool:
    """Whether ``obj``'s world bounds lie within the touches' surface points' bounds widened by
    the margin (see the module doc) on every side."""
    points = touches.surface_points
    lo, hi = points.min(axis=0), points.max(axis=0)
    margin = max(SPAN_MARGIN * float(np.max(hi - lo)), MIN_MARGIN)
    centre = np.asarray(obj.placement.translation, dtype=float)
    half = np.asarray(obj.half_extents(), dtype=float)
    return bool(np.all(centre - half >= lo - margin) and np.all(centre + half <= hi + margin))
