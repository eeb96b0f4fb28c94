"""Choose the class by model evidence and state how sure we are (``docs/planner.md``).

Every class is fitted (:func:`~eos_svc.shape.fit.fit_class`, a class far worse than the best
only briefly); with equal priors ``P(class) ∝ exp(−BIC/2)``, ``BIC = χ² + k·ln m``. The
**confidence** is P(class right and sizes and centre within :data:`SIZE_TOLERANCE`) from the
fit's covariance, lowered by faces no touch bounds and by a best fit worse than the noise
allows. A **plane**: every sensed normal within :data:`PLANE_ANGLE` of their mean.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin
from scipy import special

from eos_svc.objects import FITTED_KINDS as KINDS
from eos_svc.shape.fit import (
    GOOD_FIT,
    SIZE_INDEX,
    ClassFit,
    explains,
    extent_ratios,
    fit_class,
    fitted_object,
)
from eos_svc.shape.span import within_span
from eos_svc.shape.starts import ClassStarts, frame_with_z
from eos_svc.shape.touches import Touches

#: the classes fitted, in the order ties are broken
CLASSES: tuple[str, ...] = tuple(KINDS)
#: relative size tolerance the confidence refers to
SIZE_TOLERANCE = 0.10
#: normals all within this angle of their mean (rad) → a plane
PLANE_ANGLE = math.radians(12.0)
#: how much looser than the noise model a fit's χ² is judged (model and gap imperfections)
FIT_SLACK = 2.0
#: χ² margin beyond the best class so far past which a class's other starts are skipped
HOPELESS = 2000.0
#: iterations that show a class hopeless once another fits
QUICK_NFEV = 6
#: a sibling class (:func:`siblings`) whose χ² exceeds the best class's by more than this is
#: refitted from the best class's fit
SIBLING_GAP = 10.0
#: fewest contacts needed to fit the classes
MIN_CONTACTS = 4
#: a class whose χ² on fewer of the same touches exceeds the best now by this is settled (more
#: touches only add to its χ²; its posterior is below e^−30 of the best's): it is only screened
SETTLED = 60.0


@dataclass(frozen=True)
class Postulate:
    """The chosen class (a fitted kind or ``plane``), its confidence (P(class right and size
    within tolerance)), every class's posterior and fit (none for a plane), and the contacts
    used."""

    kind: str
    confidence: float
    probabilities: dict[str, float]
    fits: dict[str, ClassFit]
    contacts: int

    @property
    def best(self) -> ClassFit | None:
        """The chosen class's fit (None for a plane)."""
        return self.fits.get(self.kind)

    def object(self) -> dict[str, Any] | None:
        """The postulated object in the request's JSON form (None for a plane)."""
        fit = self.best
        return None if fit is None else object_dict(fit)

    def evidence(self) -> dict[str, Any]:
        """Contacts used, fit residual and the competing classes (JSON-friendly)."""
        out: dict[str, Any] = {
            "contacts": self.contacts,
            "classes": {k: round(v, 6) for k, v in sorted(self.probabilities.items(), key=lambda kv: -kv[1])},
            "chi2": {k: round(f.chi2, 3) for k, f in self.fits.items()},
        }
        fit = self.best
        if fit is not None:
            m = 3 * self.contacts
            out["fit_chi2"] = round(fit.chi2, 3)
            out["fit_rms"] = round(math.sqrt(fit.chi2 / max(m, 1)), 4)
            out["size_sigma_rel"] = [round(float(s), 6) for s in fit.size_sigmas()]
            out["centre_sigma_m"] = [round(float(s), 7) for s in fit.centre_sigmas()]
        return out


#: the 24 proper rotations that permute and flip the coordinate axes
_SYMMETRIES = [
    P
    for perm in itertools.permutations(range(3))
    for signs in itertools.product((1.0, -1.0), repeat=3)
    if np.linalg.det(P := np.eye(3)[:, list(perm)] * np.array(signs)) > 0
]


def canonical_pose(
    kind: str, rotation: np.ndarray, sizes: tuple[float, ...]
) -> tuple[np.ndarray, tuple[float, ...]]:
    """The same object with its symmetric description nearest the world axes: a kind oriented
    by a rotation (box, ellipsoid) has its axes relabelled (half sizes permuted with them) to
    the rotation closest to the identity; one oriented by an axis (cylinder, capsule) has its
    axis pointing up (or +x, +y when level), its frame's x axis the world x projected across
    the axis."""
    orientation = KINDS[kind].orientation
    if orientation == "rotation":
        best = max(_SYMMETRIES, key=lambda P: float(np.trace(rotation @ P)))
        order = [int(np.argmax(np.abs(best[:, c]))) for c in range(3)]
        return rotation @ best, tuple(sizes[i] for i in order)
    if orientation == "axis":
        z = rotation[:, 2].copy()
        level = abs(z[2]) < 1e-6
        if (not level and z[2] < 0.0) or (level and z[int(np.argmax(np.abs(z)))] < 0.0):
            z = -z
        return frame_with_z(z), sizes
    return np.eye(3), sizes


def _rounded(value: Any) -> Any:
    """Floats (in lists too) rounded to the µm / µrad, without a negative zero."""
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    return round(value, 6) + 0.0 if isinstance(value, float) else value


def object_dict(fit: ClassFit) -> dict[str, Any]:
    """A fitted kind as an object in the request's JSON form (the kind's own
    :meth:`~eos_svc.objects.base.SurfaceObject.to_dict`, in its canonical pose,
    :func:`canonical_pose`, rounded to the µm)."""
    g = fit.geometry
    rotation, half = canonical_pose(g.kind, g.rotation, tuple(g.half_sizes.tolist()))
    canonical = KINDS[g.kind].from_half_sizes(np.array(half), pin.SE3(rotation, g.centre))
    return {key: _rounded(value) for key, value in canonical.to_dict().items()}


def _within(tolerance: np.ndarray, sigma: np.ndarray) -> float:
    p = 1.0
    for t, s in zip(tolerance.tolist(), sigma.tolist(), strict=True):
        p *= 1.0 if s <= 0.0 else math.erf(t / (math.sqrt(2.0) * s))
    return p


def tolerance_probability(
    fit: ClassFit, touches: Touches | None = None, tolerance: float = SIZE_TOLERANCE
) -> float:
    """P(every size within ±``tolerance`` (relative) and the centre within ``tolerance`` × the
    mean half size), from the fit's Gaussian covariance (independent parameters) and, given
    the touches, times ``1 − r`` per size with ``r`` the likelihood ratio of a size
    ``tolerance`` off with one face kept (:func:`~eos_svc.shape.fit.extent_ratios`: a size
    bounded on one side only is not known)."""
    sizes = fit.geometry.half_sizes
    p_size = _within(np.full(len(sizes), tolerance), fit.size_sigmas())
    if touches is not None:
        p_size *= float(np.prod(1.0 - extent_ratios(fit, touches, tolerance)))
    p_centre = _within(np.full(3, tolerance * float(np.mean(sizes))), fit.centre_sigmas())
    return p_size * p_centre


def select_class(
    touches: Touches,
    classes: tuple[str, ...] = CLASSES,
    warm: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    earlier: dict[str, float] | None = None,
) -> Postulate:
    """Fit every class to ``touches`` and choose by posterior (BIC, equal priors); ValueError
    below MIN_CONTACTS contacts. ``warm``: per class, an earlier fit's (θ, R0) on fewer of the
    same touches, refitted first (unless it reaches far past them: :mod:`eos_svc.shape.span`):
    one that then :func:`explains` the touches is kept without the class's cold starts.
    ``earlier``: per class, its χ² on fewer of the same touches: a class :data:`SETTLED` by it
    is only screened (nor refitted as a sibling)."""
    if touches.count < MIN_CONTACTS:
        raise ValueError(f"need at least {MIN_CONTACTS} contacts to fit a class, got {touches.count}")
    mean = touches.normals.mean(axis=0)
    norm = float(np.linalg.norm(mean))
    if norm >= 1e-9 and np.all(touches.normals @ (mean / norm) >= math.cos(PLANE_ANGLE)):
        return Postulate("plane", 0.0, {"plane": 1.0}, {}, touches.count)  # one face, no object
    m = 3 * touches.count
    fits: dict[str, ClassFit] = {}
    screened: dict[str, ClassFit] = {}
    shared = ClassStarts(touches)  # every class's starts, their common pieces computed once
    for kind, (theta0, r0) in (warm or {}).items():
        # a fit grown far past the touches is no start: refitted, it grows on (shape.span)
        if kind in classes and within_span(fitted_object(kind, theta0, r0), touches):
            refit = fit_class(kind, touches, class_starts=shared, only=shared.add(kind, theta0, r0))
            if explains(refit.chi2, touches, kind):
                fits[kind] = refit
    # a fit from the nearest start alone, QUICK_NFEV evaluations: a screening
    screen = partial(
        fit_class, touches=touches, max_nfev=QUICK_NFEV, max_starts=1, nearest_first=True, class_starts=shared
    )
    behind = min((f.chi2 for f in fits.values()), default=math.inf) + SETTLED
    settled = [k for k in classes if k not in fits and (earlier or {}).get(k, -math.inf) > behind]
    fits.update((k, screen(k)) for k in settled)
    if classes[0] not in fits:
        fits[classes[0]] = fit_class(classes[0], touches, class_starts=shared)
    if min(f.chi2 for f in fits.values()) > GOOD_FIT * m and len(classes) > 1:
        # the first class does not explain the touches: the others, each screened, are fitted
        # from the likeliest, so that once one explains the touches the rest are shown
        # hopeless against it in a few iterations
        screened = {k: screen(k) for k in classes[1:] if k not in fits}
    rest = tuple(k for k in classes[1:] if k not in fits)
    order = sorted(rest, key=lambda k: (screened[k].chi2, classes.index(k))) if screened else rest
    for kind in order:
        # once some class fits, one far worse than it is hopeless (posterior ~ e^-HOPELESS/2):
        # a few iterations show it, the full fit is kept for the competitive ones
        best = min(f.chi2 for f in fits.values())
        if best > GOOD_FIT * m:  # no class explains the touches yet: every class gets every start
            fits[kind] = fit_class(kind, touches, class_starts=shared)
            continue
        hopeless = best + HOPELESS
        # a screening fit from the class's first start is the quick fit when it is hopeless,
        # explains the touches, or the class has one start
        quick = screened.get(kind)
        if (
            quick is None
            or quick.start != 0
            or not (quick.chi2 > hopeless or explains(quick.chi2, touches, kind) or len(shared.of(kind)) == 1)
        ):
            quick = fit_class(kind, touches, QUICK_NFEV, hopeless, class_starts=shared)
        if quick.chi2 > hopeless or quick.chi2 <= GOOD_FIT * m:
            fits[kind] = quick  # hopeless, or already explaining the touches as well as the noise allows
            continue
        fits[kind] = fit_class(kind, touches, hopeless=hopeless, class_starts=shared)
    best_kind = min(fits, key=lambda k: fits[k].chi2)
    for kind in siblings(best_kind, classes):  # a sibling's own starts may all have missed
        if kind in settled or fits[kind].chi2 <= fits[best_kind].chi2 + SIBLING_GAP:
            continue  # settled, or near the best already: a refit would barely move the posterior
        start = shared.add(kind, *sibling_start(fits[best_kind], kind))
        refit = fit_class(kind, touches, class_starts=shared, only=start)
        if refit.chi2 < fits[kind].chi2:
            fits[kind] = refit
    fits = {k: fits[k] for k in classes}
    bic = {k: f.chi2 + f.n_params * math.log(m) for k, f in fits.items()}
    low = min(bic.values())
    weights = {k: math.exp(-0.5 * (b - low)) for k, b in bic.items()}
    total = sum(weights.values())
    probs = {k: w / total for k, w in weights.items()}
    kind = max(classes, key=lambda k: (probs[k], -classes.index(k)))
    confidence = probs[kind] * tolerance_probability(fits[kind], touches) * fit_probability(fits[kind], m)
    return Postulate(kind, confidence, probs, fits, touches.count)


def siblings(kind: str, classes: tuple[str, ...]) -> list[str]:
    """The other classes oriented and sized like ``kind`` (cylinder and capsule; box and
    ellipsoid): one's fit is a good start for the other's."""
    a = KINDS[kind]
    return [
        k
        for k in classes
        if k != kind
        and KINDS[k].orientation == a.orientation != "none"
        and KINDS[k].half_size_count == a.half_size_count
    ]


def sibling_start(fit: ClassFit, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """A start ``(theta0, r0)`` of ``kind`` (a :func:`siblings` of the fit's) at the fitted
    object's centre, orientation and extents (an axis-oriented kind's half length set so the
    extent along the axis matches: a capsule's caps reach one radius past its straight part)."""
    g = fit.geometry
    half = np.array(g.half_sizes, dtype=float)
    if KINDS[kind].orientation == "axis":
        z = np.array([0.0, 0.0, 1.0])
        extent = g.local_half_extent(z)
        cap = KINDS[kind].from_half_sizes(np.array([half[0], 1.0])).local_half_extent(z) - 1.0
        half[1] = max(extent - cap, 0.1 * half[0])
    orientation = np.zeros(SIZE_INDEX[kind][0] - 3)  # about r0 = the fitted rotation
    return np.concatenate([g.centre, orientation, np.log(half)]), np.array(g.rotation)


def fit_probability(fit: ClassFit, m: int) -> float:
    """How plausible the best fit's χ² is under the noise model, taken FIT_SLACK times
    looser: ``P(χ²_dof·FIT_SLACK ≥ χ²)``. ≈ 1 for a class that fits the touches, → 0 when
    even the best class misses them (an object none of the classes describes)."""
    x = fit.chi2 / FIT_SLACK  # scipy.stats.chi2.sf(x, dof) without the distribution object
    return 1.0 if x <= 0.0 else float(special.chdtrc(max(m - fit.n_params, 1), x))
