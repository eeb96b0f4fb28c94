"""Where a closing fingertip lands on an object: its *landing*.

Along the finger's sweep (palm frame) each sample's gap is the object's signed distance at the
tip centre less the tip radius; the tip lands where the gap, interpolated linearly between the
last free sample and the first touching one, is zero. SI units.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.objects import SurfaceObject


@dataclass(frozen=True)
class Landing:
    """Where a closing fingertip first touches the object: the first touching sweep sample, the
    joint angle of the touch between it and the sample before (rad), the contact point on the
    object and its outward unit normal (world, m)."""

    index: int
    angle: float
    point: np.ndarray
    normal: np.ndarray

    def to_dict(self) -> dict:
        """JSON form (rounded to µm)."""
        return {
            "angle": round(self.angle, 6),
            "point": np.round(self.point, 6).tolist(),
            "normal": np.round(self.normal, 6).tolist(),
        }


class SweepLandings:
    """The landings of one sweep on an object, the palm at one pose, from any start sample.

    A finger closing from ``start`` lands at the first touching sample at or after
    ``max(0, start − 1)`` unless it touches there already; each landing is found once per
    touching sample. ``pts``, ``gaps``: the sweep's tip centres at this pose (world, m) and their
    gaps (m): the object's signed distance at each, less the tip's radius.
    """

    def __init__(self, obj: SurfaceObject, sweep: FingerSweep, pts: np.ndarray, gaps: np.ndarray) -> None:
        self.obj, self.sweep, self.pts, self.gaps = obj, sweep, pts, gaps
        #: the touching samples (gap ≤ 0), increasing
        self.touching: list[int] = np.flatnonzero(gaps <= 0.0).tolist()
        self._by_sample: dict[int, Landing] = {}

    def first_touch(self, start: int) -> int | None:
        """The touching sample a finger closing from ``start`` lands at (None: it never touches,
        or already touches where it starts)."""
        s = max(0, start - 1)
        i = bisect_left(self.touching, s)
        if i == len(self.touching) or self.touching[i] == s:
            return None
        return self.touching[i]

    def _between(self, k: int) -> tuple[float, np.ndarray]:
        """(fraction s of the way from sample ``k`` − 1 to ``k`` where the gap, interpolated
        linearly, is zero; the tip centre there (world, m))."""
        a, b = float(self.gaps[k - 1]), float(self.gaps[k])
        s = a / (a - b) if a != b else 1.0
        return s, self.pts[k - 1] + s * (self.pts[k] - self.pts[k - 1])

    def landing(self, start: int) -> Landing | None:
        """Where the finger closing from sample ``start`` lands (None: nowhere)."""
        k = self.first_touch(start)
        if k is None:
            return None
        if k not in self._by_sample:
            s, tip = self._between(k)
            point = self.obj.closest_surface_point(tip)
            # a sphere tip touching a convex object: the contact normal runs from the contact
            # point to the tip's centre (defined on edges and rims too, where the surface
            # normal is not)
            out = tip - point
            length = math.sqrt(float(out @ out))
            normal = out / length if length > 1e-9 else self.obj.surface_normal(tip)
            angles = self.sweep.angles
            angle = float(angles[k - 1] + s * (angles[k] - angles[k - 1]))
            self._by_sample[k] = Landing(k, angle, point, normal)
        return self._by_sample[k]


def sweep_landings(
    obj: SurfaceObject,
    sweeps: Mapping[str, FingerSweep],
    tip_radii: Mapping[str, float],
    rotation: np.ndarray,
    origin: np.ndarray,
) -> dict[str, SweepLandings]:
    """The :class:`SweepLandings` of every finger of ``tip_radii`` (its tip's radius, m), the palm
    at (``rotation``, ``origin``) in the world, in one signed-distance query (a distance costs
    mostly per query)."""
    names = list(tip_radii)
    sizes = [len(sweeps[f].points) for f in names]
    radii = np.repeat([tip_radii[f] for f in names], sizes)
    stacked = np.concatenate([sweeps[f].points for f in names]) @ rotation.T + origin
    gaps = obj.signed_distances(stacked)[0] - radii
    ends = np.cumsum(sizes)
    out: dict[str, SweepLandings] = {}
    for f, end, size in zip(names, ends.tolist(), sizes, strict=True):
        part = slice(end - size, end)
        out[f] = SweepLandings(obj, sweeps[f], stacked[part], gaps[part])
    return out
