"""A plan's hand state and scene, lent by the hand and taken back when the plan ends.

Every plan's world needs a :class:`~eos_svc.kinematics.HandState` (Pinocchio ``Data`` and
``GeometryData``) and a :class:`~eos_svc.kinematics.Scene` (the object's coal shape, distance
requests, results, transforms and functors). Building them costs ≈ 0.1 ms back to back and
≈ 0.5 ms in a process that has idled a few milliseconds (many small C++ objects, cold caches),
and a service planning one request after another builds the same ones every time.
:class:`WorldParts` keeps a hand's spare ones: :meth:`WorldParts.lend` hands out a spare state
(put back at the hand's neutral ``q``) and a spare scene of the same object (same shape, size
and pose, compared exactly), or new ones; :meth:`WorldParts.give_back` keeps them for the next
plan. A plan gives them back only when it ended normally (done, cancelled, out of cycles): one
that raised drops them.

Neither keeps anything from one plan into the next that a fresh one would not have: a state's
queries recompute from its ``q`` (its Jacobians and geometry placements are marked stale by
every update), and a scene's coal queries start from their default guess every call (coal's
cached GJK guess is off); what a scene builds on first use (its fingertips' geometry model, its
distance functors) depends on the hand and the object alone. The one thing coal carries from a
query to the next is the support-function hint of a convex polytope (``coal.ConvexBase``), so a
hand with such collision geometries gets no spares (every plan builds its own, as before); the
hands and objects here are primitives. The same request gives the same cycles and result either
way (``tests/agents/test_world_parts.py``).

Each lent part belongs to one plan until given back (a lock guards the spares: plans in several
threads never share one). One reference outlives a plan: EP1's per-thread roller
(:func:`eos_svc.kinematics.ep1.run_ep1` keeps one per hand and finger) still holds the state and
scene it last rolled on, and is re-pointed to the next plan's (``use_scene``, ``retarget(state=)``)
before it reads or writes anything. At most ``keep`` of each are kept, the least recently given
back dropped first.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import coal

from eos_svc.agents.postulate import make_object
from eos_svc.kinematics import HandModel, HandState, Scene
from eos_svc.kinematics.hand_cache import PerHandCache
from eos_svc.schema.request import ObjectSpec

__all__ = ["WorldParts", "world_parts"]


def object_key(spec: ObjectSpec) -> str:
    """A key equal for two specs exactly when they make the same object (shape, size, pose):
    ``repr`` writes every float exactly and tells -0.0 from 0.0."""
    return repr((spec.shape, tuple(spec.size.items()), spec.position, spec.rpy))


def history_free(hand: HandModel) -> bool:
    """Whether coal's distance queries on this hand's collision geometries depend on nothing but
    the shapes and their poses: no convex polytope, whose support function coal warm-starts from
    the previous query."""
    return not any(isinstance(go.geometry, coal.ConvexBase) for go in hand.collision_model.geometryObjects)


class WorldParts:
    """A hand's spare plan states and scenes (at most ``keep`` of each)."""

    def __init__(self, hand: HandModel, keep: int = 4) -> None:
        if keep < 0:
            raise ValueError(f"keep must be ≥ 0, got {keep}")
        self.hand = hand
        #: spares kept of each (0 for a hand with a convex polytope: see the module docstring)
        self.keep = keep if history_free(hand) else 0
        self._states: list[HandState] = []
        self._scenes: OrderedDict[str, list[Scene]] = OrderedDict()  # by object key, oldest first
        self._scene_count = 0
        self._lock = threading.Lock()

    def lend(self, spec: ObjectSpec) -> tuple[HandState, Scene]:
        """A state at the hand's neutral ``q`` and a scene of ``spec``'s object, each a spare
        one when there is, otherwise new; the caller's until :meth:`give_back`."""
        key = object_key(spec)
        with self._lock:
            state = self._states.pop() if self._states else None
            spares = self._scenes.get(key)
            scene = spares.pop() if spares else None
            if scene is not None:
                self._scene_count -= 1
                if not spares:
                    del self._scenes[key]
        hand = self.hand
        if state is None:
            state = hand.state(hand.neutral())
        else:
            state.update(hand.neutral())
        if scene is None:
            scene = Scene(hand, make_object(spec))
        return state, scene

    def give_back(self, spec: ObjectSpec, state: HandState, scene: Scene) -> None:
        """Keep ``state`` and ``scene`` (lent for ``spec``) for later plans, within ``keep``.

        Raises:
            ValueError: they belong to another hand.
        """
        if state.hand is not self.hand or scene.hand is not self.hand:
            raise ValueError("state and scene must belong to this hand")
        key = object_key(spec)
        with self._lock:
            if self.keep == 0:
                return
            if len(self._states) < self.keep:
                self._states.append(state)
            self._scenes.setdefault(key, []).append(scene)
            self._scenes.move_to_end(key)
            self._scene_count += 1
            while self._scene_count > self.keep:  # the least recently given back first
                oldest = next(iter(self._scenes))
                spares = self._scenes[oldest]
                spares.pop(0)
                self._scene_count -= 1
                if not spares:
                    del self._scenes[oldest]

    def spares(self) -> tuple[int, int]:
        """How many states and scenes are kept now."""
        with self._lock:
            return len(self._states), self._scene_count


_PARTS: PerHandCache[WorldParts] = PerHandCache(keep=8)


def world_parts(hand: HandModel) -> WorldParts:
    """The hand's :class:`WorldParts`, one per hand and process."""
    return _PARTS.get((hand,), lambda: WorldParts(hand))
