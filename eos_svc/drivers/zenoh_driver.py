"""A hand driver over Zenoh: the hand (a robot's bridge, or a simulator in another process) is
served elsewhere (:mod:`eos_svc.drivers.zenoh_server`); this process never holds its object.

The hand's description is known here (the same URDF): its context (:class:`HandContext`) and a
kinematic model of the hand are local, so the joint state the server returns with every reply
gives the wrist, palm and finger poses without a round trip; proximity, touch and every motion
are calls. Key expressions and payloads: :mod:`eos_svc.drivers.zenoh_wire`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import zenoh

from eos_svc.drivers.protocol import FingerStep, JointState, TactileReading, WristMove
from eos_svc.drivers.zenoh_wire import call_key, decode, encode, open_key
from eos_svc.errors import EosError, ValidationError
from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.kinematics import HandModel
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.ep1 import EP1Result
from eos_svc.kinematics.errors import KinematicsError
from eos_svc.schema.request import PlanRequest
from eos_svc.world.hand_context import HandContext, context_for
from eos_svc.world.parameters import WorldParameters
from eos_svc.world.probing import ProbeChoice, ProbeOutcome


class HandUnavailableError(EosError, RuntimeError):
    """The served hand did not answer (no server, or it timed out)."""


class ZenohDriver:
    """The :class:`~eos_svc.drivers.protocol.HandDriver` of a hand served over Zenoh.

    Args:
        session: an open Zenoh session that reaches the server.
        name: the served hand's name.
        request: the plan's request (the server builds its world from it; its seed seeds this
            side's generator).
        timeout: seconds to wait for one reply.
        context: the hand's context (default: hand3x3's).
    """

    def __init__(self, session: zenoh.Session, name: str, request: PlanRequest, *,
                 timeout: float = 60.0, context: HandContext | None = None) -> None:  # fmt: skip
        self._session = session
        self._name = name
        self._timeout = timeout
        self._context = context if context is not None else context_for(None)
        self._rng = np.random.default_rng(np.random.SeedSequence(request.seed, spawn_key=(0,)))
        self._state = self._context.hand.state()
        opened = self._query(open_key(name), {"request": request.to_dict(), "world": request.world})
        self._noise = float(opened["tactile_noise"])
        self._state.update(np.asarray(opened["q"]))

    # --- the wire ------------------------------------------------------------------------------
    def _query(self, key: str, payload: dict[str, Any]) -> dict[str, Any]:
        replies = self._session.get(key, payload=json.dumps(payload), timeout=self._timeout)
        for reply in replies:
            if reply.ok is not None:
                out: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
                return out
            error = json.loads(reply.err.payload.to_bytes())
            if error.get("type") == "validation":
                raise KinematicsError(error["field"], error["reason"])
            raise HandUnavailableError(f"the hand {self._name!r} refused {key}: {error['error']}")
        raise HandUnavailableError(f"no reply from the hand {self._name!r} on {key} within {self._timeout} s")

    def _call(self, method: str, **args: Any) -> Any:
        reply = self._query(
            call_key(self._name), {"method": method, "args": {k: encode(v) for k, v in args.items()}}
        )
        self._state.update(np.asarray(reply["q"]))
        return reply["result"]

    # --- what the hand is --------------------------------------------------------------------------
    @property
    def context(self) -> HandContext:
        """The hand's context (local)."""
        return self._context

    @property
    def hand(self) -> HandModel:
        """The hand model (local)."""
        return self._context.hand

    @property
    def params(self) -> WorldParameters:
        """The planner's constants."""
        return self._context.params

    @property
    def sweeps(self) -> dict[str, FingerSweep]:
        """The closing sweeps."""
        return self._context.sweeps

    @property
    def probe(self) -> ProbeChoice:
        """The probing fingers."""
        return self._context.probe

    @property
    def rng(self) -> np.random.Generator:
        """This side's seeded generator."""
        return self._rng

    @property
    def tactile_noise(self) -> float:
        """The served sensor's noise, m."""
        return self._noise

    @property
    def table_height(self) -> float | None:
        """The served world's table height (m), ``None`` without one."""
        value = self._call("table_height")
        return None if value is None else float(value)

    @property
    def support_height(self) -> float | None:
        """The surface the served object rests on (m), ``None`` without one."""
        value = self._call("support_height")
        return None if value is None else float(value)

    @property
    def object_fixed(self) -> bool:
        """Whether the served world holds its object fixed."""
        return bool(self._call("object_fixed"))

    @property
    def kinematic_sigma(self) -> float:
        """The served hand's fingertip position uncertainty, m."""
        return float(self._call("kinematic_sigma"))

    @property
    def probes(self) -> int:
        """Guarded probes the served world has run."""
        return int(self._call("probes"))

    def probe_finger(self, face: str) -> str:
        """The finger that explores ``face`` in the served world."""
        return str(self._call("probe_finger", face=face))

    # --- joint state (local kinematics of the last joint values) ----------------------------------
    def joint_state(self) -> JointState:
        """The last joint values and the served clock."""
        return JointState(tuple(self.q_list()), self.clock())

    def joint_positions(self) -> np.ndarray:
        """The last joint values (a copy)."""
        return self._state.q

    def q_list(self) -> list[float]:
        """The last joint values as floats."""
        out: list[float] = self._state.q.tolist()
        return out

    def clock(self) -> float:
        """The served clock, s."""
        return float(self._call("clock"))

    def wrist_position(self) -> np.ndarray:
        """The wrist's position, m."""
        return self._state.q[self._context.hand.wrist_q_index[:3]]

    def wrist_xyz(self) -> tuple[float, float, float]:
        """The wrist's position as floats, m."""
        x, y, z = self.wrist_position().tolist()
        return x, y, z

    def palm_views(self) -> tuple[np.ndarray, np.ndarray]:
        """The palm frame's translation and rotation."""
        return self._state.frame_views(self._context.hand.palm_frame_id)

    def grasp_centre_world(self) -> np.ndarray:
        """The grasp centre, m."""
        translation, rotation = self.palm_views()
        out: np.ndarray = translation + rotation @ np.asarray(self._context.params.grasp_centre)
        return out

    def finger_angle(self, finger: str) -> float:
        """The finger's joint angle, rad."""
        return float(self._state.q[self._context.angle_q[finger]])

    # --- proximity and touch ---------------------------------------------------------------------
    def object_gap_to_grasp_centre(self) -> float:
        """Grasp centre to object surface, m."""
        return float(self._call("object_gap_to_grasp_centre"))

    def located(self) -> bool:
        """The object is in the envelope."""
        return bool(self._call("located"))

    def nearest_surface_point(self, point: np.ndarray) -> np.ndarray:
        """The object's surface point nearest ``point``, m."""
        return np.asarray(self._call("nearest_surface_point", point=point))

    def hand_clear(self, threshold: float) -> bool:
        """The hand at least ``threshold`` m from the object."""
        return bool(self._call("hand_clear", threshold=threshold))

    def touching(self, finger: str) -> bool:
        """Whether the tip touches."""
        return bool(self._call("touching", finger=finger))

    def tactile(self, finger: str) -> TactileReading:
        """The tactile reading."""
        out: TactileReading = decode(self._call("tactile", finger=finger))
        return out

    # --- acting ----------------------------------------------------------------------------------
    def move_joints(self, q: np.ndarray) -> None:
        """Place the hand at ``q``."""
        self._call("move_joints", q=q)

    def search_step(self) -> tuple[str, float, bool]:
        """One search sweep (the served side's coverage order)."""
        label, moved, blocked = self._call("search_step")
        return str(label), float(moved), bool(blocked)

    def guarded_wrist_move(self, target: np.ndarray, stop_when_located: bool = False) -> WristMove:
        """A guarded straight wrist move."""
        out: WristMove = decode(
            self._call("guarded_wrist_move", target=target, stop_when_located=stop_when_located)
        )
        return out

    def step_wrist_toward(self, target: np.ndarray, step: float) -> WristMove:
        """A guarded wrist step."""
        out: WristMove = decode(self._call("step_wrist_toward", target=target, step=step))
        return out

    def close_finger_step(self, finger: str, dtheta: float) -> FingerStep:
        """A guarded closing step."""
        out: FingerStep = decode(self._call("close_finger_step", finger=finger, dtheta=dtheta))
        return out

    def guarded_probe(
        self,
        finger: str,
        start: np.ndarray,
        direction: np.ndarray,
        travel: float,
        angle: float,
        yaw: float = 0.0,
    ) -> ProbeOutcome:
        """EP2's guarded probe."""
        args = {"finger": finger, "start": start, "direction": direction, "travel": travel, "angle": angle}
        if yaw != 0.0:  # the wire form of an unturned probe is unchanged
            args["yaw"] = yaw
        out: ProbeOutcome = decode(self._call("guarded_probe", **args))
        return out

    def place_tip_on(self, finger: str, q: np.ndarray, point: np.ndarray) -> None:
        """EP1's start."""
        self._call("place_tip_on", finger=finger, q=q, point=point)

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
        """EP1 served; its samples join ``estimator`` here."""
        args = {"finger": finger, "omega": omega, "dt": dt, "steps_per_direction": steps_per_direction,
                "directions": list(directions), "solver": solver, "path_every": path_every}  # fmt: skip
        out = self._call("roll", **args)
        samples = tuple(
            estimator.add_sample(s["omega_xy"], s["u"], np.reshape(s["K_f"], (2, 2))) for s in out["samples"]
        )
        return EP1Result(
            estimate=estimator.estimate(),
            q_final=np.asarray(out["q_final"]),
            steps=int(out["steps"]),
            samples=samples,
            max_slip_speed=float(out["max_slip_speed"]),
            max_gap=float(out["max_gap"]),
            frame=np.asarray(out["frame"]).reshape(3, 3),
            contact_point=np.asarray(out["contact_point"]),
            normal=np.asarray(out["normal"]),
            path=tuple(np.asarray(q) for q in out["path"]),
        )

    # --- the referee -----------------------------------------------------------------------------
    def judge_grip(self, friction: float) -> dict[str, Any]:
        """The served world's verdict."""
        out: dict[str, Any] = self._call("judge_grip", friction=friction)
        return out

    def report(self) -> dict[str, Any] | None:
        """The served world's figures."""
        out: dict[str, Any] | None = self._call("report")
        return out


__all__ = ["HandUnavailableError", "ValidationError", "ZenohDriver"]
