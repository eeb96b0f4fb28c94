"""Curvature estimation from rolling contact (EP1): Montana's first equation with v = 0,
``K_o u = [−ω_y, ω_x]ᵀ − K_f u`` in the contact frame, solved for ``K_o`` (1/m) by least squares
over rolls along two directions (the convention and its proofs: ``docs/ep1.md``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from eos_svc.errors import ValidationError

__all__ = [
    "DEFAULT_FLAT_CURVATURE",
    "CurvatureEstimate",
    "CurvatureEstimator",
    "CurvatureSample",
    "UnderdeterminedError",
]

#: Curvatures below this magnitude [1/m] (radius above 1 m) are "flat" at hand scale;
#: it is also the floor of ``|H|`` in the relative radius error so a plane can be rated.
DEFAULT_FLAT_CURVATURE = 1.0

Array = NDArray[np.float64]


class UnderdeterminedError(ValidationError):
    """The samples do not determine the curvature form (roll along two directions);
    ``field`` is ``"samples"``."""


def _vec2(name: str, value: ArrayLike) -> Array:
    a = np.asarray(value, dtype=float).reshape(-1)
    if a.shape != (2,) or not np.isfinite(a).all():
        raise ValidationError(name, f"expected 2 finite numbers, got {value!r}")
    return a


def _mat2(name: str, value: ArrayLike) -> Array:
    a = np.asarray(value, dtype=float)
    if a.shape != (2, 2) or not np.isfinite(a).all():
        raise ValidationError(name, f"expected a finite 2x2 matrix, got {value!r}")
    if abs(a[0, 1] - a[1, 0]) > 1e-9 * (1.0 + np.abs(a).max()):
        raise ValidationError(name, f"curvature form must be symmetric, got {a.tolist()}")
    return a


@dataclass(frozen=True)
class CurvatureSample:
    """One rolling observation in the contact frame: the fingertip's tangential angular velocity
    relative to the object ``omega_xy`` [rad/s] (or increment [rad]), the contact's velocity over
    the fingertip [m/s] (or displacement [m]) and the fingertip's curvature form ``K_f`` [1/m]."""

    omega_xy: Array
    contact_velocity: Array
    K_f: Array

    def rows(self) -> tuple[Array, Array]:
        """The two least-squares rows ``A (2×3)`` and right-hand side ``b (2,)``."""
        u1, u2 = self.contact_velocity.tolist()  # floats: numpy scalars cost µs each here
        w1, w2 = self.omega_xy.tolist()
        (k11, k12), (k21, k22) = self.K_f.tolist()
        A = np.array(((u1, u2, 0.0), (0.0, u1, u2)))
        return A, np.array((-w2 - (k11 * u1 + k12 * u2), w1 - (k21 * u1 + k22 * u2)))  # (−w₂, w₁) − K_f u


@dataclass(frozen=True)
class CurvatureEstimate:
    """Least-squares estimate of the object's curvature form at the contact.

    Attributes:
        form: symmetric 2×2 curvature form ``K_o`` in the contact frame [1/m].
        covariance: 3×3 covariance of ``(k_xx, k_xy, k_yy)`` [1/m²].
        principal_curvatures: ``(k1, k2)``, eigenvalues of ``form``, ``k1 >= k2`` [1/m].
        principal_directions: 2×2, columns are the unit principal directions in ``C``.
        radii: ``(1/k1, 1/k2)`` [m]; ``inf`` where the curvature is flat (see ``flat``).
        sigma_curvatures: standard deviations of ``(k1, k2)`` [1/m].
        mean_curvature: ``H = (k1 + k2) / 2`` [1/m]; ``sigma_mean_curvature`` its σ.
        mean_radius: ``1 / H`` [m] (``inf`` when flat).
        relative_error: σ_R / R of the mean radius, ``σ_H / max(|H|, flat_curvature)``.
        rating: ``max(0, 1 - relative_error)``, EP1's opportunistic sub-rating.
        flat: per principal direction, ``|k| <= max(flat_curvature, 2 σ_k)``.
        n_samples: number of samples (2 equations each); ``residual_rms`` [1/m·m/s
            units of the equation, i.e. rad/s or rad] of the least-squares residuals.
    """

    form: Array
    covariance: Array
    principal_curvatures: tuple[float, float]
    principal_directions: Array
    radii: tuple[float, float]
    sigma_curvatures: tuple[float, float]
    mean_curvature: float
    sigma_mean_curvature: float
    mean_radius: float
    relative_error: float
    rating: float
    flat: tuple[bool, bool]
    n_samples: int
    residual_rms: float

    @property
    def is_flat(self) -> bool:
        """True when both principal curvatures are flat."""
        return self.flat[0] and self.flat[1]

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (``inf`` becomes ``None``)."""

        def f(x: float) -> float | None:
            return None if not math.isfinite(x) else float(x)

        return {
            "form": self.form.tolist(),
            "principal_curvatures": [float(k) for k in self.principal_curvatures],
            "sigma_curvatures": [f(s) for s in self.sigma_curvatures],
            "radii": [f(r) for r in self.radii],
            "mean_curvature": float(self.mean_curvature),
            "sigma_mean_curvature": f(self.sigma_mean_curvature),
            "mean_radius": f(self.mean_radius),
            "relative_error": f(self.relative_error),
            "rating": float(self.rating),
            "flat": list(self.flat),
            "n_samples": self.n_samples,
            "residual_rms": float(self.residual_rms),
        }


@dataclass
class CurvatureEstimator:
    """Accumulates rolling samples (several EP1 runs' at one contact, in one contact frame) and
    solves for the object's curvature form."""

    flat_curvature: float = DEFAULT_FLAT_CURVATURE
    _samples: list[CurvatureSample] = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.flat_curvature) and self.flat_curvature > 0):
            raise ValidationError("flat_curvature", f"must be a positive number, got {self.flat_curvature}")

    @property
    def samples(self) -> tuple[CurvatureSample, ...]:
        """All samples added so far."""
        return tuple(self._samples)

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self._samples)

    def add_sample(
        self, omega_xy: ArrayLike, contact_velocity_tip: ArrayLike, K_f: ArrayLike
    ) -> CurvatureSample:
        """Add one observation (contact frame; rates or increments, see module doc)."""
        s = CurvatureSample(
            _vec2("omega_xy", omega_xy),
            _vec2("contact_velocity_tip", contact_velocity_tip),
            _mat2("K_f", K_f),
        )
        self._samples.append(s)
        return s

    def add_samples(self, samples: Iterable[CurvatureSample]) -> None:
        """Add samples produced elsewhere (e.g. :attr:`EP1Result.samples`)."""
        for s in samples:
            self.add_sample(s.omega_xy, s.contact_velocity, s.K_f)

    def estimate(self) -> CurvatureEstimate:
        """Least squares over all samples; raises :class:`UnderdeterminedError`."""
        m = len(self._samples)
        if m < 2:
            raise UnderdeterminedError(
                "samples", f"need samples from two independent roll directions, have {m} sample(s)"
            )
        rows = [sample.rows() for sample in self._samples]
        A = np.concatenate([a for a, _ in rows])
        b = np.concatenate([rhs for _, rhs in rows])
        AtA = A.T @ A
        # 2-norm condition number of the symmetric AtA from its eigenvalues
        ev = np.abs(np.linalg.eigvalsh(AtA))
        if np.trace(AtA) == 0.0 or ev.min() == 0.0 or ev.max() / ev.min() > 1e12:
            raise UnderdeterminedError(
                "samples",
                "do not determine the curvature form: roll along two independent "
                "tangent directions (contact velocities are parallel or zero)",
            )
        AtA_inv = np.linalg.inv(AtA)  # well conditioned (checked above): θ and the covariance
        theta = AtA_inv @ (A.T @ b)
        r = b - A @ theta
        dof = 2 * m - 3
        rss = float(r @ r)
        s2 = rss / dof if dof > 0 else math.inf
        cov = s2 * AtA_inv if dof > 0 else np.full((3, 3), math.inf)
        form = np.array([[theta[0], theta[1]], [theta[1], theta[2]]])
        evals, evecs = np.linalg.eigh(form)
        ks = (float(evals[1]), float(evals[0]))  # k1 >= k2 (eigh's eigenvalues ascend)
        dirs = evecs[:, [1, 0]]
        sig = []
        for vx, vy in dirs.T:  # the columns
            g = np.array([vx * vx, 2 * vx * vy, vy * vy])
            sig.append(math.sqrt(max(float(g @ cov @ g), 0.0)) if dof > 0 else math.inf)
        gH = np.array([0.5, 0.0, 0.5])
        H = float(0.5 * (theta[0] + theta[2]))
        sH = math.sqrt(max(float(gH @ cov @ gH), 0.0)) if dof > 0 else math.inf
        kf = self.flat_curvature
        flat = tuple(abs(k) <= max(kf, 2.0 * s) for k, s in zip(ks, sig, strict=True))
        radii = tuple(math.inf if fl else 1.0 / k for k, fl in zip(ks, flat, strict=True))
        mean_flat = abs(H) <= max(kf, 2.0 * sH)
        rel = sH / max(abs(H), kf)
        return CurvatureEstimate(
            form=form,
            covariance=cov,
            principal_curvatures=ks,
            principal_directions=dirs,
            radii=(radii[0], radii[1]),
            sigma_curvatures=(sig[0], sig[1]),
            mean_curvature=H,
            sigma_mean_curvature=sH,
            mean_radius=math.inf if mean_flat else 1.0 / H,
            relative_error=rel,
            rating=max(0.0, 1.0 - rel) if math.isfinite(rel) else 0.0,
            flat=(bool(flat[0]), bool(flat[1])),
            n_samples=m,
            residual_rms=math.sqrt(rss / (2 * m)),
        )
