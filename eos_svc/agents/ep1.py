"""ep1: the exploratory procedure EP1 as an agent (paper §2.2).

Each action rolls one fingertip on the object without sliding along two tangent directions
(:func:`eos_svc.kinematics.ep1.run_ep1`) and adds the samples to that side's curvature
estimator. The top is felt by an upper finger (:class:`~eos_svc.world.probing.ProbeChoice`), the
bottom, when post_shape asks, by the opposing finger — on a table the bottom is the table's
plane and the opposing finger feels the top. The other fingers stay open. The sensed contacts
go on the board (``keys.EP1_CONTACT``); docs/planner.md has the detail.

Opportunistic sub-rating: after post_shape asked for the bottom or for more rolling,
1 − σ_R/R of the estimate (paper §2.2), floor 0.05; 0 once it asks for something else.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.ep1 import EP1Result
from eos_svc.kinematics.hand import KinematicsError
from eos_svc.kinematics.rolling import RollingQPError
from eos_svc.schema import keys

#: QP backend EP1 falls back on when OSQP does not converge on a roll
FALLBACK_SOLVER = "daqp"
#: lowest opportunistic sub-rating of EP1 while the shape is not known
RATING_FLOOR = 0.05
#: EP1 keeps the hand's configuration every this many rolling steps for viewers (keys.HAND_PATH)
PATH_EVERY = 8
#: how far above/below the hand's grasp centre the exploration aims (m): far enough that the
#: closest surface point is the object's top (bottom)
PROBE_REACH = 0.5


class EP1Agent(GraspAgent):
    """Rolls a fingertip on the object (top, then bottom if asked) and estimates its curvature."""

    reads = frozenset({keys.SHAPE, keys.CURVATURE, keys.APPROACH, keys.EP1_RUNS, keys.EP1_CONTACT})
    writes = frozenset(
        {
            keys.APPROACH,
            keys.CURVATURE,
            keys.CURVATURE_BOTTOM,
            keys.EP1_RUNS,
            keys.EP1_CONTACT,
            keys.HAND_PATH,
        }
    )

    def __init__(self, default: float, world: HandDriver, solver: str = "osqp") -> None:
        super().__init__("ep1", (INFO,), default, world)
        self.solver = solver
        self.side: str | None = None
        self.estimators: dict[str, CurvatureEstimator] = {}

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = board.get(keys.SHAPE)
        if shape is None or shape.get("needs") not in ("bottom", "curvature"):
            return 0.0
        if not ctx.changed(keys.SHAPE):
            return 0.0
        rating = float(board.get(keys.CURVATURE, {}).get("rating", 0.0))
        return max(RATING_FLOOR, min(1.0, rating))

    def _place(self, side: str, finger: str) -> tuple[np.ndarray, np.ndarray]:
        """Bring ``finger`` onto the object's top (bottom), the other fingers opened; the object's
        surface point nearest the hand and the unit direction toward it (world)."""
        world = self.world
        hand = world.hand
        q = world.joint_positions()
        q[hand.wrist_q_index[3:6]] = 0.0
        for other in hand.finger_names:
            idx = hand.finger_q_index(other)
            q[idx] = world.probe.angles[finger] if other == finger else hand.lower[idx]
        sign = 1.0 if side == "top" else -1.0
        # Proximity: the object's surface point nearest the grasp centre, 1 cm inside it,
        # then straight up (down) — the closest surface point from there is on the top (bottom).
        centre = world.grasp_centre_world()
        near = world.nearest_surface_point(centre)
        inward = near - centre
        norm = float(np.linalg.norm(inward))
        direction = inward / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
        inside = near + 0.01 * direction
        aim = inside + np.array([0.0, 0.0, sign * PROBE_REACH])
        world.place_tip_on(finger, q, aim)
        return near, direction

    def _roll(self, finger: str, estimator: CurvatureEstimator, solver: str) -> EP1Result:
        p = self.world.params
        return self.world.roll(
            finger,
            omega=p.ep1_omega,
            dt=p.ep1_dt,
            steps_per_direction=p.ep1_steps,
            directions=p.ep1_directions,
            solver=solver,
            estimator=estimator,
            path_every=PATH_EVERY,
        )

    def _table_bottom(self, board: Board, finger: str) -> ActionResult:
        """On a table the object's bottom is the table's plane under the top contact (normal −z),
        recorded as the bottom contact without a probe from under it."""
        contacts = dict(board.get(keys.EP1_CONTACT, {}))
        top = contacts.get("top")
        if top is None:
            return ActionResult(Outcome.CANNOT_ACT, "no top contact yet to place the bottom under")
        height = float(self.world.support_height)  # type: ignore[arg-type]
        point = [top["point"][0], top["point"][1], round(height, 6)]
        contacts["bottom"] = {"finger": finger, "point": point, "normal": [0.0, 0.0, -1.0]}
        board.set(keys.EP1_CONTACT, contacts)
        return ActionResult(
            Outcome.PROGRESS,
            f"the object rests on the table: its bottom is the table's plane z = {height:.3f} m "
            "(no probe from under the table)",
        )

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        world = self.world
        shape = board.get(keys.SHAPE)
        side = "bottom" if shape is not None and shape.get("needs") == "bottom" else "top"
        finger = world.probe_finger(side)
        if side == "bottom" and world.support_height is not None:
            return self._table_bottom(board, finger)
        moved = ""
        if self.side != side or not world.touching(finger):
            try:
                near, direction = self._place(side, finger)
            except KinematicsError as exc:
                return ActionResult(
                    Outcome.CANNOT_ACT, f"cannot bring {finger} onto the object's {side}: {exc}"
                )
            self.side = side
            moved = f"brought {finger} onto the object's {side}; "
            if keys.APPROACH not in board:
                board.set(
                    keys.APPROACH,
                    {"point": np.round(near, 6).tolist(), "direction": np.round(direction, 6).tolist()},
                )
        estimator = self.estimators.setdefault(side, CurvatureEstimator())
        fallback = ""
        try:
            result = self._roll(finger, estimator, self.solver)
        except (RollingQPError, KinematicsError) as exc:
            if not isinstance(exc, RollingQPError) or self.solver == FALLBACK_SOLVER:
                return ActionResult(Outcome.CANNOT_ACT, f"EP1 could not roll {finger}: {exc}")
            # OSQP can stall on a feasible but badly conditioned roll (max iterations); the
            # dense active-set solver is slower but exact: redo this run with it.
            try:
                self._place(side, finger)
                result = self._roll(finger, estimator, FALLBACK_SOLVER)
            except (RollingQPError, KinematicsError) as exc2:
                return ActionResult(Outcome.CANNOT_ACT, f"EP1 could not roll {finger}: {exc}; then {exc2}")
            fallback = f" ({self.solver} stalled: {exc.status}; rolled with {FALLBACK_SOLVER})"
        est = result.estimate
        # Where the contact is, as the fingertip senses it (noisy tactile reading).
        reading = world.tactile(finger)
        point, normal = reading.point, reading.normal
        summary = {
            **est.to_dict(),
            "finger": finger,
            "side": side,
            "max_slip_speed": float(result.max_slip_speed),
        }
        board.set(keys.CURVATURE if side == "top" else keys.CURVATURE_BOTTOM, summary)
        board.set(keys.EP1_RUNS, int(board.get(keys.EP1_RUNS, 0)) + 1)
        contacts = dict(board.get(keys.EP1_CONTACT, {}))
        contacts[side] = {
            "finger": finger,
            "point": np.round(point, 6).tolist(),
            "normal": np.round(normal, 6).tolist(),
        }
        board.set(keys.EP1_CONTACT, contacts)
        board.set(keys.HAND_PATH, [[round(x, 7) for x in q.tolist()] for q in result.path])
        k1, k2 = est.principal_curvatures
        return ActionResult(
            Outcome.PROGRESS,
            f"{moved}{fallback.strip() + '; ' if fallback else ''}rolled {finger} on the {side} "
            f"({result.steps} steps, "
            f"slip ≤ {result.max_slip_speed:.1e} m/s): "
            f"k = ({k1:.1f}, {k2:.1f}) 1/m, relative radius error {est.relative_error:.3f}",
        )
