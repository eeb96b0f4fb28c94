"""The agents, post_shape and grasp synthesis never hold the true object: they reach the world
only through the hand driver's protocol (eos_svc.drivers.protocol)."""

from __future__ import annotations

import ast
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, build_agents, build_world
from eos_svc.agents.memory import GraspMemory
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.kinematics import Scene, TactileSensor
from eos_svc.kinematics.hand_state import HandState
from eos_svc.objects import SurfaceObject
from eos_svc.world.world import GraspWorld

PACKAGE = Path(__file__).resolve().parents[2] / "eos_svc"
#: what the agents must not see: the world, its scene, the object, the hand's simulated state
FORBIDDEN_TYPES = (GraspWorld, Scene, SurfaceObject, HandState, TactileSensor)
#: the modules that own the true object (the planner, which builds the world, may import them)
WORLD_MODULES = ("eos_svc.world.world", "eos_svc.drivers.kinematic", "eos_svc.drivers.grip_verdict",
                 "eos_svc.drivers.drake_world", "eos_svc.drivers.zenoh_driver")  # fmt: skip
#: attributes of the world an agent must not read (the driver's protocol has none of them)
FORBIDDEN_ATTRIBUTES = {"scene", "obj", "state", "sensor", "memo", "set_q", "direct_motion"}


def agent_sources() -> list[Path]:
    """Every agent module but the planner (the assembler), and grasp synthesis and fitting."""
    files = [*PACKAGE.joinpath("agents").glob("*.py"), *PACKAGE.joinpath("grasp").glob("*.py")]
    files += PACKAGE.joinpath("shape").glob("*.py")
    return sorted(f for f in files if f.name not in ("planner.py", "board_table.py"))


def imported_modules(tree: ast.AST) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
    return out


def world_reads(tree: ast.AST) -> list[str]:
    """``world.X`` / ``self.world.X`` reads of a forbidden or private attribute."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        base = node.value
        named_world = (isinstance(base, ast.Name) and base.id in ("world", "driver")) or (
            isinstance(base, ast.Attribute) and base.attr in ("world", "driver")
        )
        if named_world and (node.attr in FORBIDDEN_ATTRIBUTES or node.attr.startswith("_")):
            found.append(f"line {node.lineno}: .{node.attr}")
    return found


@pytest.mark.parametrize("path", agent_sources(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_agent_code_imports_the_protocol_only_and_reads_no_world_part(path: Path) -> None:
    tree = ast.parse(path.read_text())
    assert not imported_modules(tree) & set(WORLD_MODULES), f"{path.name} imports a world"
    assert world_reads(tree) == [], f"{path.name} reads the world behind the driver"


def test_the_source_check_flags_a_world_read() -> None:
    snippet = "c = self.world.scene.contact(self.world.state, f)\nworld._world.obj"
    assert sorted(world_reads(ast.parse(snippet))) == ["line 1: .scene", "line 1: .state", "line 2: ._world"]
    assert imported_modules(ast.parse("from eos_svc.world.world import GraspWorld")) & set(WORLD_MODULES)


def reachable(value: Any, depth: int, seen: set[int]) -> list[tuple[str, Any]]:
    """Every value reachable from ``value`` through public attributes (properties included),
    dict values and sequence items, ``depth`` levels deep."""
    if depth == 0 or id(value) in seen or isinstance(value, (str, bytes, int, float, np.ndarray, type)):
        return []
    seen.add(id(value))
    out: list[tuple[str, Any]] = []
    children: list[tuple[str, Any]] = []
    if isinstance(value, dict):
        children = [(repr(k), v) for k, v in value.items()]
    elif isinstance(value, (list, tuple, set, frozenset)):
        children = [(f"[{i}]", v) for i, v in enumerate(value)]
    else:
        for name in dir(value):
            if name.startswith("_"):
                continue
            try:
                with warnings.catch_warnings():  # Pinocchio's deprecated members
                    warnings.simplefilter("ignore")
                    child = getattr(value, name)
            except Exception:  # a property that cannot be read is no path
                continue
            if callable(child) and not hasattr(child, "__dict__"):
                continue  # a bound method: calling it is the protocol
            children.append((name, child))
    for name, child in children:
        out.append((name, child))
        out.extend((f"{name}.{n}", v) for n, v in reachable(child, depth - 1, seen))
    return out


def held_world_parts(agent: Any) -> list[str]:
    return [
        f"{agent.name}.{path}"
        for path, value in reachable(agent, 4, set())
        if isinstance(value, FORBIDDEN_TYPES)
    ]


def test_no_agent_can_reach_the_true_object_through_public_attributes() -> None:
    world = build_world(PlanRequest(seed=1))
    agents = build_agents(world, memory=GraspMemory(":memory:"))
    for agent in agents:
        assert isinstance(agent.world, KinematicDriver)  # the world itself was wrapped
        assert held_world_parts(agent) == []


def test_the_reachability_walk_finds_a_world_handed_to_an_agent() -> None:
    """The walk above can fail: an agent given the world itself reaches its object."""
    world = build_world(PlanRequest(seed=1))
    agent = build_agents(world)[0]
    agent.world = world  # type: ignore[assignment]  # what the planner must never do
    found = held_world_parts(agent)
    assert any(path.endswith("world.scene") for path in found)
    assert any(path.endswith(".obj") for path in found)


def test_no_agent_reads_the_moving_object_pose_the_viewers_get() -> None:
    from eos_svc.schema import keys

    agents = build_agents(build_world(PlanRequest(seed=1)), memory=GraspMemory(":memory:"))
    assert all(keys.OBJECT_POSE not in agent.reads for agent in agents)
    assert all("OBJECT_POSE" not in path.read_text() for path in agent_sources())
