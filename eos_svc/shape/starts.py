"""Where each kind's fit starts: parameters and orientations from the touches (the sphere at the
point nearest the normal lines; the others about the normals' scatter axes, groups of normals
and the world axes). The parameter layout is :mod:`~eos_svc.shape.fit`'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cached_property
from typing import Any

import numpy as np

from eos_svc.objects import FITTED_KINDS as KINDS
from eos_svc.shape.touches import Touches

#: smallest half size a start may take (m)
MIN_HALF = 0.004
#: normals within this angle (rad) count as one group (a face) or one axis
GROUP_ANGLE = math.radians(15.0)


def columns(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The 3×3 matrix of columns x, y, z."""
    out = np.empty((3, 3))
    out[:, 0], out[:, 1], out[:, 2] = x, y, z
    return out


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u × v of 3-vectors (np.cross's axis handling costs thirty times the product here)."""
    (u0, u1, u2), (v0, v1, v2) = u.tolist(), v.tolist()
    return np.array([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0])


def frame_with_z(axis: np.ndarray) -> np.ndarray:
    """A right-handed rotation whose third column is ``axis`` (normalised)."""
    z = axis / math.sqrt(float(axis @ axis))
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = a - float(a @ z) * z
    x /= math.sqrt(float(x @ x))
    return columns(x, cross(z, x), z)


def normal_scatter_axes(normals: np.ndarray) -> np.ndarray:
    """Eigenvectors (columns, ascending eigenvalue) of Σ n nᵀ, right-handed."""
    _, V = np.linalg.eigh(normals.T @ normals)
    if np.linalg.det(V) < 0:
        V[:, 0] = -V[:, 0]
    return V


def normal_line_centre(points: np.ndarray, normals: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """The point nearest every inward normal line (a sphere's centre), regularised toward
    ``prior`` where the lines are parallel: Σ (I − n nᵀ) x = Σ (I − n nᵀ) s."""
    A = len(points) * np.eye(3) - normals.T @ normals
    b = points.sum(axis=0) - normals.T @ np.sum(normals * points, axis=1)
    lam = 1e-3 * len(points)
    out: np.ndarray = np.linalg.solve(A + lam * np.eye(3), b + lam * prior)
    return out


def normal_clusters(
    normals: np.ndarray, angle: float = GROUP_ANGLE, most: int | None = None
) -> list[np.ndarray]:
    """Mean directions of the sensed normals grouped greedily within ``angle`` (the first
    normal left and every normal left within ``angle`` of it, and so on), largest first;
    ``most``: only that many of the largest."""
    cos = math.cos(angle)
    left = np.arange(len(normals))
    groups = []
    while len(left):
        near = normals[left] @ normals[left[0]] >= cos
        groups.append(left[near])
        left = left[~near]
    groups.sort(key=lambda g: -len(g))
    means = [normals[g].sum(axis=0) for g in groups[:most]]
    return [mean / np.linalg.norm(mean) for mean in means]


def face_frames(normals: np.ndarray) -> list[np.ndarray]:
    """Box orientations from pairs of roughly orthogonal groups of normals (the largest
    groups first, at most three frames)."""
    clusters = normal_clusters(normals, most=4)
    frames = []
    for i, x in enumerate(clusters):
        for c in clusters[i + 1 :]:
            if abs(c @ x) < 0.3:
                y = c - (c @ x) * x
                y /= np.linalg.norm(y)
                frames.append(columns(x, y, cross(x, y)))
    return frames[:3]


def distinct(axes: list[np.ndarray], angle: float = GROUP_ANGLE) -> list[np.ndarray]:
    """The axes (normalised), each more than ``angle`` from the ones before it (unsigned)."""
    out: list[np.ndarray] = []
    for a in axes:
        a = a / np.linalg.norm(a)
        if all(abs(a @ b) < math.cos(angle) for b in out):
            out.append(a)
    return out


class ClassStarts:
    """Every kind's starts ``(theta0, r0)`` from one set of touches (each kind's on first use;
    the pieces kinds share once), and, for the fits of one selection, each start's
    least-squares problem (:class:`~eos_svc.shape.fit.Problem`)."""

    def __init__(self, touches: Touches) -> None:
        self.touches = touches
        S = touches.surface_points
        self.surface, self.mid = S, 0.5 * (S.min(axis=0) + S.max(axis=0))
        self._of: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
        self._problems: dict[tuple[str, int], Any] = {}

    def problem(self, kind: str, index: int, make: Callable[[], Any]) -> Any:
        """The least-squares problem of ``kind`` from its start ``index``, made by ``make`` on
        first use."""
        if (kind, index) not in self._problems:
            self._problems[(kind, index)] = make()
        return self._problems[(kind, index)]

    def of(self, kind: str) -> list[tuple[np.ndarray, np.ndarray]]:
        """Start parameters and orientations ``(theta0, r0)`` of ``kind``."""
        if kind not in self._of:
            self._of[kind] = self._starts(kind)
        return list(self._of[kind])

    def add(self, kind: str, theta0: np.ndarray, r0: np.ndarray) -> int:
        """Add a start of ``kind`` (e.g. from another kind's fit); its index."""
        if kind not in self._of:
            self._of[kind] = self._starts(kind)
        starts = self._of[kind]
        starts.append((theta0, r0))
        return len(starts) - 1

    @cached_property
    def scatter_axes(self) -> np.ndarray:
        """:func:`normal_scatter_axes` of the normals."""
        return normal_scatter_axes(self.touches.normals)

    @cached_property
    def line_centre(self) -> np.ndarray:
        """:func:`normal_line_centre` of the contacts, toward the middle of their bounds."""
        return normal_line_centre(self.surface, self.touches.normals, self.mid)

    @cached_property
    def axial_frames(self) -> list[tuple[np.ndarray, float, float]]:
        """(frame, median radial distance of the contacts, largest axial one) (m) about each
        distinct candidate axis of a cylinder or a capsule, centred mid-bounds."""
        V = self.scatter_axes
        out = []
        for axis in distinct([V[:, 0], *np.eye(3), V[:, 1], V[:, 2]]):
            r0 = frame_with_z(axis)
            local = (self.surface - self.mid) @ r0
            radial = float(np.median(np.hypot(local[:, 0], local[:, 1])))
            out.append((r0, radial, float(np.max(np.abs(local[:, 2])))))
        return out

    def _starts(self, kind: str) -> list[tuple[np.ndarray, np.ndarray]]:
        S, mid, normals = self.surface, self.mid, self.touches.normals
        orientation = KINDS[kind].orientation
        if orientation == "none":
            c = self.line_centre
            r = max(float(np.mean(np.linalg.norm(S - c, axis=1))), MIN_HALF)
            return [(np.array([*c, math.log(r)]), np.eye(3))]
        out: list[tuple[np.ndarray, np.ndarray]] = []
        if orientation == "rotation":
            V = self.scatter_axes
            box = kind == "box"
            frames = [*face_frames(normals), np.eye(3), V] if box else [V, np.eye(3)]
            c = mid if box else self.line_centre
            for r0 in frames:
                half = np.maximum(np.max(np.abs((S - c) @ r0), axis=0), MIN_HALF)
                out.append((np.concatenate([c, np.zeros(3), np.log(half)]), r0))
            return out
        for r0, median_radius, axial in self.axial_frames:
            radius = max(median_radius, MIN_HALF)
            half = max(axial - radius, MIN_HALF) if kind == "capsule" else max(axial, MIN_HALF)
            out.append((np.concatenate([mid, [0.0, 0.0, math.log(radius), math.log(half)]]), r0))
        return out
