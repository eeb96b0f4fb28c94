"""sampled_grasp_points: a worked example of a plug-in agent — grasp_points with another sampler.

The stock grasp_points agent (:mod:`eos_svc.agents.grasp_points`) tries GraspIt's orientations
per primitive and, of grasps within 5 % of the best ε, takes the least wrist rotation. This
plug-in samples the closing axis instead: ``samples`` directions spread evenly over a
hemisphere (a Fibonacci lattice), each taken in both senses with every approach across it
(:func:`eos_svc.grasp.frames.approach_axes`); every orientation is simulated, checked and scored
as the stock synthesis does (:meth:`eos_svc.grasp.synthesis.GraspSynthesis.score_frames`), and
the best ε wins.

It rates its own worth (paper §2.1): its precondition test, once post_shape's postulate is
confident and no target exists yet, runs both samplers on the postulate and gives post_shape's
confidence when its best grasp has a higher predicted ε than the stock synthesis's best (by
more than :data:`BETTER_BY`, relative), 0 otherwise. Its default sub-rating, 0.65, is above
grasp_points' 0.6: with the paper's weights (0.5/0.5) it is chosen exactly when its grasp is
better, and passed over (its total 0.325, grasp_points' ≥ 0.6) when it is not. Both agents
complete the information stage when they act, so only one of them acts in a plan.

Use it by name (it is registered under the ``eos_svc.agents`` entry-point group)::

    plan(request, agents=["sampled_grasp_points"])
    eos plan --agent sampled_grasp_points

or as a factory with other settings: ``plan(request, agents=[functools.partial(
SampledGraspPointsAgent, samples=8)])``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator

import numpy as np

from eos_svc.agent import CycleContext
from eos_svc.agents.grasp_points import GraspPointsAgent
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.errors import ValidationError
from eos_svc.grasp.candidate import GraspCandidate
from eos_svc.grasp.frames import approach_axes, candidate_frames, frame
from eos_svc.grasp.postulate import read_postulate
from eos_svc.grasp.synthesis import GraspSynthesis
from eos_svc.objects import SurfaceObject
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec

#: the plug-in's default sub-rating: above grasp_points' 0.6, so that it wins when it asks
DEFAULT_RATING = 0.65
#: closing axes sampled by default
DEFAULT_SAMPLES = 12
#: relative margin by which its best ε must beat the stock synthesis's to count as better: 1 %
#: (two routes to the same grasp, or to an equivalent one, differ by less; the stock rule itself
#: counts grasps within 5 % of the best ε as equal)
BETTER_BY = 0.01


def hemisphere_axes(samples: int) -> list[np.ndarray]:
    """``samples`` unit vectors spread evenly over the upper hemisphere (z ≥ 0): a Fibonacci
    lattice, deterministic."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    out = []
    for i in range(samples):
        z = 1.0 - (i + 0.5) / samples  # in (0, 1]
        r = math.sqrt(max(0.0, 1.0 - z * z))
        out.append(np.array([r * math.cos(golden * i), r * math.sin(golden * i), z]))
    return out


def sampled_frames(
    obj: SurfaceObject, samples: int, primitive_frames: bool = True
) -> Iterator[tuple[str, np.ndarray]]:
    """(label, palm rotation) for every sampled closing axis in both senses, every approach
    across it; after GraspIt's orientations for the primitive (the stock synthesis's,
    :func:`eos_svc.grasp.frames.candidate_frames`) when ``primitive_frames``."""
    if primitive_frames:
        yield from candidate_frames(obj)
    for i, g in enumerate(hemisphere_axes(samples)):
        for x in approach_axes(obj, g):
            for sign in (1.0, -1.0):
                yield f"along sampled axis {i}", frame(x, sign * g)


class SampledGraspPointsAgent(GraspPointsAgent):
    """grasp_points with a sampled closing axis (module docstring); a plug-in factory: the
    planner calls it with the plan's world.

    Args:
        world: the plan's world.
        default: default sub-rating (:data:`DEFAULT_RATING`).
        samples: closing axes sampled over the hemisphere (≥ 1).
        primitive_frames: also try GraspIt's orientations for the primitive (the stock
            synthesis's); without them the sampler relies on its samples alone.
        name: the agent's name.
    """

    # the same board contract as grasp_points (inherited reads and writes, restated here)
    reads = GraspPointsAgent.reads
    writes = GraspPointsAgent.writes

    def __init__(
        self,
        world: HandDriver,
        default: float = DEFAULT_RATING,
        samples: int = DEFAULT_SAMPLES,
        primitive_frames: bool = True,
        name: str = "sampled_grasp_points",
    ) -> None:
        super().__init__(default, world, name=name)
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            raise ValidationError(f"agents.{name}.samples", f"must be an integer ≥ 1, got {samples!r}")
        self.samples = samples
        self.primitive_frames = bool(primitive_frames)
        #: per postulate (its JSON form and μ): (own best ε, stock best ε) — this plan's only
        self._compared: dict[str, tuple[float, float]] = {}

    def choose_candidates(self, synthesis: GraspSynthesis, spec: ObjectSpec) -> list[GraspCandidate]:
        """The sampled orientations, checked and scored; best ε first."""
        frames = sampled_frames(synthesis.obj, self.samples, self.primitive_frames)
        return synthesis.score_frames(frames)

    def compare(self, board: Board, shape: dict) -> tuple[float, float] | None:
        """(best predicted ε of this sampler, of the stock synthesis) on the postulate in
        ``shape`` (0 for a sampler that finds no grasp); None when it cannot be planned on."""
        try:
            postulate = read_postulate(shape)
        except ValidationError:
            return None
        if postulate is None:
            return None
        key = json.dumps([postulate.spec.to_dict(), board.get(keys.FRICTION, 0.5)], sort_keys=True)
        known = self._compared.get(key)
        if known is None:
            own = self.choose_candidates(self.synthesis(board, postulate), postulate.spec)
            stock = self.synthesis(board, postulate).candidates()
            known = (own[0].epsilon if own else 0.0, stock[0].epsilon if stock else 0.0)
            self._compared[key] = known
        return known

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = self.confident_shape(board)
        if shape is None or keys.TARGET in board:
            return 0.0
        compared = self.compare(board, shape)
        if compared is None:
            return 0.0
        own, stock = compared
        return float(shape["confidence"]) if own > stock * (1.0 + BETTER_BY) else 0.0
