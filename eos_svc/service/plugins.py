"""The plug-in agents a service instance offers (``eos serve --agent SPEC``).

A SPEC is ``NAME=module:attr`` (offered as NAME), ``module:attr`` or the name of an
``eos_svc.agents`` entry point (offered under the SPEC itself). Each is resolved when the
instance starts (:func:`eos_svc.agents.plugins.loading.resolve`), so a bad one stops ``eos
serve`` before it serves; a request then names the plug-ins it wants in its ``agents`` field,
and the planner takes them from this mapping only — a request cannot make the service import
anything else.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from eos_svc.errors import ValidationError


def offered_plugins(specs: Sequence[str], field: str = "--agent") -> dict[str, Any]:
    """Name -> plug-in factory for each SPEC (module docstring).

    Raises:
        ValidationError: naming ``field``, for a SPEC that does not resolve or a name given twice.
    """
    from eos_svc.agents.plugins.loading import resolve  # lazy: the planner's world loads here

    offered: dict[str, Any] = {}
    for spec in specs:
        name, _, target = spec.rpartition("=") if "=" in spec else (spec, "", spec)
        if not name:
            raise ValidationError(field, f"{spec!r}: the name before '=' is empty")
        if name in offered:
            raise ValidationError(field, f"plug-in name {name!r} is given twice")
        offered[name] = resolve(target, field)
    return offered
