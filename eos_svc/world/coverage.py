"""The search's coverage plan: where the hand looks, in a seeded space-filling order.

Every search move is a *sweep*: back to the search box's rear (−x), across to one column
``(y, z)`` of a lattice whose columns are at most ``√2·envelope_radius`` apart, and forward
through the box. The columns are visited once each in a seeded farthest-point (maximin) order;
a sweep stopped by a bump moves the column nearest the bump to the front. :func:`findable`
states what the search is sure to find (docs/planner.md); admission
(:mod:`eos_svc.world.admission`) refuses the rest.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from eos_svc.objects import SurfaceObject
    from eos_svc.world.parameters import WorldParameters


def coverage_spacing(params: WorldParameters) -> float:
    """Largest column spacing along y and z whose sweep tubes cover the box (m)."""
    return math.sqrt(2.0) * params.envelope_radius


def column_counts(params: WorldParameters) -> tuple[int, int]:
    """Columns along y and z (corners included)."""
    spacing = coverage_spacing(params)
    lo, hi = params.search_box_lo, params.search_box_hi
    ny = max(1, math.ceil((hi[1] - lo[1] - 1e-12) / spacing) + 1)
    nz = max(1, math.ceil((hi[2] - lo[2] - 1e-12) / spacing) + 1)
    return ny, nz


def wrist_columns(params: WorldParameters) -> np.ndarray:
    """The (y, z) wrist positions of the columns, shape (ny, nz, 2), m."""
    lo, hi = params.search_box_lo, params.search_box_hi
    counts = column_counts(params)
    ys = np.linspace(lo[1], hi[1], counts[0]) if counts[0] > 1 else np.array([0.5 * (lo[1] + hi[1])])
    zs = np.linspace(lo[2], hi[2], counts[1]) if counts[1] > 1 else np.array([0.5 * (lo[2] + hi[2])])
    return np.stack(np.meshgrid(ys, zs, indexing="ij"), axis=-1)


def space_filling_order(
    counts: tuple[int, int], rng: np.random.Generator, lattice: Lattice | None = None
) -> list[tuple[int, int]]:
    """Every column index once, in a seeded farthest-point (maximin) order.

    The first column is drawn by ``rng``; each next one is the column farthest from every
    column visited so far (ties broken by a seeded jitter), so the visited columns cover the
    face ever more finely and evenly: after k columns every column is within the k-th
    column's distance of a visited one, and that distance never grows. ``lattice``:
    :func:`lattice_of` ``(*counts)``, when the caller keeps it.
    """
    points, distances = lattice if lattice is not None else lattice_of(*counts)
    jitter: list[float] = rng.uniform(0.0, 1e-3, len(points)).tolist()
    first = int(rng.integers(len(points)))
    nearest = list(distances[first])  # each column's distance to the nearest ordered one (-1: ordered)
    nearest[first] = -1.0
    order = [points[first]]
    for _ in range(len(points) - 1):
        k, best = 0, -math.inf  # the unordered column farthest from the ordered ones (argmax)
        for n, d in enumerate(nearest):
            score = d + jitter[n] if d >= 0.0 else -1.0
            if score > best:
                k, best = n, score
        order.append(points[k])
        nearest[k] = -1.0
        for n, to_k in enumerate(distances[k]):
            if to_k < nearest[n]:  # never for an ordered column (-1)
                nearest[n] = to_k
    return order


#: a lattice's column indices and their distances (see :func:`lattice_of`)
Lattice = tuple[tuple[tuple[int, int], ...], tuple[tuple[float, ...], ...]]


def lattice_of(ny: int, nz: int) -> Lattice:
    """The column indices of an ny × nz lattice, row by row, and their distances (in
    lattice steps: square roots of exact integers, as numpy's norm gives them)."""
    points = tuple((i, j) for i in range(ny) for j in range(nz))
    distances = tuple(
        tuple(math.sqrt(float((i - a) ** 2 + (j - b) ** 2)) for i, j in points) for a, b in points
    )
    return points, distances


#: hand3x3's forward reach from the wrist (m): its fingertips' farthest x (straight fingers at
#: 0.13 m) plus the tip radius; another hand's is its context's ``forward_reach``
HAND3X3_FORWARD_REACH = 0.14


def findable(
    obj: SurfaceObject,
    params: WorldParameters,
    forward_reach: float = HAND3X3_FORWARD_REACH,
    samples_per_metre: int = 1000,
    exhaustive: bool = False,
) -> bool:
    """Whether the search is guaranteed to locate ``obj``: (1) some sweep line passes within
    ``envelope_radius`` of it (sampled every ``1/samples_per_metre`` m), (2) it lies wholly
    ahead of the fingers' reach from the rear of the box (x > ``search_box_lo[0] +
    forward_reach + clearance``) and (3) its centre lies within the grasp-centre box's height
    range (else the fingers bump it on every sweep). (1) holds at once when the centre lies in
    the grasp-centre box (:func:`centre_in_grasp_box`) unless ``exhaustive``."""
    gc = np.asarray(params.grasp_centre, dtype=float)
    lo, hi = params.search_box_lo[0], params.search_box_hi[0]
    c = np.asarray(obj.placement.translation, dtype=float)
    rear = obj.closest_surface_point(c - np.array([10.0, 0.0, 0.0]))  # the object's rearmost point
    if rear[0] <= lo + forward_reach + params.clearance:
        return False
    z_lo, z_hi = params.search_box_lo[2] + gc[2], params.search_box_hi[2] + gc[2]
    if not z_lo <= float(c[2]) <= z_hi:
        return False
    if not exhaustive and centre_in_grasp_box(c, params):
        return True
    xs = np.linspace(lo, hi, max(2, math.ceil((hi - lo) * samples_per_metre) + 1))
    reach = 0.5 * float(obj.diameter) + params.envelope_radius
    for y, z in wrist_columns(params).reshape(-1, 2).tolist():
        points = np.column_stack([xs, np.full_like(xs, y), np.full_like(xs, z)]) + gc
        near = points[np.linalg.norm(points - c, axis=1) <= reach + 1e-9]
        if any(obj.signed_distance(p) <= params.envelope_radius for p in near):
            return True
    return False


def centre_in_grasp_box(centre: np.ndarray, params: WorldParameters) -> bool:
    """Whether ``centre`` lies in the grasp-centre box (m): then some sweep line passes within
    ``envelope_radius`` of it (condition 1 of :func:`findable`)."""
    gc = params.grasp_centre
    lo, hi = params.search_box_lo, params.search_box_hi
    return all(lo[i] + gc[i] <= float(centre[i]) <= hi[i] + gc[i] for i in range(3))
