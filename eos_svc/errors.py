"""Exceptions of the EOS core.

Planning outcomes (stalled, cycle limit, ...) are never exceptions: they are a
:class:`~eos_svc.records.RunStatus`. Exceptions are for programming errors and
bad input, and always name the offending field and the reason.
"""

from __future__ import annotations


class EosError(Exception):
    """Base class of every error raised by eos_svc."""


class ValidationError(EosError, ValueError):
    """A value given to eos_svc is not acceptable.

    Attributes:
        field: dotted name of the offending field (``"weights.default"``).
        reason: why it is rejected, in words.
    """

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")

    def to_dict(self) -> dict[str, str]:
        """JSON-friendly form (used by the CLI and the service's error replies)."""
        return {"field": self.field, "reason": self.reason}
