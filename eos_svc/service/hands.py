"""The hands a service plans with: every registered hand (``eos hands``) and those
``eos serve --hand FILE`` adds; a request names one in its ``hand`` field.

:class:`ServedHands` builds each hand's context once, when the service starts, and gives the
service a planner and an admission check that pick the request's hand
(``PlanService(planner=hands.plan, admission=hands.admit)``).
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from eos_svc.agents.planner import plan
from eos_svc.hands import DEFAULT_HAND, HandRegistry, shipped_hand_files
from eos_svc.kinematics.errors import UnknownNameError
from eos_svc.schema.request import PlanRequest
from eos_svc.world.admission import check_plannable
from eos_svc.world.hand_context import HandContext, default_context

__all__ = ["ServedHands"]


class ServedHands:
    """The hands a service's requests may name, each with its context (built once here).

    Args:
        files: hand description files to register besides the shipped hands (a file's name
            replaces a shipped hand of that name).

    Raises:
        HandDescriptionError: a file's bad key (before the service starts).
    """

    def __init__(self, files: Iterable[str | Path] = ()) -> None:
        registry = HandRegistry(files)
        self.names: tuple[str, ...] = registry.names
        shipped_default = registry.spec(DEFAULT_HAND).source == shipped_hand_files()[DEFAULT_HAND].resolve()
        self._contexts: dict[str, HandContext] = {}
        for name in registry.names:
            if name == DEFAULT_HAND and shipped_default:  # the process's default context
                self._contexts[name] = default_context()
            else:
                self._contexts[name] = HandContext.build(registry.build(name))

    def context(self, request: PlanRequest) -> HandContext:
        """The context of the hand ``request`` names (the default hand when it names none).

        Raises:
            UnknownNameError: field ``hand``, naming the hands this service has.
        """
        name = request.hand or DEFAULT_HAND
        context = self._contexts.get(name)
        if context is None:
            raise UnknownNameError(
                "hand", f"unknown hand {name!r}; this service has: {', '.join(self.names)}"
            )
        return context

    def admit(self, request: PlanRequest) -> None:
        """The admission check of ``request`` with its hand (:func:`check_plannable`)."""
        check_plannable(request, context=self.context(request))

    def plan(
        self,
        request: PlanRequest,
        *,
        on_cycle: Any = None,
        cancel: Any = None,
        keep_trace: bool = True,
        check: bool = False,
    ) -> Any:
        """:func:`~eos_svc.agents.planner.plan` with the hand ``request`` names (``check``: run
        the admission check again; off by default: the service has run :meth:`admit` on this
        request before queueing it)."""
        context = self.context(request)
        return plan(
            request, on_cycle=on_cycle, cancel=cancel, keep_trace=keep_trace, check=check, context=context
        )
