"""Serve a hand over Zenoh: another process drives it
(:class:`~eos_svc.drivers.zenoh_driver.ZenohDriver`).

    python -m eos_svc.drivers.zenoh_server --name sim1 --listen tcp/127.0.0.1:7448

The serving process owns the world (the kinematic world or the Drake world, chosen by each
``open``) and so the object; the planner's process never sees it. Key expressions and payloads:
:mod:`eos_svc.drivers.zenoh_wire`. Queries are taken from a channel and answered one at a time
in the serving thread (no Zenoh call inside a Zenoh callback); every query ends in exactly one
``reply`` or ``reply_err``.
"""

from __future__ import annotations

import argparse
import json
import threading
from typing import Any

import numpy as np
import zenoh

from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.drivers.worlds import make_driver
from eos_svc.drivers.zenoh_wire import call_key, encode, encode_samples, open_key
from eos_svc.errors import EosError, ValidationError
from eos_svc.kinematics.curvature import CurvatureEstimator
from eos_svc.kinematics.rolling import RollingQPError
from eos_svc.schema.request import PlanRequest
from eos_svc.service.session import make_config

#: the protocol's methods a client may call, with the arguments that cross as arrays
#: the protocol's properties served as calls without arguments
PROPERTIES = frozenset({"table_height", "support_height", "object_fixed", "kinematic_sigma", "probes"})
#: the protocol's methods served, each with its array-valued arguments
METHODS: dict[str, tuple[str, ...]] = {
    "clock": (),
    "probe_finger": (),
    "table_height": (),  # the next five are the driver's properties, read rather than called
    "support_height": (),
    "object_fixed": (),
    "kinematic_sigma": (),
    "probes": (),
    "object_gap_to_grasp_centre": (),
    "located": (),
    "nearest_surface_point": ("point",),
    "hand_clear": (),
    "touching": (),
    "tactile": (),
    "move_joints": ("q",),
    "search_step": (),
    "guarded_wrist_move": ("target",),
    "step_wrist_toward": ("target",),
    "close_finger_step": (),
    "guarded_probe": ("start", "direction"),
    "place_tip_on": ("q", "point"),
    "roll": (),
    "judge_grip": (),
    "report": (),
}


class HandServer:
    """The world behind one served hand name (see the module docstring)."""

    def __init__(self, session: zenoh.Session, name: str) -> None:
        self.session = session
        self.name = name
        self.driver: KinematicDriver | None = None

    def open(self, payload: dict[str, Any]) -> dict[str, Any]:
        """A new world for the request in ``payload``."""
        from eos_svc.agents.planner import build_world

        request = PlanRequest.from_dict(payload.get("request", {}))
        world = payload.get("world", request.world)
        self.driver = make_driver(world, build_world(request), request)
        return {"q": encode(self.driver.joint_positions()), "tactile_noise": self.driver.tactile_noise}

    def call(self, payload: dict[str, Any]) -> dict[str, Any]:
        """One protocol call on the open world."""
        if self.driver is None:
            raise ValidationError("open", "no world is open: send an open query first")
        method = payload.get("method")
        if method not in METHODS:
            raise ValidationError("method", f"unknown method {method!r}")
        args = dict(payload.get("args", {}))
        for name in METHODS[method]:
            args[name] = np.asarray(args[name], dtype=float)
        driver = self.driver
        if method == "roll":
            result = driver.roll(**args, estimator=CurvatureEstimator())
            out: Any = {
                "samples": encode_samples(result.samples),
                "q_final": encode(result.q_final),
                "steps": result.steps,
                "max_slip_speed": float(result.max_slip_speed),
                "max_gap": float(result.max_gap),
                "frame": encode(result.frame),
                "contact_point": encode(result.contact_point),
                "normal": encode(result.normal),
                "path": [encode(q) for q in result.path],
            }
        elif method in PROPERTIES:
            out = encode(getattr(driver, method))
        else:
            out = encode(getattr(driver, method)(**args))
        return {"result": out, "q": encode(driver.joint_positions())}

    def serve(self, stop: threading.Event) -> None:
        """Answer queries until ``stop`` is set."""
        opens = self.session.declare_queryable(open_key(self.name))
        calls = self.session.declare_queryable(call_key(self.name))
        try:
            while not stop.is_set():
                answered = False
                for queryable, handle in ((opens, self.open), (calls, self.call)):
                    query = queryable.try_recv()
                    if query is not None:
                        answered = True
                        self._answer(query, handle)
                if not answered:
                    stop.wait(0.0005)
        finally:
            opens.undeclare()
            calls.undeclare()

    @staticmethod
    def _answer(query: zenoh.Query, handle: Any) -> None:
        try:
            HandServer._reply(query, handle)
        finally:
            query.drop()  # the query ends here: the client gets its one reply now

    @staticmethod
    def _reply(query: zenoh.Query, handle: Any) -> None:
        try:
            payload = json.loads(query.payload.to_bytes()) if query.payload is not None else {}
            reply = handle(payload)
        except RollingQPError as exc:
            query.reply_err(json.dumps({"error": str(exc), "type": "rolling", "status": exc.status}))
        except ValidationError as exc:
            query.reply_err(json.dumps({"error": f"{exc.field}: {exc.reason}", "type": "validation",
                                        "field": exc.field, "reason": exc.reason}))  # fmt: skip
        except (EosError, ValueError, TypeError, KeyError) as exc:
            query.reply_err(json.dumps({"error": f"{type(exc).__name__}: {exc}", "type": "error"}))
        else:
            query.reply(query.key_expr, json.dumps(reply))


def main(argv: list[str] | None = None) -> int:
    """Serve one hand until interrupted."""
    parser = argparse.ArgumentParser(description="serve a hand (its world) over Zenoh")
    parser.add_argument("--name", default="sim", help="the hand's name in the key expressions (sim)")
    parser.add_argument("--listen", nargs="*", default=[], help="endpoints to listen on")
    parser.add_argument("--connect", nargs="*", default=[], help="endpoints to connect to")
    args = parser.parse_args(argv)
    session = zenoh.open(make_config(listen=args.listen, connect=args.connect))
    stop = threading.Event()
    print(f"serving hand {args.name!r} on {call_key(args.name)}", flush=True)
    try:
        HandServer(session, args.name).serve(stop)
    except KeyboardInterrupt:
        pass
    finally:
        session.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
