"""Names of the information-board entries the grasp agents share (their types:
:mod:`eos_svc.schema.board_entries`)."""

from __future__ import annotations

LOCATED = "located"  #: bool: the object is within the hand's envelope
GAP = "gap_to_object"  #: float m: object surface to the grasp centre
SEARCH_MOVES = "search_moves"  #: int: search moves (sweeps) made
CURVATURE = "curvature"  #: dict: EP1's curvature estimate on the object's top (curvatures, σ, rating)
CURVATURE_BOTTOM = "curvature_bottom"  #: dict: the same on the object's bottom, when explored
EP1_RUNS = "ep1_runs"  #: int: EP1 runs so far
EP1_CONTACT = "ep1_contact"  #: dict side -> {finger, point, normal}: sensed EP1 contact (world)
EP2_TOUCHES = "ep2_touches"  #: list of {face, finger, centre, normal, radius}: EP2's contacts (world, m)
EP2_FREE = "ep2_free"  #: list of [x, y, z, tip radius]: tip-centre samples of EP2 probes that touched nothing
EP2_RUNS = "ep2_runs"  #: int: EP2 rounds over the whole surface so far (active-touch rounds not counted)
APPROACH = "approach"  #: dict: proximity point of the object nearest the hand and the direction to it
SHAPE = "shape"  #: dict: post_shape's postulate (class, confidence, object, evidence, centre, size)
TARGET = "grasp_target"  #: dict: grasp_points' target (wrist goal, pre-grasp, predicted contacts)
D_OVER_H = "d_over_h"  #: float: estimated object diameter over hand height
AT_TARGET = "wrist_at_target"  #: bool: the wrist reached its grasp position
WRIST_LEFT = "wrist_distance_left"  #: float m: distance left to the wrist's grasp position
FINGER_STATE = "finger_state"  #: dict finger -> "open" | "closing" | "touching" | "missed" | "link"
FINGER_ANGLE = "finger_angle"  #: dict finger -> joint angle (rad)
OUTCOME = "grasp_outcome"  #: dict: the end agent's verdict
FRICTION = "friction"  #: float: Coulomb μ of the fingertip contacts (from the request; read by end)
HAND_Q = "hand_q"  #: tuple: the hand's configuration after the cycle (rad/m, 1e-7; written by PoseBoard)
RECALLED = "recalled"  #: str: the grasp-memory key recall applied
OBJECT_POSE = "object_pose"  #: list: the object's pose after the cycle, Drake world (by PoseBoard)
HAND_PATH = "hand_path"  #: list of q: the hand's path during an EP1 roll (sampled; for viewers)
