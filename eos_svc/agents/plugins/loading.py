"""Naming, building and checking plug-in agents of the grasp planner.

A *plug-in* is one of:

- a factory: a callable taking the plan's :class:`~eos_svc.drivers.protocol.HandDriver` and
  returning an :class:`~eos_svc.agent.Agent` (an ``Agent`` subclass whose constructor takes the
  world is one) — called once per plan;
- an ``Agent`` instance, used as it is (an agent bound to no world, e.g. a
  :class:`~eos_svc.remote_agents.proxy.RemoteAgent`);
- a name: an entry point of the ``eos_svc.agents`` group (an installed package declares
  ``[project.entry-points."eos_svc.agents"] my_agent = "my_pkg.agents:MyAgent"``), or
  ``module:attr`` naming a factory directly.

Every plug-in agent is checked before the plan's first cycle (:func:`check_contract`): it is an
``Agent``, its name is new, its stages are the planner's, and every board entry it reads or
writes is declared — in :data:`eos_svc.schema.board_entries.ENTRIES`, or by the agent itself
in a ``board_entries`` class attribute (entry name -> :class:`~eos_svc.schema.board_entries.Entry`)
for entries of its own. In ``check_board`` mode the controller then holds it to those
declarations as it holds the built-in agents. Plug-ins join the agent list just before ``end``,
in the order given (ties go to the agent listed first, so the built-in agents win them).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Union

from eos_svc.agent import Agent
from eos_svc.drivers.protocol import HandDriver
from eos_svc.errors import ValidationError
from eos_svc.schema.board_entries import ENTRIES, Entry

#: the entry-point group installed packages register their agents in
ENTRY_POINT_GROUP = "eos_svc.agents"

#: a factory of a plug-in agent: called with the plan's world
AgentFactory = Callable[[HandDriver], Agent]
#: what ``plan(..., agents=[...])`` takes: a factory, an agent, or a name
PluginSpec = Union[str, AgentFactory, Agent]  # noqa: UP007 (a runtime alias on Python 3.10)


def available() -> dict[str, EntryPoint]:
    """The installed plug-ins (the ``eos_svc.agents`` entry points), by name."""
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


def resolve(spec: str, field: str = "agents") -> AgentFactory:
    """The factory a name stands for: ``module:attr`` (imported), else an entry point's name.

    Raises:
        ValidationError: naming ``field``, when the module, the attribute or the entry point
            does not exist, or what it names is not callable.
    """
    if not isinstance(spec, str) or not spec:
        raise ValidationError(field, f"must be a non-empty plug-in name, got {spec!r}")
    if ":" in spec:
        module_name, _, attr = spec.partition(":")
        try:
            found: Any = importlib.import_module(module_name)
        except ImportError as exc:
            raise ValidationError(field, f"cannot import module {module_name!r}: {exc}") from None
        for part in attr.split("."):
            if not hasattr(found, part):
                raise ValidationError(field, f"module {module_name!r} has no attribute {attr!r}")
            found = getattr(found, part)
    else:
        installed = available()
        if spec not in installed:
            names = ", ".join(sorted(installed)) or "none"
            raise ValidationError(
                field,
                f"no plug-in named {spec!r} in entry-point group {ENTRY_POINT_GROUP!r} (installed: {names})",
            )
        try:
            found = installed[spec].load()
        except Exception as exc:
            raise ValidationError(
                field, f"plug-in {spec!r} failed to load: {type(exc).__name__}: {exc}"
            ) from None
    if not callable(found):
        raise ValidationError(field, f"{spec!r} is a {type(found).__name__}, not an agent factory")
    return found


def own_entries(agent: Agent) -> Mapping[str, Entry]:
    """The board entries an agent declares for itself (its ``board_entries``, else none)."""
    declared = getattr(agent, "board_entries", None)
    return {} if declared is None else declared


def check_contract(
    agent: object,
    field: str,
    taken: Iterable[str],
    stages: Sequence[str],
    entries: Mapping[str, Entry] = ENTRIES,
) -> Agent:
    """``agent`` if it keeps the plug-in contract (module docstring), else a clear error.

    Raises:
        ValidationError: naming ``field`` (the plug-in's place, e.g. ``agents[0]``) and what
            is wrong.
    """
    if not isinstance(agent, Agent):
        raise ValidationError(field, f"must make an eos_svc.Agent, got {type(agent).__name__}")
    name = agent.name
    if name in set(taken):
        raise ValidationError(f"{field}.name", f"agent name {name!r} is already taken in this plan")
    unknown = sorted(agent.stages - set(stages))
    if unknown:
        raise ValidationError(
            f"{field}.stages", f"unknown stage(s) {unknown} (the planner's: {list(stages)})"
        )
    own = own_entries(agent)
    if not isinstance(own, Mapping) or not all(isinstance(e, Entry) for e in own.values()):
        raise ValidationError(f"{field}.board_entries", "must map entry names to schema.board_entries.Entry")
    clash = sorted(set(own) & set(entries))
    if clash:
        raise ValidationError(f"{field}.board_entries", f"redeclares the planner's entries {clash}")
    for kind, declared in (("reads", agent.reads), ("writes", agent.writes)):
        undeclared = sorted(k for k in declared if k not in entries and k not in own)
        if undeclared:
            raise ValidationError(
                f"{field}.{kind}",
                f"agent {name!r} declares entries {undeclared} that no one declares a type for "
                "(eos_svc.schema.board_entries.ENTRIES, or the agent's own board_entries)",
            )
    return agent


def plugin_agents(
    world: HandDriver, plugins: Sequence[PluginSpec], builtin: Sequence[Agent], stages: Sequence[str]
) -> list[Agent]:
    """The plug-in agents of one plan, built and checked, in the order given.

    Raises:
        ValidationError: naming ``agents[i]``, for a plug-in that cannot be resolved, fails
            to build, or breaks the contract.
    """
    if isinstance(plugins, (str, bytes)) or not isinstance(plugins, Sequence):
        raise ValidationError("agents", f"must be a list of plug-ins, got {type(plugins).__name__}")
    taken = [a.name for a in builtin]
    out: list[Agent] = []
    for i, spec in enumerate(plugins):
        field = f"agents[{i}]"
        if isinstance(spec, Agent):
            agent: object = spec
        else:
            factory = resolve(spec, field) if isinstance(spec, str) else spec
            if not callable(factory):
                raise ValidationError(
                    field, f"must be a name, a factory or an Agent, got {type(spec).__name__}"
                )
            try:
                agent = factory(world)
            except ValidationError:
                raise
            except Exception as exc:
                raise ValidationError(
                    field, f"the plug-in failed to build: {type(exc).__name__}: {exc}"
                ) from None
        out.append(check_contract(agent, field, taken, stages))
        taken.append(out[-1].name)
    return out


def requested_plugins(names: Sequence[str], offered: Mapping[str, PluginSpec] | None) -> list[PluginSpec]:
    """The plug-ins a request names (``PlanRequest.agents``): looked up in ``offered`` when
    given (a service instance's), else left as names for :func:`plugin_agents` to resolve.

    Raises:
        ValidationError: naming ``agents[i]``, for a name ``offered`` does not hold.
    """
    if offered is None:
        return list(names)
    out = []
    for i, name in enumerate(names):
        if name not in offered:
            have = ", ".join(sorted(offered)) or "none"
            raise ValidationError(f"agents[{i}]", f"plug-in {name!r} is not offered here (offered: {have})")
        out.append(offered[name])
    return out


def plugin_entries(agents: Iterable[Agent]) -> dict[str, Entry]:
    """The board entries the plug-in agents declare for themselves, merged."""
    merged: dict[str, Entry] = {}
    for agent in agents:
        merged.update(own_entries(agent))
    return merged
