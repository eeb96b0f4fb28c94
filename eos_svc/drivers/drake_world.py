"""The Drake world behind the driver protocol: the object a free body on a table, under gravity.

:class:`DrakeDriver` drives the hand of a :class:`~eos_svc.drivers.drake_plant.DrakeHandPlant`
(hand on its PD-controlled wrist and finger joints, a table, the object resting on it with its
mass and friction). It keeps a kinematic model of the scene (a
:class:`~eos_svc.world.world.GraspWorld`: the hand in Pinocchio, the object in coal at the pose
Drake reports) to plan each guarded motion, as a robot's driver plans a motion on its model
before it executes it:

- **free-space transfers** (the hand placed between guarded motions: the kinematic world's
  jumps) are made without simulation — a collision-free transfer by the arm is assumed;
- **guarded motions** (the search's sweeps and the wrist's steps, a finger's closing step,
  EP2's probe advance, EP1's roll) are executed in Drake: the PD targets ramp along the
  planned joint path (with its velocity as feed-forward), the motion stops early when any hand
  body pushes the object with more than :attr:`DrakeSettings.stop_force`;
- a **touch** (a closing step or a probe that reached the object) then presses on until the
  fingertip's normal force, read from the plant's contact results, passes
  :attr:`DrakeSettings.touch_force`; the touch reported is Drake's contact point, normal and force;
- after every simulated motion the model takes the object's pose and the hand's joint values
  from Drake: a touch that pushed or rolled the object is seen by the next query;
- **the referee** (:meth:`DrakeDriver.judge_grip`): the contacts and quality on the object where
  it now is, then the lift test (:mod:`eos_svc.drivers.lift_test`); the grip is good only if it
  also held.

:meth:`DrakeDriver.report` says how far the exploration moved the object and how long the
simulation ran: the seconds simulated (the lift test's nine loads, each simulated from the same
lifted state, counted: 2.7 s a grip), the plan's clock and the wall time spent simulating.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from pydrake.math import RigidTransform

from eos_svc.drivers import balanced_squeeze as balanced
from eos_svc.drivers.drake_plant import DrakeHandPlant, PlantSettings
from eos_svc.drivers.grip_verdict import grasp_geometry
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.drivers.lift_test import GRAVITY, SQUEEZE, lift_test, squeeze_grip
from eos_svc.drivers.protocol import RELOCATE_AFTER, FingerStep, TactileReading, Touch, WristMove
from eos_svc.schema.request import ObjectSpec
from eos_svc.world import wrist_motion

if TYPE_CHECKING:
    from eos_svc.kinematics.curvature import CurvatureEstimator
    from eos_svc.kinematics.ep1 import EP1Result
    from eos_svc.world.probing import ProbeOutcome
    from eos_svc.world.world import GraspWorld


@dataclass(frozen=True)
class DrakeSettings:
    """How the Drake world executes guarded motions (SI).

    Attributes:
        free_speed: the wrist's speed in free space (search sweeps), m/s.
        approach_speed: the wrist's speed of a motion that may touch (probes, grasp steps), m/s.
        joint_speed: a rotation's speed (wrist rotations, fingers), rad/s.
        chunk: how often a motion's target is updated and its contacts read, s.
        stop_force: a hand body pushing the object harder than this ends a motion early, N
            (at most :data:`STOP_FRACTION` of the force that slides the resting object: μ m g).
        touch_force: a touch presses on until the fingertip's normal force reaches this, N.
        press_limit: the most a touch presses on past the kinematic first touch (m of the
            wrist; a finger presses on by ``finger_press_limit`` rad).
        finger_press_limit: the most a finger's touch presses on, rad.
        press_steps: a press advances in this many plant steps (its force read at each).
    """

    free_speed: float = 0.5
    approach_speed: float = 0.05
    joint_speed: float = 1.0
    chunk: float = 0.005
    stop_force: float = 2.0
    touch_force: float = 0.05
    press_limit: float = 0.003
    finger_press_limit: float = 0.05
    press_steps: int = 150


#: the longest the object is given to come to rest on the table before the plan starts, s
SETTLE_LIMIT = 3.0
#: a guarded motion stops before a hand body pushes the resting object with more than this
#: fraction of the force that would slide it on the table (μ m g)
STOP_FRACTION = 0.5


class DrakeDriver(KinematicDriver):
    """The hand driver of the Drake world (see the module docstring).

    Args:
        world: the kinematic model (hand, object at its start pose, sensor, randomness).
        spec: the object (its shape and size for Drake).
        friction: Coulomb μ of every contact.
    """

    __slots__ = (
        "_explored",
        "_last_pose",
        "_lift",
        "_motion",
        "_moved_by",
        "_moved_max",
        "_plant",
        "_settings",
        "_sim_wall",
        "_start",
        "_stop",
        "_transfers",
        "_transfers_into",
    )

    def __init__(
        self,
        world: GraspWorld,
        spec: ObjectSpec,
        friction: float,
        settings: DrakeSettings | None = None,
        plant_settings: PlantSettings | None = None,
    ) -> None:
        super().__init__(world)
        self._settings = settings or DrakeSettings()
        self._plant = DrakeHandPlant(
            world.hand, spec, world.obj, friction, plant_settings, table_height=world.table_height
        )
        self._plant.set_hand_q(world.state.q)
        self._plant.simulator.Initialize()
        self._sim_wall = 0.0
        self._timed(self._settle)  # the object comes to rest on the table (it may tip over first)
        self._start = np.array(self._plant.object_pose().translation())  # where it rests
        self._moved_max = 0.0
        self._transfers = 0  # free-space transfers made without simulation
        self._transfers_into = 0  # transfers that placed the hand pressing on the object
        self._explored: float | None = None  # how far the object had moved when the grip was judged
        self._lift: dict[str, Any] | None = None
        self._motion = "settle"  # the motion running now: what moves the object is charged to it
        self._moved_by: dict[str, float] = {}  # per motion kind, how far it moved the object, m
        self._last_pose = self._start.copy()
        weight = self._plant.settings.mass * GRAVITY
        self._stop = min(self._settings.stop_force, STOP_FRACTION * friction * weight)
        self._sync()

    @property
    def support_height(self) -> float | None:
        """The Drake table's top (m): the object rests on it (the hand passes through it)."""
        return self._plant.table_top

    @property
    def object_fixed(self) -> bool:
        """False: the object is a free body a touch may push."""
        return False

    # --- time ---------------------------------------------------------------------------------
    def clock(self) -> float:
        """Simulated time, s."""
        return self._plant.time()

    def _timed(self, run: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return run()
        finally:
            self._sim_wall += time.perf_counter() - t0

    def _settle(self) -> None:
        """Simulate until the object rests (speed < 1 mm/s, spin < 0.05 rad/s: it may topple
        from the pose it was put in) or :data:`SETTLE_LIMIT` s have passed."""
        plant = self._plant
        plant.advance(0.2)
        while plant.time() < SETTLE_LIMIT:
            v = plant.plant.EvalBodySpatialVelocityInWorld(plant.context, plant.body)
            if np.linalg.norm(v.translational()) < 1e-3 and np.linalg.norm(v.rotational()) < 0.05:
                return
            plant.advance(0.1)

    # --- keeping the model in step with Drake ---------------------------------------------------
    def _sync(self, hand: bool = True) -> None:
        """The model takes the object's pose and (with ``hand``) the hand's joint values from Drake."""
        world = self._world
        pose = self._plant.object_pose()
        world.scene.set_object_placement(pin.SE3(np.asarray(pose.rotation().matrix()), pose.translation()))
        if hand:
            model = world.hand
            world.set_q(np.clip(self._plant.hand_q(), model.lower, model.upper))
        self._moved_max = max(self._moved_max, float(np.linalg.norm(pose.translation() - self._start)))
        now = np.array(pose.translation())
        step = float(np.linalg.norm(now - self._last_pose))
        self._moved_by[self._motion] = self._moved_by.get(self._motion, 0.0) + step
        self._last_pose = now

    def object_pose(self) -> list[float]:
        """The object's pose for viewers: x, y, z (m), quaternion w, x, y, z (rounded to 1e-7)."""
        pose = self._plant.object_pose()
        q = pose.rotation().ToQuaternion()
        values = [*pose.translation(), q.w(), q.x(), q.y(), q.z()]
        return [round(float(v), 7) for v in values]

    def displace_object(self, shift: np.ndarray, settle_s: float = 0.3) -> None:
        """Move the object by ``shift`` (world, m; an outside push the hand did not make, as a
        person bumping the table), then let it settle for ``settle_s`` s."""
        plant = self._plant
        pose = plant.object_pose()
        moved = RigidTransform(pose.rotation(), pose.translation() + np.asarray(shift, dtype=float))
        plant.plant.SetFreeBodyPose(plant.context, plant.body, moved)
        self._motion = "outside push"
        self._timed(lambda: plant.advance(settle_s))
        self._sync(hand=False)

    def object_moved(self) -> float:
        """How far the object's centre is from where it rested at the start, m."""
        return float(np.linalg.norm(self._plant.object_pose().translation() - self._start))

    def _execute(
        self, q_from: np.ndarray, q_to: np.ndarray, speed: float, guard: float | None = None
    ) -> bool:
        """Place the hand at ``q_from`` (a transfer), then ramp to ``q_to`` in Drake, the wrist
        at ``speed`` m/s; stops early when a hand body pushes the object harder than
        ``guard`` N (default: the stop force; a touch's motion: the touch force). Returns whether
        it stopped early."""
        plant, s = self._plant, self._settings
        q_from, q_to = np.asarray(q_from, dtype=float), np.asarray(q_to, dtype=float)
        if np.max(np.abs(plant.hand_q() - q_from)) > 1e-6:
            self._transfer(q_from)
        delta = q_to - q_from
        xyz = self._world.wrist_xyz_q
        rest = np.ones(len(delta), dtype=bool)
        rest[xyz] = False
        turn = float(np.max(np.abs(delta[rest]), initial=0.0))
        duration = max(float(np.linalg.norm(delta[xyz])) / speed, turn / s.joint_speed)
        if duration < 1e-9:
            return False
        duration *= 1.5  # a smoothstep profile: its peak speed is 1.5 times its mean
        steps = max(1, int(np.ceil(duration / s.chunk)))
        stopped = False
        limit = self._stop if guard is None else guard

        def run() -> None:
            nonlocal stopped
            t0 = plant.time()
            for k in range(1, steps + 1):
                tau = k / steps  # smoothstep 3τ² − 2τ³: starts and stops at rest, no overshoot kick
                along, rate = (3 - 2 * tau) * tau * tau, 6 * tau * (1 - tau) / duration
                plant.command_moving(q_from + along * delta, rate * delta)
                plant.advance_to(t0 + tau * duration)
                if self._pushing() > limit:
                    plant.command(plant.hand_q())
                    stopped = True
                    return
            plant.advance(s.chunk)  # the hand comes to rest at the target

        self._timed(run)
        self._sync()
        return stopped

    def _transfer(self, q: np.ndarray) -> None:
        """Place Drake's hand at ``q`` without simulating the way there (a free-space transfer:
        the arm's collision-free motion is assumed), counted when the wrist jumps more than 1 mm."""
        jump = float(
            np.linalg.norm(self._plant.hand_q()[self._world.wrist_xyz_q] - q[self._world.wrist_xyz_q])
        )
        if jump > 1e-3:
            self._transfers += 1
        before = self._pushing()
        self._plant.set_hand_q(q)
        if before < self._settings.touch_force < self._stop < self._pushing():  # placed into the object
            self._transfers_into += 1

    def _pushing(self) -> float:
        """The largest normal force of any hand body on the object, N."""
        table = 0  # the world body (the table is welded to it)
        return max((f for other, _, _, f in self._plant.object_contacts() if other != table), default=0.0)

    def _press(self, finger: str, direction: np.ndarray) -> Touch | None:
        """Press on along the joint-space ``direction`` (its length: the most to press on) until
        ``finger``'s tip pushes with ``touch_force``, one plant step at a time so that the press
        ends near that force (a light touch moves no resting object); the touch as Drake
        reports it."""
        plant, s = self._plant, self._settings
        self._motion = self._motion.removesuffix(" press") + " press"
        body = plant.tip_bodies[finger]
        q0 = plant.hand_q()
        found = plant.tip_force(body)
        step = plant.settings.time_step

        def run() -> tuple[np.ndarray, np.ndarray, float] | None:
            nonlocal found
            for k in range(1, s.press_steps + 1):
                if found is not None and found[2] >= s.touch_force:
                    break
                plant.command(q0 + direction * (k / s.press_steps))
                plant.advance(step)
                found = plant.tip_force(body)
            return found

        contact = self._timed(run)
        self._sync()
        if contact is None:
            return None
        point, normal, force = contact
        return Touch(finger, np.asarray(point), np.asarray(normal), float(force))

    # --- acting ---------------------------------------------------------------------------------
    def search_step(self) -> tuple[str, float, bool]:
        """One search sweep, planned on the model and executed in Drake leg by leg (a sweep's
        legs turn corners around the object: one straight motion from its start to its end
        would cut through it)."""
        self._motion = "search"
        speed = self._settings.free_speed
        return wrist_motion.search_step(self._world, lambda a, b: self._execute(a, b, speed))

    def guarded_wrist_move(self, target: np.ndarray, stop_when_located: bool = False) -> WristMove:
        """A guarded straight wrist move, planned on the model and executed in Drake."""
        self._motion = "wrist"
        q0 = self._world.state.q
        move = super().guarded_wrist_move(target, stop_when_located)
        self._execute(q0, self._world.state.q, self._settings.free_speed)
        return move

    def step_wrist_toward(self, target: np.ndarray, step: float) -> WristMove:
        """A guarded wrist step, planned on the model and executed in Drake."""
        self._motion = "wrist step"
        q0 = self._world.state.q
        move = super().step_wrist_toward(target, step)
        self._execute(q0, self._world.state.q, self._settings.approach_speed)
        return move

    def close_finger_step(self, finger: str, dtheta: float) -> FingerStep:
        """A closing step executed in Drake; a touch presses on to the touch force."""
        self._motion = "closing"
        world = self._world
        q0 = world.state.q
        step = super().close_finger_step(finger, dtheta)
        self._execute(q0, world.state.q, self._settings.approach_speed, self._settings.touch_force)
        if step.event != "touched":
            return step
        direction = np.zeros(len(q0))
        direction[world.context.finger_q[finger]] = 1.0
        touch = self._press(finger, direction * self._settings.finger_press_limit)
        return FingerStep(step.event, world.finger_angle(finger), touch or step.touch)

    def guarded_probe(
        self,
        finger: str,
        start: np.ndarray,
        direction: np.ndarray,
        travel: float,
        angle: float,
        yaw: float = 0.0,
    ) -> ProbeOutcome:
        """EP2's probe: placed (a transfer), advanced in Drake; a touch presses on."""
        self._motion = "probe"
        world = self._world
        outcome = super().guarded_probe(finger, start, direction, travel, angle, yaw)
        q_end = world.state.q
        unit = np.asarray(direction, dtype=float) / float(np.linalg.norm(direction))
        q_start = q_end.copy()
        q_start[world.wrist_xyz_q] -= outcome.travelled * unit
        self._execute(q_start, q_end, self._settings.approach_speed, self._settings.touch_force)
        if outcome.event == "touched":
            push = np.zeros(len(q_end))
            push[world.wrist_xyz_q] = unit * self._settings.press_limit
            self._press(finger, push)
        return outcome

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
        """EP1: the rolling QP's joint path, planned on the model, commanded to Drake's hand."""
        every = max(1, path_every)
        result = super().roll(
            finger, omega=omega, dt=dt, steps_per_direction=steps_per_direction, directions=directions,
            solver=solver, estimator=estimator, path_every=every,
        )  # fmt: skip
        self._motion = "roll"
        plant = self._plant
        path = [np.asarray(q) for q in result.path] or [result.q_final]
        self._transfer(path[0])

        def run() -> None:
            for a, b in itertools.pairwise(path):
                plant.command_moving(b, (b - a) / (every * dt))
                plant.advance(every * dt)
            plant.command(path[-1])
            plant.advance(self._settings.chunk)

        self._timed(run)
        # the model keeps the roll's planned end (its tip on the surface), not Drake's joint values:
        # a soft fingertip pressed on the object sinks into it past the contact tolerance
        self._sync(hand=False)
        return result

    def tactile(self, finger: str) -> TactileReading:
        """The reading of the model's sensor, with Drake's normal force."""
        reading = super().tactile(finger)
        found = self._plant.tip_force(self._plant.tip_bodies[finger])
        force = 0.0 if found is None else float(found[2])
        return TactileReading(reading.finger, reading.in_contact, reading.point, reading.normal,
                              reading.point_tip, force)  # fmt: skip

    # --- the referee ------------------------------------------------------------------------------
    def judge_grip(self, friction: float) -> dict[str, Any]:
        """The grip squeezed (a balanced squeeze, :mod:`eos_svc.drivers.balanced_squeeze`; where
        a fingertip does not touch, every finger joint 0.1 rad further after its light close), its
        contacts and quality where the object now is, then the lift test: good only if held."""
        moved = self._explored = self.object_moved()  # before the grip and the lift move it
        self._motion = "squeeze"
        world = self._world
        drake = dict(getattr(world.hand, "drake", {}))  # a described hand's [drake] table
        kp = float(drake.get("kp", self._plant.settings.finger_kp))
        # the balanced squeeze; where a fingertip does not touch, the uniform one (the
        # description's own: per joint unit, m for a prismatic finger)
        squeeze = float(drake.get("squeeze", SQUEEZE))
        target = self._timed(lambda: balanced.squeeze(self._plant, world.hand, kp))
        if target is None:
            target = self._timed(lambda: squeeze_grip(self._plant, world.hand, squeeze))
        self._sync()
        verdict = grasp_geometry(world, friction)
        verdict["object_moved_mm"] = round(1000.0 * moved, 3)
        if verdict["all_touching"]:
            radius = 0.5 * float(world.obj.diameter)
            lift = self._timed(lambda: lift_test(self._plant, world.hand, world.wrist_xyz_q, radius, target))
        else:
            lift = {"held": False, "why": "not every fingertip touches: nothing to lift"}
        self._lift = lift
        verdict["lift"] = lift
        verdict["good"] = bool(verdict["good"] and lift["held"])
        return verdict

    def report(self) -> dict[str, Any]:
        """The Drake world's figures for the plan result."""
        sim = self._plant.simulated_s  # the lift test's loads, each from the lifted state, included
        moved = self.object_moved() if self._explored is None else self._explored
        return {
            "name": "drake",
            "object_moved_mm": round(1000.0 * moved, 3),
            # past RELOCATE_AFTER the plan's reason says whether the relocate agent re-located it
            "moved_past_relocation_limit": bool(moved > RELOCATE_AFTER),
            "object_moved_max_mm": round(1000.0 * self._moved_max, 3),
            # the path length the object's centre moved during each kind of motion, mm
            "moved_by_mm": {k: round(1000.0 * v, 3) for k, v in sorted(self._moved_by.items())},
            "lift": self._lift,
            "transfers_unsimulated": self._transfers,
            "transfers_into_object": self._transfers_into,
            "simulated_s": round(sim, 4),
            "clock_s": round(self._plant.time(), 4),
            "simulation_wall_s": round(self._sim_wall, 4),
            "real_time_factor": round(sim / self._sim_wall, 3) if self._sim_wall > 0 else None,
        }
