"""A hand's Pinocchio model reduced to one fingertip's kinematic chain.

With every joint off the chain locked, forward kinematics, the tip's Jacobian and its
acceleration are the same to the bit as on the full model when the other joints keep still
(tested), over fewer joints (9 instead of 15 for hand3x3's wrist + one finger): the rolling
step's kinematics use it.
"""

from __future__ import annotations

import weakref
from typing import Any

import pinocchio as pin

__all__ = ["chain_model"]

# per hand: finger -> (Pinocchio model reduced to the tip's chain, the tip frame's id in it)
_CHAIN_MODELS: weakref.WeakKeyDictionary[Any, dict[str, tuple[Any, int]]] = weakref.WeakKeyDictionary()


def chain_model(hand: Any, finger: str, fid: int, chain: list[int]) -> tuple[Any, int]:
    """``hand``'s model with every joint off the tip's kinematic chain locked (built once per
    hand and finger, ~0.25 ms; read-only, shared by the rollers, each with its own data)."""
    per_hand = _CHAIN_MODELS.setdefault(hand, {})
    if finger not in per_hand:
        model = hand.model
        kept = set(chain)
        lock = [j for j in range(1, model.njoints) if int(model.idx_vs[j]) not in kept]
        frame = model.frames[fid]
        reduced = pin.buildReducedModel(model, lock, pin.neutral(model))
        per_hand[finger] = (reduced, int(reduced.getFrameId(frame.name, frame.type)))
    return per_hand[finger]
