"""pytest fixtures: every registered hand, built from its description, and a scene with an object.

Loaded automatically where eos_svc is installed (entry point ``pytest11``); a checkout used
without installing loads it with ``pytest_plugins = ["eos_svc.testing.pytest_plugin"]`` in a
``conftest.py``. Fixtures:

- ``eos_hand_names`` — the registered hands' names (``eos hands``);
- ``eos_hand`` — each registered hand in turn (a test using it runs once per hand, ids by
  name), a :class:`~eos_svc.hands.DescribedHand` built once per session;
- ``eos_hand_context`` — that hand's :class:`~eos_svc.world.hand_context.HandContext`;
- ``eos_load_hand`` — a function: name or description file → hand, each built once per session;
- ``eos_scene_request`` — a plan request for ``eos_hand``: a sphere of diameter 0.5 × the
  hand's height (at most 0.8 × its fingertips' widest convex reach) in front of it;
- ``eos_world`` — a fresh :class:`~eos_svc.world.world.GraspWorld` of that request (the world
  the agents act in: hand at its start pose, the object, seeded randomness).

Heavy imports (Pinocchio, coal) happen when a fixture is first used, not when pytest starts.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest


def _shipped_names() -> tuple[str, ...]:
    """The shipped descriptions' names, found without importing eos_svc.hands (Pinocchio)."""
    spec = importlib.util.find_spec("eos_svc")
    if spec is None or spec.origin is None:  # pragma: no cover - eos_svc is this package
        return ()
    data = Path(spec.origin).parent / "hands" / "data"
    return tuple(sorted(p.stem for p in data.glob("*.toml")))


#: the hands the parametrized fixtures run over (the shipped descriptions, by name)
HAND_NAMES: tuple[str, ...] = _shipped_names()
#: the scene's sphere diameter as a fraction of the hand's height
SCENE_D_OVER_H = 0.5


@pytest.fixture(scope="session")
def eos_hand_names() -> tuple[str, ...]:
    """The registered hands' names, sorted."""
    return HAND_NAMES


@pytest.fixture(scope="session")
def eos_load_hand() -> Callable[[str | Path], Any]:
    """A function: a registered name or a description file → its hand, built once per session."""
    from eos_svc.hands import HandRegistry

    registry = HandRegistry()
    built: dict[str, Any] = {}

    def load(name_or_file: str | Path) -> Any:
        key = str(name_or_file)
        if key not in built:
            built[key] = registry.build(name_or_file)
        return built[key]

    return load


@pytest.fixture(scope="session", params=HAND_NAMES, ids=HAND_NAMES)
def eos_hand(request: pytest.FixtureRequest, eos_load_hand: Callable[[str], Any]) -> Any:
    """Each registered hand in turn (a :class:`~eos_svc.hands.DescribedHand`)."""
    return eos_load_hand(request.param)


@pytest.fixture(scope="session")
def eos_hand_context(eos_hand: Any) -> Any:
    """The :class:`~eos_svc.world.hand_context.HandContext` of ``eos_hand`` (built once)."""
    from eos_svc.world.hand_context import HandContext

    return HandContext.build(eos_hand)


@pytest.fixture
def eos_scene_request(eos_hand: Any, eos_hand_context: Any) -> Any:
    """A plan request for ``eos_hand``: a sphere of diameter 0.5 × its hand height (at most
    0.8 × the widest convex width all its fingertips reach) at the default object position,
    seed 1."""
    from eos_svc.agents.planner import ratio_sphere_request

    reach = 0.8 * eos_hand_context.opening.curved / eos_hand.hand_height
    return ratio_sphere_request(min(SCENE_D_OVER_H, reach), seed=1, hand=eos_hand)


@pytest.fixture
def eos_world(eos_hand_context: Any, eos_scene_request: Any) -> Any:
    """A fresh world of ``eos_scene_request`` with ``eos_hand`` (admission checked)."""
    from eos_svc.agents.planner import build_world

    return build_world(eos_scene_request, context=eos_hand_context)
