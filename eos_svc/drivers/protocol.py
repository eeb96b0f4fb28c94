"""The hand driver: the only way the grasp agents sense and act.

A grasp planner that explores by touch is only useful on a hand it can drive. The agents
(:mod:`eos_svc.agents`), post_shape and grasp synthesis (:mod:`eos_svc.grasp`) never hold the
true object: they talk to a :class:`HandDriver`, as a controller talks to a robot through
ros2_control's hardware interfaces. What owns the object — the kinematic world
(:mod:`eos_svc.drivers.kinematic`), a Drake simulation (:mod:`eos_svc.drivers.drake_world`) —
sits behind it, and the planner that builds the world hands the agents only its driver.

What a driver offers, in SI units (m, rad, s, N), world frame z up:

- **joint state and clock**: :meth:`HandDriver.joint_state` (the configuration and the
  driver's time), :meth:`HandDriver.clock`;
- **proximity** (what a wrist camera or a proximity sensor gives): the distance from the
  grasp centre to the object's surface, the surface point nearest a point, whether the hand
  is clear of the object by a margin, whether a fingertip touches;
- **the wrist's guarded motions**: a straight move that stops where the object enters the
  hand's envelope or short of a contact (:class:`WristMove`), a step toward a target that
  stops short of touching, a search sweep;
- **a finger's guarded closing step**: stops at first touch and reports the contact point,
  normal and force (:class:`FingerStep`, :class:`Touch`);
- **EP2's guarded probe** and **EP1's roll** (the rolling QP's joint-velocity commands, each
  step with its tactile reading), and the **tactile reading** of a fingertip now
  (:class:`TactileReading`);
- **the referee**: :meth:`HandDriver.judge_grip`, the world's own verdict of the grip it
  holds (contacts and quality on the true object; the Drake world adds its lift test). The
  agents get the verdict, never the object.

A driver also carries the hand's context (the hand model and what is derived from it) and the
plan's seeded random generator, so the same request and seed give the same cycles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from eos_svc.grasp.sweeps import FingerSweep
    from eos_svc.kinematics import HandModel
    from eos_svc.kinematics.curvature import CurvatureEstimator
    from eos_svc.kinematics.ep1 import EP1Result
    from eos_svc.world.hand_context import HandContext
    from eos_svc.world.parameters import WorldParameters
    from eos_svc.world.probing import ProbeChoice, ProbeOutcome

#: an object found farther than this from where it was postulated (a check touch off the predicted
#: surface; the Drake world's object off where it rested) has moved and is re-located, m
RELOCATE_AFTER = 0.002


@dataclass(frozen=True)
class Touch:
    """A fingertip's contact with the object.

    Attributes:
        finger: the touching finger.
        point: the contact point on the object's surface (world, m).
        normal: the object's outward unit normal there (world; from the object toward the tip).
        force: the normal contact force, N (0 in the kinematic world: the hand stops at first
            touch and the object cannot move).
    """

    finger: str
    point: np.ndarray
    normal: np.ndarray
    force: float


@dataclass(frozen=True)
class TactileReading:
    """A fingertip sensor's reading (with the sensor's noise).

    Attributes:
        finger: the finger.
        in_contact: whether the tip touches the object.
        point: the sensed contact point (world, m).
        normal: the sensed outward object normal (world, unit).
        point_tip: the sensed contact point in the fingertip frame, m.
        force: the normal contact force, N (0 in the kinematic world).
    """

    finger: str
    in_contact: bool
    point: np.ndarray
    normal: np.ndarray
    point_tip: np.ndarray
    force: float


@dataclass(frozen=True)
class WristMove:
    """What a guarded wrist motion did.

    Attributes:
        moved: the length moved, m.
        blocked: the motion stopped short of a contact.
        left: the distance left to the target, m.
        contact_point: when blocked, the object's surface point nearest the hand (world, m).
    """

    moved: float
    blocked: bool
    left: float = 0.0
    contact_point: np.ndarray | None = None


@dataclass(frozen=True)
class FingerStep:
    """What a guarded finger closing step did.

    Attributes:
        event: ``"moved"``, ``"touched"`` (the tip reached the object), ``"link"`` (another
            part of the finger touched first) or ``"limit"`` (the joint limit, no touch).
        angle: the finger's (first) joint angle after the step, rad.
        touch: when touched, the contact.
    """

    event: str
    angle: float
    touch: Touch | None = None


@dataclass(frozen=True)
class JointState:
    """The hand's configuration at a time.

    Attributes:
        q: every joint in the hand model's order (wrist x, y, z in m, roll, pitch, yaw in rad,
            then the finger joints in rad).
        time: the driver's clock, s.
    """

    q: tuple[float, ...]
    time: float


class HandDriver(Protocol):
    """The agents' hand: sensing and guarded motions (see the module docstring)."""

    # --- what the hand is, and the plan's randomness ----------------------------------------
    @property
    def context(self) -> HandContext:
        """The hand's context: the model and what is derived from it once."""
        ...

    @property
    def hand(self) -> HandModel:
        """The hand model."""
        ...

    @property
    def table_height(self) -> float | None:
        """The height of the table the object rests on (m), ``None`` without one."""
        ...

    @property
    def support_height(self) -> float | None:
        """The height of the surface the object rests on (m), ``None`` when it rests on none: the
        table's, or in a world whose hand may pass through its support (the Drake world's) that
        support's. Its bottom need not be felt (it is that plane) and is never probed from under."""
        ...

    @property
    def object_fixed(self) -> bool:
        """Whether the object is held fixed (the kinematic world's): no touch can move it, so
        the planner never checks where it is before the grasp (:mod:`eos_svc.agents.relocate`)."""
        ...

    @property
    def kinematic_sigma(self) -> float:
        """The joint sensing's fingertip position uncertainty (m; 0 for exact kinematics)."""
        ...

    @property
    def probes(self) -> int:
        """Guarded probes run so far (EP2's straight moves, touched or not)."""
        ...

    def probe_finger(self, face: str) -> str:
        """The finger that explores ``face`` ("top", "bottom", "front" or "side")."""
        ...

    @property
    def params(self) -> WorldParameters:
        """The planner's constants for this hand."""
        ...

    @property
    def sweeps(self) -> dict[str, FingerSweep]:
        """Each finger's closing sweep (palm frame)."""
        ...

    @property
    def probe(self) -> ProbeChoice:
        """Which finger explores the object's top and bottom, and at which angle."""
        ...

    @property
    def rng(self) -> np.random.Generator:
        """The plan's seeded random generator (the search's order, EP2's choices)."""
        ...

    @property
    def tactile_noise(self) -> float:
        """The tactile sensor's noise (standard deviation of a contact point, m)."""
        ...

    # --- joint state and clock ----------------------------------------------------------------
    def joint_state(self) -> JointState:
        """The hand's configuration and the driver's time."""
        ...

    def joint_positions(self) -> np.ndarray:
        """The configuration as an array (a copy)."""
        ...

    def q_list(self) -> list[float]:
        """The configuration as a list of floats (do not modify)."""
        ...

    def clock(self) -> float:
        """The driver's time, s (simulated time in a simulator)."""
        ...

    def wrist_position(self) -> np.ndarray:
        """The wrist's (palm origin's) world position, m."""
        ...

    def wrist_xyz(self) -> tuple[float, float, float]:
        """:meth:`wrist_position` as floats."""
        ...

    def palm_views(self) -> tuple[np.ndarray, np.ndarray]:
        """The palm frame's world translation (m) and rotation (do not modify)."""
        ...

    def grasp_centre_world(self) -> np.ndarray:
        """The grasp centre between the fingers, world, m."""
        ...

    def finger_angle(self, finger: str) -> float:
        """The finger's (first) joint angle, rad."""
        ...

    # --- proximity and touch --------------------------------------------------------------------
    def object_gap_to_grasp_centre(self) -> float:
        """Distance from the grasp centre to the object's surface, m (negative inside)."""
        ...

    def located(self) -> bool:
        """The object is within the hand's envelope."""
        ...

    def nearest_surface_point(self, point: np.ndarray) -> np.ndarray:
        """The object's surface point nearest ``point`` (world, m)."""
        ...

    def hand_clear(self, threshold: float) -> bool:
        """Every hand geometry is at least ``threshold`` m from the object."""
        ...

    def touching(self, finger: str) -> bool:
        """Whether ``finger``'s tip touches the object."""
        ...

    def tactile(self, finger: str) -> TactileReading:
        """``finger``'s tactile reading now."""
        ...

    # --- acting ----------------------------------------------------------------------------------
    def move_joints(self, q: np.ndarray) -> None:
        """Bring the hand to ``q`` (free-space placement: the caller checks :meth:`hand_clear`)."""
        ...

    def search_step(self) -> tuple[str, float, bool]:
        """One sweep of the search's coverage lattice: (column label, length moved m, blocked)."""
        ...

    def guarded_wrist_move(self, target: np.ndarray, stop_when_located: bool = False) -> WristMove:
        """A straight wrist move toward ``target`` (world, m), stopping short of a contact."""
        ...

    def step_wrist_toward(self, target: np.ndarray, step: float) -> WristMove:
        """Move the wrist up to ``step`` m toward ``target``, stopping short of touching."""
        ...

    def close_finger_step(self, finger: str, dtheta: float) -> FingerStep:
        """Close ``finger`` by ``dtheta`` rad per joint, stopping at first touch."""
        ...

    def guarded_probe(
        self,
        finger: str,
        start: np.ndarray,
        direction: np.ndarray,
        travel: float,
        angle: float,
        yaw: float = 0.0,
    ) -> ProbeOutcome:
        """EP2's guarded straight move of a fingertip from ``start`` along ``direction``, the
        wrist turned by ``yaw`` (rad) about the vertical."""
        ...

    def place_tip_on(self, finger: str, q: np.ndarray, point: np.ndarray) -> None:
        """From ``q`` (the fingers set), move the wrist so ``finger``'s tip touches the object at
        the surface point nearest ``point`` (EP1's start)."""
        ...

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
        """EP1: roll ``finger``'s tip on the object without sliding (the rolling QP's
        joint-velocity commands, a tactile reading each step) and estimate the curvature; the
        arguments (units, ranges) are :func:`~eos_svc.kinematics.ep1.run_ep1`'s."""
        ...

    # --- the referee -------------------------------------------------------------------------------
    def judge_grip(self, friction: float) -> dict[str, Any]:
        """The world's verdict of the grip it holds: contacts per finger, the good-grasp test
        and quality on the true object (:func:`eos_svc.drivers.grip_verdict.grasp_geometry`)."""
        ...
