"""Exploring the object with a fingertip: which finger probes which side
(:class:`ProbeChoice`, used by EP1 and EP2) and what one guarded probe found
(:class:`ProbeOutcome`, :func:`eos_svc.world.probe_motion.guarded_probe`)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.kinematics import HandModel


@dataclass(frozen=True)
class ProbeChoice:
    """Which finger explores the object's top (the non-opposing finger whose closing path runs
    nearest the palm's x–z plane, the first on a tie) and its bottom (the opposing finger), and
    each one's joint ``angles`` (rad) while exploring: its closing path's most forward point."""

    top: str
    bottom: str
    angles: dict[str, float]

    @classmethod
    def for_hand(cls, hand: HandModel, sweeps: dict[str, FingerSweep]) -> ProbeChoice:
        """The choice for ``hand`` from its closing paths."""
        opposing = hand.description.opposing_finger
        upper = [f for f in hand.finger_names if f != opposing]
        side = {f: float(np.min(np.abs(sweeps[f].points[:, 1]))) for f in upper}
        nearest = min(side.values())
        top = next(f for f in upper if side[f] <= nearest + 1e-9)
        angles = {}
        for finger in (top, opposing):
            sweep = sweeps[finger]
            k = int(np.argmax(sweep.points[:, 0]))
            angles[finger] = round(float(sweep.angles[k]), 6) + 0.0  # + 0.0: never -0.0
        return cls(top=top, bottom=opposing, angles=angles)

    def finger(self, side: str) -> str:
        """The finger that explores ``side`` ("top" or "bottom")."""
        return self.bottom if side == "bottom" else self.top


@dataclass(frozen=True)
class ProbeOutcome:
    """What one guarded probe of ``finger`` found: ``event`` "touched" (the tip's ``centre`` and
    the sensed outward ``normal``, world, m), "missed" or "blocked" (``why``), those two with the
    ``free`` tip-centre path (N, 3); the length ``travelled`` (m)."""

    event: str
    finger: str
    centre: np.ndarray | None = None
    normal: np.ndarray | None = None
    free: np.ndarray | None = None
    travelled: float = 0.0
    why: str = ""


def densify(path: np.ndarray, spacing: float = 0.005) -> np.ndarray:
    """The polyline ``path`` (N, 3) resampled at most ``spacing`` m apart (a guarded probe's tip
    path is free between its samples: each step was shorter than the tip's gap)."""
    dense = [path[0]]
    for a, b in itertools.pairwise(path):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
        dense.extend(a + (b - a) * (i / n) for i in range(1, n + 1))
    return np.array(dense)
