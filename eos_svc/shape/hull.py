"""The approximate postulate of an object none of the primitive classes explains: the convex
hull of the touches.

When even the best-fitting primitive misses the touches by more than the noise allows (a
mug, a duck, a random blob), post_shape postulates the convex hull of the sensed surface
points instead — a mesh in the request's form (``{"shape": "mesh", "vertices", "faces"}``),
flagged ``approximate``. On a support surface the object rests on it: the touches'
projections onto the table join the hull (the bottom is never probed there).

Its **confidence** says how far a convex shape explains the touches: the fraction of touches
on the hull's surface (within :data:`ON_HULL_SIGMAS` σ of the contact-gap spread plus the
tactile noise; a touch inside a concavity lies under the hull), times :data:`APPROXIMATE_CAP`
— so it never reaches the confidence a primitive earns by fitting within the noise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from eos_svc.shape.touches import Touches

#: the most an approximate postulate's confidence can be (a primitive within the noise may exceed it)
APPROXIMATE_CAP = 0.5
#: a touch within this many σ of the hull's surface counts as on it
ON_HULL_SIGMAS = 3.0
#: fewest surface points a hull is made of
MIN_POINTS = 6


@dataclass(frozen=True)
class HullPostulate:
    """The convex hull of the touches: its object (request form), its confidence and evidence."""

    object: dict[str, Any]
    confidence: float
    on_hull: float
    centre: np.ndarray
    half_extents: np.ndarray


def hull_postulate(touches: Touches, table_height: float | None = None) -> HullPostulate | None:
    """The convex hull of the touches' surface points (and their projections onto the table at
    ``table_height``, m, when there is one), or None when they span no volume."""
    points = touches.surface_points
    if table_height is not None:  # the unseen lower half: the seen upper half mirrored
        middle = 0.5 * (table_height + float(points[:, 2].max()))
        mirrored = points.copy()
        mirrored[:, 2] = np.maximum(2.0 * middle - points[:, 2], table_height)
        points = np.vstack([points, mirrored])
    if len(points) < MIN_POINTS:
        return None
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    if hull.volume <= 0.0:
        return None
    used = np.unique(hull.simplices)
    index = {int(v): i for i, v in enumerate(used)}
    vertices = points[used]
    faces = [[index[int(v)] for v in _outward(points, s, hull)] for s in hull.simplices]
    centre = _centroid(points, hull)
    sigma = touches.sigma_distance + touches.tactile_noise
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
    depth = -(touches.surface_points @ normals.T + offsets).max(axis=1)  # ≥ 0: under the hull
    on_hull = float(np.mean(depth <= ON_HULL_SIGMAS * sigma))
    obj = {
        "shape": "mesh",
        "vertices": np.round(vertices - centre, 6).tolist(),
        "faces": faces,
        "scale": 1.0,
        "position": np.round(centre, 6).tolist(),
        "rpy": [0.0, 0.0, 0.0],
    }
    half = 0.5 * (vertices.max(axis=0) - vertices.min(axis=0))
    return HullPostulate(obj, APPROXIMATE_CAP * on_hull, on_hull, centre, half)


def _outward(points: np.ndarray, simplex: np.ndarray, hull: ConvexHull) -> list[int]:
    """The triangle's vertex indices ordered counter-clockwise seen from outside."""
    a, b, c = points[simplex]
    inside = points[hull.vertices].mean(axis=0)
    if np.cross(b - a, c - a) @ (a - inside) < 0.0:
        return [int(simplex[0]), int(simplex[2]), int(simplex[1])]
    return [int(s) for s in simplex]


def _centroid(points: np.ndarray, hull: ConvexHull) -> np.ndarray:
    """The hull solid's centroid: the volume-weighted centroids of the tetrahedra from an
    inner point to each facet."""
    inner = points[hull.vertices].mean(axis=0)
    tets = points[hull.simplices]
    vol = (
        np.abs(np.einsum("ij,ij->i", tets[:, 0] - inner, np.cross(tets[:, 1] - inner, tets[:, 2] - inner)))
        / 6.0
    )
    centres = (tets.sum(axis=1) + inner) / 4.0
    out: np.ndarray = (vol[:, None] * centres).sum(axis=0) / vol.sum()
    return out
