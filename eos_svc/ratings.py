"""Ratings and weights, the paper's eq. (4)-(6): P(A_j) = sum_i P(A_j | B_i) * P(B_i) over the
*default*, *opportunistic* and *learned* sub-ratings. Every one and every weight is a probability
in [0, 1], the weights summing to 1; other values are rejected, never clipped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from eos_svc.errors import ValidationError

#: tolerance on sum(weights) == 1
WEIGHT_SUM_TOLERANCE = 1e-9


def check_probability(value: float, field: str) -> float:
    """``value`` as a float if it is a number in [0, 1], else a ValidationError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValidationError(field, f"must be a number in [0, 1], got {type(value).__name__}")
    v = float(value)
    if math.isnan(v):
        raise ValidationError(field, "must be a number in [0, 1], got NaN")
    if not 0.0 <= v <= 1.0:
        raise ValidationError(field, f"must be in [0, 1], got {v!r}")
    return v


@dataclass(frozen=True, slots=True)
class Weights:
    """Weights P(B_i) of the ``default``, ``opportunistic`` and ``learned`` (0 in the paper)
    sub-ratings; each in [0, 1], summing to 1."""

    default: float = 0.5
    opportunistic: float = 0.5
    learned: float = 0.0

    def __post_init__(self) -> None:
        for name in ("default", "opportunistic", "learned"):
            object.__setattr__(self, name, check_probability(getattr(self, name), f"weights.{name}"))
        total = self.default + self.opportunistic + self.learned
        if abs(total - 1.0) > WEIGHT_SUM_TOLERANCE:
            raise ValidationError(
                "weights",
                f"must sum to 1, got default {self.default} + opportunistic "
                f"{self.opportunistic} + learned {self.learned} = {total!r}",
            )

    def total(self, default: float, opportunistic: float, learned: float = 0.0) -> float:
        """The total rating P(A_j) of one agent (paper eq. 6, plus the learned term)."""
        return default * self.default + opportunistic * self.opportunistic + learned * self.learned

    def to_dict(self) -> dict[str, float]:
        """JSON-friendly form."""
        return {"default": self.default, "opportunistic": self.opportunistic, "learned": self.learned}

    @classmethod
    def from_dict(cls, data: object) -> Weights:
        """Build from a mapping with keys default/opportunistic/learned (missing learned = 0)."""
        if not isinstance(data, dict):
            raise ValidationError("weights", f"must be an object, got {type(data).__name__}")
        unknown = set(data) - {"default", "opportunistic", "learned"}
        if unknown:
            raise ValidationError(f"weights.{sorted(unknown)[0]}", "unknown weight")
        for key in ("default", "opportunistic"):
            if key not in data:
                raise ValidationError(f"weights.{key}", "is required")
        return cls(**data)  # each weight checked, and their sum, by __post_init__
