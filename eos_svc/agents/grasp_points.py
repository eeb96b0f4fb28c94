"""grasp_points: chooses a precision-grip target and pre-shapes the hand.

For a sphere-like postulate of radius R (paper Fig. 2, "a good grasp"): the
contacts lie about a diameter — the opposing finger's tip touches the object
straight below its centre and the upper pair straight above. From the opposing
finger's closing sweep (palm frame) the agent finds the first angle θ* at which
its tip centre is R + r_f from the hand's axis; the object centre must then sit
on the hand axis at that tip's x. The wrist goal follows, and the pre-grasp is
``WorldParameters.approach_distance`` before it (the wrist closes that gap in
the grasping stage). The action moves the hand to the pre-grasp with the
fingers open (a collision-free repositioning, counted as one information cycle)
and completes the information stage.

Opportunistic sub-rating: post_shape's confidence once it is ≥ 60 % and no
target exists yet; 0 otherwise. If the estimated d/h ≥ 1 the object is too big
to grasp (paper §2.1) and the agent ends the run with status failed.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents import keys
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board


class GraspPointsAgent(GraspAgent):
    """Chooses the grasp and places the hand at the pre-grasp."""

    def __init__(self, default: float, world: GraspWorld) -> None:
        super().__init__("grasp_points", (INFO,), default, world)

    def confident_shape(self, board: Board) -> dict | None:
        """post_shape's postulate if it is confident enough, else None."""
        shape = board.get(keys.SHAPE)
        if shape is None or shape["confidence"] < self.world.params.confidence_threshold:
            return None
        return shape

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = self.confident_shape(board)
        if shape is None or keys.TARGET in board:
            return 0.0
        return float(shape["confidence"])

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        shape = self.confident_shape(board)
        if shape is None:
            return ActionResult(Outcome.CANNOT_ACT, "no shape postulated with enough confidence yet")
        if shape["centre"] is None:
            return ActionResult(
                Outcome.FINISHED,
                f"cannot choose grasp points on a {shape['class']} of unknown size from EP1 alone",
                succeeded=False,
            )
        d_over_h = float(board.get(keys.D_OVER_H, 0.0))
        if d_over_h >= 1.0:
            return ActionResult(
                Outcome.FINISHED,
                f"object too large to grasp: estimated d/h = {d_over_h:.2f} ≥ 1",
                succeeded=False,
            )
        world = self.world
        hand = world.hand
        radius = float(shape["grasp_radius"])
        opposing = hand.description.opposing_finger
        sweep = world.sweeps[opposing]
        reach = radius + hand.tip_radius(opposing)
        off_axis = np.hypot(sweep.points[:, 1], sweep.points[:, 2])
        inside = np.nonzero(off_axis <= reach)[0]
        if len(inside) == 0:
            return ActionResult(
                Outcome.FINISHED,
                f"object too small for this hand: radius {radius * 1000:.1f} mm",
                succeeded=False,
            )
        k = int(inside[0])
        x_tip = float(sweep.points[k, 0])
        centre = np.asarray(shape["centre"], dtype=float)
        wrist_goal = centre - np.array([x_tip, 0.0, 0.0])
        lower, upper = hand.lower[hand.wrist_q_index[:3]], hand.upper[hand.wrist_q_index[:3]]
        if np.any(wrist_goal < lower) or np.any(wrist_goal > upper):
            return ActionResult(
                Outcome.FINISHED, "the grasp position is outside the wrist's workspace", succeeded=False
            )
        q = hand.neutral()
        for finger in hand.finger_names:
            idx = hand.finger_q_index(finger)
            q[idx] = hand.lower[idx]  # open
        approach = world.params.approach_distance
        for _ in range(4):
            pre = wrist_goal - np.array([approach, 0.0, 0.0])
            q[hand.wrist_q_index[:3]] = np.clip(pre, lower, upper)
            world.set_q(q)
            if world.hand_clear(world.params.clearance):
                break
            approach += 0.01
        else:
            return ActionResult(Outcome.FINISHED, "no collision-free pre-grasp found", succeeded=False)
        board.set(
            keys.TARGET,
            {
                "wrist": np.round(wrist_goal, 6).tolist(),
                "pregrasp": np.round(pre, 6).tolist(),
                "centre": np.round(centre, 6).tolist(),
                "opposing_angle": round(float(sweep.angles[k]), 6),
            },
        )
        board.set(keys.FINGER_STATE, dict.fromkeys(hand.finger_names, "open"))
        board.set(keys.AT_TARGET, False)
        board.set(keys.WRIST_LEFT, round(approach, 6))
        return ActionResult(
            Outcome.STAGE_COMPLETE,
            f"grasp about the diameter of the {shape['class']} (d/h = {d_over_h:.2f}): centre on the hand "
            f"axis {x_tip * 1000:.1f} mm ahead of the palm; hand placed {approach * 1000:.0f} mm "
            "before it, open",
        )
