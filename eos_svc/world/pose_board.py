"""The planner's information board: the core :class:`~eos_svc.board.Board` plus the hand's pose,
written after every cycle that moved it (``keys.HAND_Q``: every joint in m and rad, rounded to
1e-7), so a recording or a watcher can draw the hand cycle by cycle. No agent reads it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from eos_svc.board import Board, BoardChange
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys

#: decimals kept of every joint value in ``keys.HAND_Q`` (0.1 µm, 0.1 µrad)
Q_DECIMALS = 7


def hand_q(world: HandDriver) -> tuple[float, ...]:
    """The hand's configuration as written on the board (rounded to :data:`Q_DECIMALS`)."""
    return tuple(world.joint_positions().round(Q_DECIMALS).tolist())


class PoseBoard(Board):
    """A board that records the hand's configuration after every cycle that moved it, and the
    object's pose (``keys.OBJECT_POSE``, read by ``object_pose()``: x, y, z, qw, qx, qy, qz) in a
    world whose object moves (the Drake world's); ``entries``: set up, not recorded as changes.
    """

    __slots__ = ("_object_pose", "_world")

    def __init__(
        self,
        world: HandDriver,
        entries: Mapping[str, Any] | None = None,
        object_pose: Callable[[], list[float]] | None = None,
    ) -> None:
        initial = {**(entries or {}), keys.HAND_Q: hand_q(world)}
        if object_pose is not None:
            initial[keys.OBJECT_POSE] = object_pose()
        super().__init__(initial)
        self._world = world
        self._object_pose = object_pose

    def end_cycle(self) -> tuple[BoardChange, ...]:
        """Write ``keys.HAND_Q`` (a change only when the hand moved) and the object's pose (when
        it moved), then end the cycle."""
        if self._changes is not None:
            self.set(keys.HAND_Q, hand_q(self._world))
            if self._object_pose is not None:
                self.set(keys.OBJECT_POSE, self._object_pose())
        return super().end_cycle()


#: board entries only viewers read: the hand's configuration, EP1's sampled path, a moving object's pose
VIEW_KEYS = frozenset({keys.HAND_Q, keys.HAND_PATH, keys.OBJECT_POSE})


def has_hand_q(cycles: Sequence[Mapping[str, Any]]) -> bool:
    """Whether any cycle record (JSON form) writes the hand's configuration — false for a
    recording made before ``hand_q`` existed."""
    return any(
        isinstance(c, Mapping) and c.get("key") == keys.HAND_Q
        for record in cycles
        for c in record.get("changes") or ()
    )


def view_entries_as_recorded(
    recorded: Sequence[Mapping[str, Any]], replayed: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    """``replayed`` cycle records (JSON form) as comparable with ``recorded``: unchanged when
    the recording has the view entries (:data:`VIEW_KEYS`), else without them (a recording
    made before they existed)."""
    if has_hand_q(recorded) or not has_hand_q(replayed):
        return replayed
    return [{**c, "changes": [ch for ch in c["changes"] if ch.get("key") not in VIEW_KEYS]} for c in replayed]
