"""Reading a screenshot of a view: where the hand's and the object's colours are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

#: hue ranges (degrees) of the drawn colours, as rendered (lit) by MeshCat
HUES = {
    "object": (175.0, 225.0),  # blue (translucent over grey), teal under the translucent yellow postulate
    "tip1": (20.0, 44.0),  # orange
    "postulate": (45.0, 75.0),  # translucent yellow
    "tip2": (90.0, 150.0),  # green
    "tip3": (270.0, 310.0),  # purple
}
#: the page's panel (top left) and MeshCat's controls bar (top right): not the scene
MASKS = ((0, 200, 0, 480), (0, 24, 760, 1024))


def colour_regions(png: str | Path) -> dict[str, tuple[int, tuple[float, float] | None]]:
    """Per colour of :data:`HUES`: the number of saturated pixels of that hue and their centroid
    (x, y in px; None when there are none), outside the :data:`MASKS`."""
    rgb = Image.open(png).convert("RGB")
    hsv = np.asarray(rgb.convert("HSV"), dtype=float)
    hue = hsv[..., 0] * 360.0 / 255.0
    saturated = hsv[..., 1] / 255.0 > 0.25
    for y0, y1, x0, x1 in MASKS:
        saturated[y0:y1, x0:x1] = False
    out: dict[str, tuple[int, tuple[float, float] | None]] = {}
    for name, (lo, hi) in HUES.items():
        ys, xs = np.nonzero(saturated & (hue >= lo) & (hue <= hi))
        out[name] = (len(xs), (float(xs.mean()), float(ys.mean())) if len(xs) else None)
    return out


def mean_difference(a: str | Path, b: str | Path) -> float:
    """Mean absolute difference of two screenshots' pixels (0..255)."""
    pa = np.asarray(Image.open(a).convert("RGB"), dtype=float)
    pb = np.asarray(Image.open(b).convert("RGB"), dtype=float)
    return float(np.mean(np.abs(pa - pb)))


def distance(p: tuple[float, float] | None, q: tuple[float, float] | None) -> float:
    """Distance between two centroids (px)."""
    assert p is not None and q is not None
    return float(np.hypot(p[0] - q[0], p[1] - q[1]))
