"""The expected information of a guarded probe: where the candidate postulates disagree.

After a fit (:mod:`eos_svc.shape.selection`) the object is uncertain in two ways: which class
it is (the posterior over classes) and, within a class, its parameters (the fit's covariance:
size, pose). A guarded probe measures one number — how far its fingertip travels along its line
before it touches, or that it touches nothing in its travel — so a probe is informative where
the candidates predict different distances.

Each candidate class (:class:`Candidate`) stands for its fitted object and its 2k sigma points
``θ ± Lᵢ`` (``L`` a square root of the fit's covariance, each column shrunk to at most
:data:`MAX_CENTRE_STEP`, :data:`MAX_ANGLE_STEP` and :data:`MAX_LOG_SIZE_STEP`: a direction no
touch constrains is "as uncertain as that", not infinitely). The distance a probe predicts
under each of them is found by sphere tracing the tip centre's offset surface (signed distance
= tip radius, :func:`hit_distances`). The predictions give the probes' covariance ``C = RᵀR``
(:func:`disagreement`): rows of R are the classes' mean predictions about the mixture mean,
weighted by √P(class), and each sigma pair's half difference, weighted by √P(class) — the
mixture's variance, the within-class part linearised (the unscented transform's 1-σ points) —
and, for a face the touches bound on one side only, the fit with that face moved far out
(:func:`reaches_of`), weighted by √(P(class) × its likelihood ratio).
:func:`choose` then picks probes greedily: the one of largest predicted variance, C conditioned
on measuring it with noise σ (``C ← C − c cᵀ / (c_jj + σ²)``), the next, …: each pick maximises
the expected information gain ``½ ln(1 + var/σ²)`` given the earlier ones (greedy selection for
Gaussian models; Krause, Singh and Guestrin, JMLR 2008).

SI units: metres, radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from eos_svc.objects import FITTED_KINDS as KINDS
from eos_svc.shape.fit import SIZE_INDEX, ClassFit, batch_geometry, face_moved, size_axis, whitened_residuals
from eos_svc.shape.selection import Postulate
from eos_svc.shape.touches import Touches

#: largest sigma-point step of a centre coordinate (m)
MAX_CENTRE_STEP = 0.03
#: largest sigma-point step of an orientation parameter (rad)
MAX_ANGLE_STEP = 0.35
#: largest sigma-point step of a log size (a factor e^0.35 ≈ 1.4)
MAX_LOG_SIZE_STEP = 0.35
#: classes below this posterior are not candidates
MIN_PROBABILITY = 0.01
#: most candidate classes
MOST_CANDIDATES = 3
#: a reach moves a face out by this fraction of its size
REACH_STEP = 0.5
#: reaches less likely than this (likelihood ratio against the fit) are left out
MIN_REACH_WEIGHT = 0.01
#: sphere tracing: most steps, and the gap (m) at which a trace has touched
TRACE_STEPS = 80
TRACE_TOLERANCE = 1e-4


@dataclass(frozen=True)
class Candidate:
    """One candidate class of the postulate: its posterior ``probability``, its fit's
    parameters ``theta`` about the start orientation ``r0`` (:mod:`eos_svc.shape.fit`'s
    layout), the sigma steps ``steps`` (k, k): column i is the i-th 1-σ step, and its
    ``reaches`` (E, k): the fit with a face moved far out, each with its likelihood ratio
    against the fit in ``reach_weights`` (:func:`reaches_of`)."""

    kind: str
    probability: float
    theta: np.ndarray
    r0: np.ndarray
    steps: np.ndarray
    reaches: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    reach_weights: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def of(cls, fit: ClassFit, probability: float, touches: Touches | None = None) -> Candidate:
        """The candidate of a class fit: its covariance's Cholesky factor, each column
        shrunk so that no step exceeds the caps; given the touches, its :func:`reaches` too."""
        cov = 0.5 * (fit.covariance + fit.covariance.T)
        try:
            root = np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:  # not positive definite: the symmetric square root
            w, V = np.linalg.eigh(cov)
            root = V * np.sqrt(np.maximum(w, 0.0))
        caps = step_caps(fit.kind)
        scale = np.max(np.abs(root) / caps[:, None], axis=0)
        root = root / np.maximum(scale, 1.0)[None, :]
        none = (np.zeros((0, len(fit.theta))), np.zeros(0))
        reaches, weights = none if touches is None else reaches_of(fit, touches)
        theta, r0 = np.asarray(fit.theta, float), np.asarray(fit.r0, float)
        return cls(fit.kind, float(probability), theta, r0, root, reaches, weights)

    def members(self) -> np.ndarray:
        """The parameter vectors (1 + 2k, k): θ, then θ + Lᵢ for each i, then θ − Lᵢ."""
        return np.concatenate([self.theta[None], self.theta + self.steps.T, self.theta - self.steps.T])

    def to_dict(self) -> dict[str, Any]:
        """JSON form (post_shape's ``candidates``)."""
        return {
            "class": self.kind,
            "probability": round(self.probability, 6),
            "parameters": np.round(self.theta, 9).tolist(),
            "start_rotation": np.round(self.r0, 12).tolist(),
            "sigma_steps": np.round(self.steps, 9).tolist(),
            "reaches": np.round(self.reaches, 9).tolist(),
            "reach_weights": np.round(self.reach_weights, 6).tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Candidate:
        """The candidate of its JSON form."""
        kind = str(data["class"])
        if kind not in KINDS:
            raise ValueError(f"candidate.class: unknown class {kind!r}")
        return cls(
            kind,
            float(data["probability"]),
            np.asarray(data["parameters"], dtype=float),
            np.asarray(data["start_rotation"], dtype=float).reshape(3, 3),
            np.asarray(data["sigma_steps"], dtype=float),
            np.asarray(data.get("reaches", []), dtype=float).reshape(-1, len(data["parameters"])),
            np.asarray(data.get("reach_weights", []), dtype=float),
        )


def step_caps(kind: str) -> np.ndarray:
    """The largest step of each of ``kind``'s parameters: centre (m), orientation (rad), log sizes."""
    k = len(SIZE_INDEX[kind]) + SIZE_INDEX[kind][0]
    caps = np.full(k, MAX_ANGLE_STEP)
    caps[:3] = MAX_CENTRE_STEP
    caps[list(SIZE_INDEX[kind])] = MAX_LOG_SIZE_STEP
    return caps


def reaches_of(fit: ClassFit, touches: Touches) -> tuple[np.ndarray, np.ndarray]:
    """(parameters (E, k), likelihood ratios (E,)) of the fit with one face moved out by
    :data:`REACH_STEP` of its size, the opposite face kept — along each oriented size axis,
    both ways — where the ratio ``exp(−Δχ²/2)`` is at least :data:`MIN_REACH_WEIGHT`: a face
    bounded on one side only (the touches stop at it, nothing touched beyond) may lie much
    farther than the fit's covariance, a local quadratic, says."""
    axes = [(n, size_axis(fit, n)) for n in range(len(SIZE_INDEX[fit.kind]))]
    variants = [
        face_moved(fit, n, 1.0 + REACH_STEP, side, axis)
        for n, axis in axes
        if axis is not None
        for side in (1.0, -1.0)
    ]
    if not variants:
        return np.zeros((0, len(fit.theta))), np.zeros(0)
    thetas = np.array(variants)
    residuals = whitened_residuals(thetas, fit.kind, fit.r0, touches)
    weights = np.exp(-0.5 * np.maximum(np.sum(residuals * residuals, axis=1) - fit.chi2, 0.0))
    keep = weights >= MIN_REACH_WEIGHT
    return thetas[keep], weights[keep]


def candidates_of(post: Postulate, touches: Touches | None = None) -> list[Candidate]:
    """The postulate's candidate classes: at most :data:`MOST_CANDIDATES`, each at least
    :data:`MIN_PROBABILITY` likely, the likeliest first (with their reaches, given the
    touches)."""
    ranked = sorted(post.probabilities.items(), key=lambda kv: -kv[1])
    return [
        Candidate.of(post.fits[kind], p, touches)
        for kind, p in ranked[:MOST_CANDIDATES]
        if p >= MIN_PROBABILITY and kind in post.fits
    ]


def hit_distances(
    kind: str,
    thetas: np.ndarray,
    r0: np.ndarray,
    starts: np.ndarray,
    directions: np.ndarray,
    travel: np.ndarray,
    radius: np.ndarray,
) -> np.ndarray:
    """(M, P) distances each of P probes travels (``starts`` (P, 3), unit ``directions``
    (P, 3), ``travel`` (P,) m, tip ``radius`` (P,) m) before its tip touches each of the M
    objects of parameters ``thetas`` (M, k) — ``travel`` where it touches nothing, 0 where it
    starts touching. Sphere tracing on the kind's exact signed distance: each step advances by
    the gap between the tip and the surface, which never passes the surface; a trace stops once
    within TRACE_TOLERANCE of it or at the end of its travel (the others go on)."""
    centres, rotations, half = batch_geometry(kind, np.asarray(thetas, dtype=float), r0)
    t = np.zeros((len(thetas), len(starts)))
    m, p = np.indices(t.shape).reshape(2, -1)  # the traces still going: object m, probe p
    for _ in range(TRACE_STEPS):
        points = starts[p] + t[m, p, None] * directions[p]
        local = np.einsum("ni,nij->nj", points - centres[m], rotations[m])
        d, _ = KINDS[kind].local_distance(local, half[m])
        gap = np.maximum(d - radius[p], 0.0)
        t[m, p] = np.minimum(t[m, p] + gap, travel[p])
        going = (gap >= TRACE_TOLERANCE) & (t[m, p] < travel[p])
        m, p = m[going], p[going]
        if not len(m):
            break
    return t


def disagreement(
    candidates: list[Candidate],
    starts: np.ndarray,
    directions: np.ndarray,
    travel: np.ndarray,
    radius: np.ndarray,
) -> np.ndarray:
    """R (rows, P): ``RᵀR`` is the candidates' predicted covariance of the P probes'
    distances (m²): the classes' means about the mixture mean and the sigma points' spread,
    weighted by the classes' posterior renormalised over the candidates."""
    total = sum(c.probability for c in candidates)
    if not candidates or total <= 0.0:
        return np.zeros((0, len(starts)))
    rows, means, weights = [], [], []
    for c in candidates:
        w = c.probability / total
        T = hit_distances(c.kind, c.members(), c.r0, starts, directions, travel, radius)
        k = len(c.theta)
        rows.append(np.sqrt(w) * 0.5 * (T[1 : 1 + k] - T[1 + k :]))
        if len(c.reaches):
            E = hit_distances(c.kind, c.reaches, c.r0, starts, directions, travel, radius)
            rows.append(np.sqrt(w * c.reach_weights)[:, None] * (E - T[0]))
        means.append(T[0])
        weights.append(w)
    mean = sum(w * m for w, m in zip(weights, means, strict=True))
    rows.extend(np.sqrt(w) * (m - mean)[None] for w, m in zip(weights, means, strict=True))
    return np.concatenate(rows)


def choose(R: np.ndarray, noise: float, most: int, floor: float) -> list[int]:
    """Indices of at most ``most`` probes chosen greedily by expected information (see the
    module docstring): each the probe of largest predicted variance given the earlier picks'
    measurements (noise σ = ``noise``, m), while that variance exceeds ``floor`` (m²)."""
    C = R.T @ R
    chosen: list[int] = []
    for _ in range(min(most, C.shape[0])):
        var = np.diag(C).copy()
        var[chosen] = -np.inf
        j = int(np.argmax(var))
        if not var[j] > floor:
            break
        chosen.append(j)
        c = C[:, j].copy()
        C = C - np.outer(c, c) / (c[j] + noise**2)
    return chosen
