"""The kinematic world behind the driver protocol: exact, the object fixed in space.

:class:`KinematicDriver` is the :class:`~eos_svc.drivers.protocol.HandDriver` of a
:class:`~eos_svc.world.world.GraspWorld` — the simulated hand (Pinocchio) and the true object
(coal) with exact contact queries. The world stays private to the driver: the agents reach
the object only through the protocol's sensing and guarded motions. Every call is the world's
own (the same queries, the same order), so a plan through this driver is the plan of the
paper's experiments, cycle for cycle.

What this world guarantees: touches are exact (the hand stops within the contact tolerance,
never pushing); the object never moves; touches carry no force (0 N); the clock counts the
hand's moves (no dynamics), so :meth:`KinematicDriver.clock` is 0 throughout.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from eos_svc.drivers.grip_verdict import grasp_geometry
from eos_svc.drivers.protocol import FingerStep, JointState, TactileReading, Touch, WristMove
from eos_svc.kinematics.ep1 import EP1Result, place_hand_for_ep1, run_ep1
from eos_svc.kinematics.hand import HandState
from eos_svc.world import finger_closing, probe_motion, wrist_motion

if TYPE_CHECKING:
    from eos_svc.grasp.sweeps import FingerSweep
    from eos_svc.kinematics import HandModel
    from eos_svc.kinematics.curvature import CurvatureEstimator
    from eos_svc.world.hand_context import HandContext
    from eos_svc.world.parameters import WorldParameters
    from eos_svc.world.probing import ProbeChoice, ProbeOutcome
    from eos_svc.world.world import GraspWorld


class KinematicDriver:
    """The driver of a :class:`~eos_svc.world.world.GraspWorld` (see the module docstring)."""

    __slots__ = ("_scratch", "_world")

    def __init__(self, world: GraspWorld) -> None:
        self._world = world
        self._scratch: HandState | None = None  # EP1's placements reuse one state of the hand

    # --- what the hand is ------------------------------------------------------------------------
    @property
    def context(self) -> HandContext:
        """The hand's context."""
        return self._world.context

    @property
    def hand(self) -> HandModel:
        """The hand model."""
        return self._world.context.hand

    @property
    def params(self) -> WorldParameters:
        """The planner's constants."""
        return self._world.context.params

    @property
    def sweeps(self) -> dict[str, FingerSweep]:
        """Each finger's closing sweep (palm frame)."""
        return self._world.context.sweeps

    @property
    def probe(self) -> ProbeChoice:
        """The probing fingers and their angles."""
        return self._world.context.probe

    @property
    def rng(self) -> np.random.Generator:
        """The plan's seeded generator."""
        return self._world.rng

    @property
    def tactile_noise(self) -> float:
        """The tactile sensor's noise, m."""
        return float(self._world.sensor.noise_std)

    # --- joint state and clock -------------------------------------------------------------------
    @property
    def table_height(self) -> float | None:
        """The table's height (m), ``None`` without one."""
        return self._world.table_height

    @property
    def support_height(self) -> float | None:
        """The surface the object rests on (m): the table's, ``None`` without one."""
        return self._world.table_height

    @property
    def object_fixed(self) -> bool:
        """True: the kinematic world's object never moves."""
        return True

    @property
    def kinematic_sigma(self) -> float:
        """The joint encoders' fingertip position uncertainty, m."""
        return float(self._world.encoders.position_sigma)

    @property
    def probes(self) -> int:
        """Guarded probes run so far."""
        return self._world.probes

    def probe_finger(self, face: str) -> str:
        """The finger that explores ``face`` (:meth:`GraspWorld.probe_finger`)."""
        return self._world.probe_finger(face)

    def joint_state(self) -> JointState:
        """The configuration and the clock (always 0 s: no dynamics)."""
        return JointState(tuple(self._world.q_list()), self.clock())

    def joint_positions(self) -> np.ndarray:
        """The configuration (a copy)."""
        return self._world.state.q

    def q_list(self) -> list[float]:
        """The configuration as floats (do not modify)."""
        return self._world.q_list()

    def clock(self) -> float:
        """0 s: the kinematic world has no time."""
        return 0.0

    def wrist_position(self) -> np.ndarray:
        """The wrist's world position, m."""
        return self._world.wrist_position()

    def wrist_xyz(self) -> tuple[float, float, float]:
        """The wrist's world position as floats, m."""
        return self._world.wrist_xyz()

    def palm_views(self) -> tuple[np.ndarray, np.ndarray]:
        """The palm frame's translation and rotation (live views)."""
        return self._world.palm_views()

    def grasp_centre_world(self) -> np.ndarray:
        """The grasp centre, world, m."""
        return self._world.grasp_centre_world()

    def finger_angle(self, finger: str) -> float:
        """The finger's joint angle, rad."""
        return self._world.finger_angle(finger)

    # --- proximity and touch ---------------------------------------------------------------------
    def object_gap_to_grasp_centre(self) -> float:
        """Grasp centre to object surface, m (exact)."""
        return self._world.object_gap_to_grasp_centre()

    def located(self) -> bool:
        """The object is within the hand's envelope."""
        return self._world.located()

    def nearest_surface_point(self, point: np.ndarray) -> np.ndarray:
        """The object's surface point nearest ``point`` (exact), m."""
        return np.asarray(self._world.obj.closest_surface_point(np.asarray(point, dtype=float)))

    def hand_clear(self, threshold: float) -> bool:
        """Every hand geometry at least ``threshold`` m from the object."""
        return self._world.hand_clear(threshold)

    def touching(self, finger: str) -> bool:
        """Whether the tip touches (within the contact tolerance)."""
        return self._world.touching(finger)

    def tactile(self, finger: str) -> TactileReading:
        """The tactile sensor's reading of ``finger`` (one noisy sample)."""
        world = self._world
        state = world.state
        contact = world.scene.contact(state, finger)
        reading = world.sensor.read(state, contact)
        tip = world.encoders.tip_frame(state, finger)  # as the joint encoders report it
        return TactileReading(
            finger=finger,
            in_contact=bool(reading.in_contact),
            point=tip.translation + tip.rotation @ reading.point_tip,
            normal=-(tip.rotation @ reading.normal_tip),
            point_tip=np.asarray(reading.point_tip),
            force=0.0,
        )

    # --- acting ----------------------------------------------------------------------------------
    def move_joints(self, q: np.ndarray) -> None:
        """Place the hand at ``q`` (validated by the hand model)."""
        self._world.set_q(q)

    def search_step(self) -> tuple[str, float, bool]:
        """One search sweep (:func:`eos_svc.world.wrist_motion.search_step`)."""
        return wrist_motion.search_step(self._world)

    def guarded_wrist_move(self, target: np.ndarray, stop_when_located: bool = False) -> WristMove:
        """A guarded straight wrist move (:func:`eos_svc.world.wrist_motion.guarded_wrist_move`)."""
        world = self._world
        moved, blocked = wrist_motion.guarded_wrist_move(world, target, stop_when_located)
        left = float(np.linalg.norm(np.asarray(target, dtype=float) - world.wrist_position()))
        return WristMove(moved, blocked, left, self._witness() if blocked else None)

    def step_wrist_toward(self, target: np.ndarray, step: float) -> WristMove:
        """A guarded wrist step (:func:`eos_svc.world.wrist_motion.step_wrist_toward`)."""
        world = self._world
        start = world.wrist_position().copy()
        left, blocked = wrist_motion.step_wrist_toward(world, target, step)
        moved = float(np.linalg.norm(world.wrist_position() - start))
        return WristMove(moved, blocked, left, self._witness() if blocked else None)

    def _witness(self) -> np.ndarray:
        world = self._world
        return np.asarray(world.scene.min_distance(world.state).point_object, dtype=float)

    def close_finger_step(self, finger: str, dtheta: float) -> FingerStep:
        """A guarded closing step (:func:`eos_svc.world.finger_closing.close_finger_step`)."""
        world = self._world
        event, angle = finger_closing.close_finger_step(world, finger, dtheta)
        touch = None
        if event == "touched":
            c = world.scene.contact(world.state, finger)
            touch = Touch(finger, np.asarray(c.point_object), np.asarray(c.normal), 0.0)
        return FingerStep(event, angle, touch)

    def guarded_probe(
        self,
        finger: str,
        start: np.ndarray,
        direction: np.ndarray,
        travel: float,
        angle: float,
        yaw: float = 0.0,
    ) -> ProbeOutcome:
        """EP2's guarded probe (:func:`eos_svc.world.probe_motion.guarded_probe`)."""
        return probe_motion.guarded_probe(self._world, finger, start, direction, travel, angle, yaw)

    def place_tip_on(self, finger: str, q: np.ndarray, point: np.ndarray) -> None:
        """EP1's start (:func:`eos_svc.kinematics.ep1.place_hand_for_ep1`)."""
        if self._scratch is None:  # a state of the world's hand reused by every placement
            self._scratch = self._world.hand.state()
        self._world.set_q(
            place_hand_for_ep1(self._world.scene, finger, q=q, point=point, scratch=self._scratch)
        )

    def roll(
        self,
        finger: str,
        *,
        omega: float,
        dt: float,
        steps_per_direction: int,
        directions: Sequence[float],
        solver: str,
        estimator: CurvatureEstimator,
        path_every: int,
    ) -> EP1Result:
        """EP1 (:func:`eos_svc.kinematics.ep1.run_ep1`) on the world's hand and object."""
        world = self._world
        with world.direct_motion() as state:  # run_ep1 moves the state directly
            return run_ep1(
                world.scene,
                state,
                finger,
                world.sensor,
                omega=omega,
                dt=dt,
                steps_per_direction=steps_per_direction,
                directions=directions,
                solver=solver,
                estimator=estimator,
                path_every=path_every,
            )

    def report(self) -> dict[str, Any] | None:
        """The world's figures for the plan result: none for the kinematic world."""
        return None

    # --- the referee -----------------------------------------------------------------------------
    def judge_grip(self, friction: float) -> dict[str, Any]:
        """The grip judged on the true object (:func:`eos_svc.drivers.grip_verdict.grasp_geometry`)."""
        return grasp_geometry(self._world, friction)
