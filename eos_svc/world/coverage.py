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


def space_filling_order(counts: tuple[int, int], rng: np.random.Generator) -> list[tuple[int, int]]:
    """Every column index once, in a seeded farthest-point (maximin) order.

    The first column is drawn by ``rng``; each next one is the column farthest from every
    column visited so far (ties broken by a seeded jitter), so the visited columns cover the
    face ever more finely and evenly: after k columns every column is within the k-th
    column's distance of a visited one, and that distance never grows.

    The whole order at once: :class:`SpaceFillingOrder` (what the search uses) computes it a
    column at a time, the same columns from the same draws of ``rng``.
    """
    return SpaceFillingOrder(counts, rng).pending()[:]


class SpaceFillingOrder:
    """The columns of :func:`space_filling_order`, each computed when the search asks for it.

    The search seldom sweeps more than a few of the few dozen columns before it locates the
    object, so the order is extended one farthest column at a time (a pass over the columns)
    rather than all at once (one pass per column: ≈ 0.1 ms on hand3x3's 6 × 6 lattice, as much
    as a search move). Same draws of ``rng`` at construction (the jitter, the first column) and
    the same columns in the same order as the whole order computed at once (tested).

    Scalar Python over the few dozen columns (a vectorised form costs ~40× more in numpy call
    overhead); the lattice distances are square roots of exact integers, so the order is the
    same as the vectorised form's (tested against it).
    """

    __slots__ = ("_distances", "_jitter", "_left", "_nearest", "_points", "_queue")

    def __init__(
        self, counts: tuple[int, int], rng: np.random.Generator, lattice: Lattice | None = None
    ) -> None:
        points, distances = lattice if lattice is not None else lattice_of(*counts)
        self._points = points
        self._distances = distances
        self._jitter: list[float] = rng.uniform(0.0, 1e-3, len(points)).tolist()
        first = int(rng.integers(len(points)))
        # each column's distance to the nearest column ordered so far (-1: ordered)
        self._nearest = list(distances[first])
        self._nearest[first] = -1.0
        self._left = len(points) - 1  # columns not yet ordered
        self._queue: list[tuple[int, int]] = [points[first]]  # ordered, not yet taken

    def __len__(self) -> int:
        """Columns not yet taken."""
        return len(self._queue) + self._left

    def _extend(self) -> None:
        """Order one more column: the unordered column farthest from the ordered ones (the
        first of equal scores, as argmax), then every column's nearest distance updated."""
        nearest, jitter = self._nearest, self._jitter
        k, best = 0, -math.inf
        for n, d in enumerate(nearest):
            score = d + jitter[n] if d >= 0.0 else -1.0
            if score > best:
                k, best = n, score
        self._queue.append(self._points[k])
        self._left -= 1
        nearest[k] = -1.0
        for n, to_k in enumerate(self._distances[k]):
            if to_k < nearest[n]:  # never for an ordered column (-1)
                nearest[n] = to_k

    def take(self) -> tuple[int, int]:
        """The next column (``IndexError`` when every column was taken)."""
        if not self._queue:
            if not self._left:
                raise IndexError("every column was taken")
            self._extend()
        return self._queue.pop(0)

    def pending(self) -> list[tuple[int, int]]:
        """Every column not yet taken, in order (the whole rest ordered now; the list itself:
        reorder it with :meth:`move_to_front`)."""
        while self._left:
            self._extend()
        return self._queue

    def move_to_front(self, index: int) -> None:
        """Take the ``index``-th pending column next (the rest keep their order)."""
        queue = self.pending()
        queue.insert(0, queue.pop(index))


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
    """Whether the search is guaranteed to locate ``obj``:

    1. some sweep line passes within ``envelope_radius`` of the object (signed distance,
       sampled every ``1/samples_per_metre`` m along x), and
    2. the object lies wholly ahead of what the hand reaches from the rear of the box — every
       point at x > ``search_box_lo[0] + forward_reach + clearance`` — so the crossings at the
       rear never bump into it, and
    3. its centre lies within the grasp-centre box's height range: the upper and lower fingers
       sit above and below the grasp centre, so an object centred above or below that range is
       bumped by them on every sweep before the grasp centre comes near it (measured: such
       objects ran the search into the cycle limit).

    Condition 1 holds at once when the object's centre lies in the grasp-centre box
    (:func:`centre_in_grasp_box`); ``exhaustive=True`` samples every sweep line regardless
    (the plain test the shortcut is checked against).
    """
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
    """Whether ``centre`` lies in the grasp-centre box ``B`` (m). Then some sweep line passes
    within half a lattice cell's diagonal (≤ ``envelope_radius``) of it, and the object's
    signed distance from that point is at most the distance to its centre: condition 1 of
    :func:`findable` holds without sampling."""
    gc = params.grasp_centre
    lo, hi = params.search_box_lo, params.search_box_hi
    return all(lo[i] + gc[i] <= float(centre[i]) <= hi[i] + gc[i] for i in range(3))
