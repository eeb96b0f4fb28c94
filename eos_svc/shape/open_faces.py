"""The faces of a fitted object that no touch bounds: where the next probe should go.

A size whose far face no contact or free sample sees is not known (:func:`~eos_svc.shape.fit
.extent_ratios`): the object may reach farther that way. This module says *which* face is open
— the one that can move outward, the opposite face kept, with the likelihood barely changed —
so that EP2 can ask for exactly the surface that separates the candidate extents. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eos_svc.objects import KINDS
from eos_svc.shape.fit import SIZE_INDEX, ClassFit, face_moved, size_axis, whitened_residuals
from eos_svc.shape.touches import Touches

#: a face is open when moving it out by this fraction of its size changes χ² by less than
#: OPEN_CHI2 (a likelihood ratio above e^-1)
OPEN_STEP = 0.10
OPEN_CHI2 = 2.0


@dataclass(frozen=True)
class OpenFace:
    """A face of the fit no touch bounds: its centre on the fitted surface and its outward
    normal (world, m), the fitted half size along it (m) and how open it is (Δχ² of moving it
    out by :data:`OPEN_STEP`; 0 = nothing sees it)."""

    centre: np.ndarray
    normal: np.ndarray
    half: float
    delta_chi2: float

    def to_dict(self) -> dict[str, object]:
        """JSON form (board entry)."""
        return {
            "centre": np.round(self.centre, 6).tolist(),
            "normal": np.round(self.normal, 6).tolist(),
            "half": round(self.half, 6),
            "delta_chi2": round(self.delta_chi2, 3),
        }


def open_faces(fit: ClassFit, touches: Touches) -> list[OpenFace]:
    """The faces of ``fit`` along its oriented size axes (a box's or an ellipsoid's three, a
    cylinder's or capsule's axis) that can move out by :data:`OPEN_STEP` of their size, the
    opposite face kept, with χ² changed by less than :data:`OPEN_CHI2`; the most open first."""
    kind = fit.kind
    orientation = KINDS[kind].orientation
    if orientation == "none":
        return []
    geometry = fit.geometry
    variants, faces = [], []
    for n in range(len(SIZE_INDEX[kind])):
        axis = size_axis(fit, n)
        if axis is None:
            continue
        for side in (1.0, -1.0):
            variants.append(face_moved(fit, n, 1.0 + OPEN_STEP, side, axis))
            faces.append((side * axis, float(geometry.half_sizes[n])))
    if not variants:
        return []
    residuals = whitened_residuals(np.array(variants), kind, fit.r0, touches)
    delta = np.sum(residuals * residuals, axis=1) - fit.chi2
    centre = np.asarray(geometry.placement.translation, dtype=float)
    out = []
    for (normal, h), d in zip(faces, delta.tolist(), strict=True):
        if d < OPEN_CHI2:
            reach = float(geometry.half_extent(normal))
            out.append(OpenFace(centre + reach * normal, normal, h, max(0.0, d)))
    return sorted(out, key=lambda f: f.delta_chi2)
