"""The simulated hand and its world, as the grasp agents see and move it.

:class:`GraspWorld` holds the hand's context, the scene (coal), the hand's state (Pinocchio),
the tactile sensor and the run's generator; it answers the agents' questions and runs their
guarded motions (:mod:`~eos_svc.world.wrist_motion`, :mod:`~eos_svc.world.probe_motion`,
:mod:`~eos_svc.world.finger_closing`). Conventions: world z up; the palm's x axis is the
approach, its z axis the closing direction. SI units. Gaps are exact coal distances, queried
only where the lower bounds of :mod:`eos_svc.kinematics.gap_bounds` cannot decide.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.kinematics import HandModel, HandState, Scene, TactileSensor
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.gap_bounds import ball_gap_lower_bounds
from eos_svc.objects import SurfaceObject
from eos_svc.world.hand_context import HandContext
from eos_svc.world.joint_sensing import JointSensing
from eos_svc.world.parameters import WorldParameters
from eos_svc.world.probing import ProbeChoice
from eos_svc.world.table import hand_table_gap, table_shape


@dataclass
class GraspWorld:
    """The hand, the object and the run's randomness; guarded motions for the agents. ``hand``,
    ``params``, ``sweeps`` and ``probe`` are the context's, ``obj`` the scene's object; ``memo``
    keeps what is derived from the current hand pose until the next move."""

    context: HandContext
    scene: Scene
    state: HandState
    sensor: TactileSensor
    rng: np.random.Generator
    estimator: CurvatureEstimator = field(default_factory=CurvatureEstimator)
    sensing: JointSensing | None = None  # the joint encoders' and links' errors (None: exact)
    #: the support surface's height (world z, m) the object rests on, or None (no table)
    table_height: float | None = None

    def __post_init__(self) -> None:
        self.hand: HandModel = self.context.hand
        self.params: WorldParameters = self.context.params
        self.sweeps: dict[str, FingerSweep] = self.context.sweeps
        self.probe: ProbeChoice = self.context.probe
        self.obj: SurfaceObject = self.scene.object
        # where the hand reports its fingertips (EP1's and EP2's contacts come from it)
        self.encoders: JointSensing = self.sensing if self.sensing is not None else JointSensing(self.hand)
        self.wrist_xyz_q = self.hand.wrist_q_index[:3]  # the wrist's x, y, z joints' q indices
        self.grasp_centre_palm = np.asarray(self.params.grasp_centre, dtype=float)
        self.version = 0  # bumped on every move
        self.probes = 0  # guarded probes run so far (EP2's straight moves, touched or not)
        self.memo: dict[object, Any] = {}
        # the object's bounding ball (centre, m; radius, m) for the gaps' lower bounds: the
        # object is fixed for a world's lifetime (a plan never moves it)
        self.obj_centre = tuple(float(x) for x in self.scene.object.placement.translation)
        self.obj_radius = 0.5 * float(self.scene.object.diameter)
        # the search's columns left, in order, drawn from rng at the first search move (search_step)
        self.search_order: list[tuple[int, int]] = []
        self.search_columns = np.empty((0, 0, 2))
        self.table = None if self.table_height is None else table_shape(self.table_height)

    # --- reading the world -------------------------------------------------------------
    def wrist_position(self) -> np.ndarray:
        """World position of the wrist (= palm origin), m."""
        return self.state.q[self.wrist_xyz_q]

    def grasp_centre_world(self) -> np.ndarray:
        """World position of the grasp centre between the fingers, m."""
        translation, rotation = self.palm_views()  # the wrist may be turned
        out: np.ndarray = translation + rotation @ self.grasp_centre_palm
        return out

    def palm_views(self) -> tuple[np.ndarray, np.ndarray]:
        """Live views of the palm frame's world translation (m) and rotation in the current
        state (do not modify them; copy what must outlive a move)."""
        return self.state.frame_views(self.hand.palm_frame_id)

    def object_gap_to_grasp_centre(self) -> float:
        """Distance from the grasp centre to the object surface, m (negative inside)."""
        value = self.memo.get("gap")
        if value is None:
            value = self.memo["gap"] = self.scene.point_gap(self.grasp_centre_world())
        return value

    def located(self) -> bool:
        """The object is in the hand's envelope (see :class:`WorldParameters`)."""
        return self.object_gap_to_grasp_centre() <= self.params.envelope_radius

    def tip_distance(self, finger: str) -> float:
        """Signed fingertip–object distance, m."""
        value = self.memo.get(finger)
        if value is None:
            value = self.memo[finger] = float(self.scene.contact(self.state, finger).distance)
        return value

    def touching(self, finger: str) -> bool:
        """Whether ``finger``'s tip touches the object."""
        return self.tip_distance(finger) <= self.params.contact_tolerance

    def finger_angle(self, finger: str) -> float:
        """The finger's (common) joint angle, rad (its first joint)."""
        return self.q_list()[self.context.angle_q[finger]]

    def q_list(self) -> list[float]:
        """The hand's configuration as a list of floats (do not modify)."""
        value = self.memo.get("q")
        if value is None:
            value = self.memo["q"] = self.state.q.tolist()
        return value

    def wrist_xyz(self) -> tuple[float, float, float]:
        """:meth:`wrist_position` as a tuple of floats."""
        x, y, z = self.wrist_position().tolist()
        return x, y, z

    # --- clearance -----------------------------------------------------------------------
    def hand_clearance(self) -> float:
        """Smallest distance between any hand geometry and the object, m; beyond ``hand_bound``
        of the grasp centre its lower bound (gap − hand_bound), without a collision query."""
        value = self.memo.get("clearance")
        if value is None:
            gap = self.object_gap_to_grasp_centre()
            if gap > self.params.hand_bound + self.params.clearance:
                value = gap - self.params.hand_bound
            else:
                value = self.min_gap(range(len(self.context.bounds)), math.inf)
            self.memo["clearance"] = value
        return value

    def probe_finger(self, face: str) -> str:
        """The finger that explores ``face`` ("top", "bottom", "front" or "side"): :attr:`probe`'s
        choice, except on a table, where every probe is the opposing finger's (the hand's lowest)."""
        if self.table is not None or face == "bottom":
            return self.probe.bottom
        return self.probe.top

    def table_gap(self) -> float:
        """The hand's least distance to the table (m; :mod:`eos_svc.world.table`), ``inf`` without one."""
        if self.table is None:
            return math.inf
        value = self.memo.get("table_gap")
        if value is None:
            value = self.memo["table_gap"] = hand_table_gap(self.state, self.table)
        return value

    def hand_clear(self, threshold: float) -> bool:
        """Whether :meth:`hand_clearance` is at least ``threshold`` (m)."""
        return self.hand_clearance() >= threshold

    def exact_clearance(self) -> float:
        """:meth:`hand_clearance`, exact whenever the object is within 5 mm of the hand's
        bound (the plain lower bound ``gap − hand_bound`` beyond that), m."""
        gap = self.object_gap_to_grasp_centre()
        if gap - self.params.hand_bound > self.params.clearance + 5e-3:
            return gap - self.params.hand_bound
        value = self.memo.get("exact_clearance")
        if value is None:
            value = self.memo["exact_clearance"] = self.min_gap(range(len(self.context.bounds)), math.inf)
        return value

    def min_gap(self, geometry_ids: Iterable[int], best: float) -> float:
        """min(best, exact gap of every geometry in ``geometry_ids``) (m), skipping the query of a
        geometry whose lower bound already reaches the minimum."""
        for lower, gid in sorted(self.lower_bounds(geometry_ids)):
            if lower >= best:
                break
            best = min(best, self.scene.gap(self.state, gid))
        return best

    def lower_bounds(self, geometry_ids: Iterable[int]) -> list[tuple[float, int]]:
        """``(lower bound of the gap, id)`` of every geometry in ``geometry_ids`` to the
        object's bounding ball (m)."""
        state = self.state
        state.geometry_data  # noqa: B018 -- brings the placements (and the views below) up to date
        views = state.geometry_views()  # live views of every geometry's placement
        return ball_gap_lower_bounds(
            self.context.bounds, views, geometry_ids, self.obj_centre, self.obj_radius
        )

    # --- moving it -------------------------------------------------------------------------
    def set_q(self, q: np.ndarray) -> None:
        """Move the hand to ``q`` (validated by the hand model)."""
        self.state.update(q)
        self.sync()

    def sync(self) -> None:
        """Forget memoised values after ``state`` was moved directly (prefer :meth:`direct_motion`)."""
        self.version += 1
        self.memo.clear()

    @contextlib.contextmanager
    def direct_motion(self) -> Iterator[HandState]:
        """``with world.direct_motion() as state:`` — move ``state`` directly inside (EP1's rolling
        QP); on leaving, even by an exception, the world forgets what it memoised."""
        try:
            yield self.state
        finally:
            self.sync()
