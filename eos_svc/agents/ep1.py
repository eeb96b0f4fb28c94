"""ep1: the exploratory procedure EP1 as an agent (paper §2.2).

Each action rolls one fingertip on the object without sliding, along two
tangent directions (``eos_svc.kinematics.ep1.run_ep1``), and adds the samples to
the run's curvature estimator, so repeated EP1 runs sharpen one estimate. The
first run brings the fingertip closest to the object into contact.

Opportunistic sub-rating: after post_shape has pondered a new estimate and is
not yet confident (< 60 %), the complement of the estimate's relative radius
error, ``1 − σ_R/R`` (paper §2.2), floored at 0.05 so that EP1 keeps being
chosen while the shape is unknown; 0 once the shape is postulated with
enough confidence.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents import keys
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board
from eos_svc.kinematics.ep1 import place_hand_for_ep1, run_ep1
from eos_svc.kinematics.hand import KinematicsError
from eos_svc.kinematics.rolling import RollingQPError

#: lowest opportunistic sub-rating of EP1 while the shape is not known
RATING_FLOOR = 0.05


class EP1Agent(GraspAgent):
    """Rolls a fingertip on the object and estimates its curvature."""

    def __init__(self, default: float, world: GraspWorld, solver: str = "osqp") -> None:
        super().__init__("ep1", (INFO,), default, world)
        self.solver = solver
        self.finger: str | None = None

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = board.get(keys.SHAPE)
        if shape is None or shape["confidence"] >= self.world.params.confidence_threshold:
            return 0.0
        if not ctx.changed(keys.SHAPE):
            return 0.0
        rating = float(board.get(keys.CURVATURE, {}).get("rating", 0.0))
        return max(RATING_FLOOR, min(1.0, rating))

    def _choose_finger(self) -> str:
        world = self.world
        return min(world.hand.finger_names, key=world.tip_distance)

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        world = self.world
        p = world.params
        moved = ""
        if self.finger is None or not world.touching(self.finger):
            self.finger = self._choose_finger()
            try:
                world.set_q(place_hand_for_ep1(world.scene, self.finger, q=world.state.q))
            except KinematicsError as exc:
                return ActionResult(Outcome.CANNOT_ACT, f"cannot bring {self.finger} into contact: {exc}")
            moved = f"brought {self.finger} into contact; "
        finger = self.finger
        try:
            result = run_ep1(
                world.scene,
                world.state,
                finger,
                world.sensor,
                omega=p.ep1_omega,
                dt=p.ep1_dt,
                steps_per_direction=p.ep1_steps,
                directions=p.ep1_directions,
                solver=self.solver,
                estimator=world.estimator,
            )
        except (RollingQPError, KinematicsError) as exc:
            world.sync()
            return ActionResult(Outcome.CANNOT_ACT, f"EP1 could not roll {finger}: {exc}")
        world.sync()  # run_ep1 moved the state directly
        est = result.estimate
        # Where the contact is, as the fingertip senses it (noisy tactile reading).
        reading = world.sensor.read(world.state, world.scene.contact(world.state, finger))
        tip = world.state.data.oMf[world.hand.tip_frame_id(finger)]
        point = tip.translation + tip.rotation @ reading.point_tip
        normal = -(tip.rotation @ reading.normal_tip)
        summary = est.to_dict()
        summary["finger"] = finger
        summary["max_slip_speed"] = float(result.max_slip_speed)
        board.set(keys.CURVATURE, summary)
        board.set(keys.EP1_RUNS, int(board.get(keys.EP1_RUNS, 0)) + 1)
        board.set(
            keys.EP1_CONTACT,
            {"finger": finger, "point": np.round(point, 6).tolist(), "normal": np.round(normal, 6).tolist()},
        )
        k1, k2 = est.principal_curvatures
        return ActionResult(
            Outcome.PROGRESS,
            f"{moved}rolled {finger} ({result.steps} steps, slip ≤ {result.max_slip_speed:.1e} m/s): "
            f"k = ({k1:.1f}, {k2:.1f}) 1/m, relative radius error {est.relative_error:.3f}",
        )
