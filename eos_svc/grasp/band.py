"""The height band the touches measured, where a grip on the hull of the touches may land.

On a table EP2 touches an object's upper part; the convex hull of the touches
(:mod:`eos_svc.shape.hull`) mirrors that upper part about mid-height for the unseen lower part.
Grasp synthesis closes the hand through the hull's centre, at mid-height: often below the band
the touches measured, where the real faces may slant or a stem may stand under an overhang (on
pybullet's random objects 503, 552, 600 and 614 the failed grips' contacts lay there). The band
is the touches' heights above the table, from a low quantile (:data:`LOW_QUANTILE`, so a few
stray low touches do not widen it) to the highest; grasp synthesis closes the hand through a
point raised into the band instead (:meth:`TouchBand.grip_height`), through the centre only
when no grip through that point is reachable.

SI units: metres, world z.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: touches this close above the table (m) are the table's plane, not the object's side
AT_TABLE = 0.002
#: the band's bottom: this quantile of the touches' heights
LOW_QUANTILE = 0.1
#: where in the band (0 bottom, 1 top) the raised grip passes
GRIP_FRACTION = 0.25
#: a raised grip less than this (m) above the centre is not tried (it is the centre's)
MIN_RAISE = 0.003
#: fewest touches above the table that make a band
MIN_TOUCHES = 6


@dataclass(frozen=True)
class TouchBand:
    """The heights (world z, m) the touches measured: ``low`` to ``high``."""

    low: float
    high: float

    @classmethod
    def of(cls, points: np.ndarray, table_height: float) -> TouchBand | None:
        """The band of touch points (N, 3; world, m) above the table at ``table_height`` (m),
        or None with fewer than :data:`MIN_TOUCHES` of them."""
        z = np.asarray(points, dtype=float).reshape(-1, 3)[:, 2]
        z = z[z > table_height + AT_TABLE]
        if len(z) < MIN_TOUCHES:
            return None
        return cls(float(np.quantile(z, LOW_QUANTILE)), float(z.max()))

    def grip_height(self, centre_z: float) -> float | None:
        """The height (m) of a grip raised into the band from the centre's ``centre_z``, or None
        when the centre lies within :data:`MIN_RAISE` of it or above."""
        z = self.low + GRIP_FRACTION * (self.high - self.low)
        return z if z >= centre_z + MIN_RAISE else None
