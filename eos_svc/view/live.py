"""A live 3-D view of plans: a Drake MeshCat page on localhost that follows the cycles
(``eos plan --view``; ``eos client watch --view`` through :class:`StreamView`, which queues the
service's messages so that every MeshCat call happens in the view's thread; ``docs/view.md``).
"""

from __future__ import annotations

import queue
import time
from collections.abc import Mapping
from typing import Any

from pydrake.geometry import MeshcatAnimation

from eos_svc.agents.planner import default_hand
from eos_svc.errors import ValidationError
from eos_svc.kinematics import HandModel
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.view.replay_html import animate_hand
from eos_svc.view.scene import (
    CONTACTS,
    OBJECT,
    OBJECT_RGBA,
    POSTULATE,
    POSTULATE_RGBA,
    ROOT,
    HandDrawing,
    add_contacts,
    add_object,
    drawn_postulate,
    new_meshcat,
    play_once,
    postulated_object,
    set_camera,
)
from eos_svc.view.timeline import FPS, as_q, build_timeline

#: most hand updates sent to the browsers per second while a plan runs
MAX_UPDATES_PER_S = 30.0
#: goals a stream view remembers as done (their late messages are ignored)
GOALS_KEPT = 1000
#: board entries a live view reads from a cycle record
WANTED = frozenset({keys.HAND_Q, keys.HAND_PATH, keys.SHAPE, keys.OUTCOME})


def light_record(record: Any) -> dict[str, Any]:
    """The parts of a cycle record a view needs (JSON form), from a
    :class:`~eos_svc.records.CycleRecord` or its JSON form."""
    if not isinstance(record, Mapping):
        record = record.to_dict()
    seq, changes = record.get("seq"), record.get("changes")
    if isinstance(seq, bool) or not isinstance(seq, int) or not isinstance(changes, list):
        raise TypeError("not a cycle record: seq must be an integer and changes a list")
    return {
        **{k: record.get(k) for k in ("seq", "stage", "chosen", "outcome", "detail")},
        "changes": [c for c in changes if isinstance(c, Mapping) and c.get("key") in WANTED],
    }


class LiveView:
    """A MeshCat server showing one plan at a time, updated cycle by cycle.

    Serves ``url`` on ``host`` (``port`` None: the first free one of 7000–7099) for ``hand``
    (default hand3x3). Counts since :meth:`start`: ``cycles_seen``, ``updates_sent`` (hand poses
    sent to connected browsers, at most :data:`MAX_UPDATES_PER_S` a second).
    """

    def __init__(
        self, hand: HandModel | None = None, port: int | None = None, host: str = "localhost"
    ) -> None:
        self.meshcat = new_meshcat(host, port)
        self.url = self.meshcat.web_url()
        self.hand = hand or default_hand()
        self.drawing = HandDrawing(self.hand)
        self.drawing.add_to(self.meshcat)
        self._q0: tuple[float, ...] = tuple(float(x) for x in self.hand.neutral())
        set_camera(self.meshcat, ObjectSpec().position)  # where the default object lies
        self._label: str | None = None
        self._last_push = 0.0
        self.finished = False
        self.start()  # the hand at its start, nothing else drawn

    # --- what a plan does to the view ----------------------------------------------------------
    def start(self, request: PlanRequest | Mapping[str, Any] | None = None) -> None:
        """Show a new plan: the hand at its start, no contacts or postulate, its object when the
        request is given (ValidationError when it is not valid: the view stays reset)."""
        mc = self.meshcat
        for path in (CONTACTS, POSTULATE, OBJECT):
            mc.Delete(path)
        if self.finished:
            mc.SetAnimation(MeshcatAnimation(FPS))  # forget the previous plan's animation
        self.request: PlanRequest | None = None
        self._q_new: Any = None  # the last hand_q written (JSON form), converted when drawn
        self._records: list[dict[str, Any]] = []  # the cycles' entries a view reads, for finish()
        self._postulate: dict[str, Any] | None = None
        self.cycles_seen = 0
        self.updates_sent = 0
        self.finished = False
        self.drawing.pose_in(mc, self._q0)
        self._show_label("waiting for the first cycle")
        if request is not None:
            self.show_object(request)

    def show_object(self, request: PlanRequest | Mapping[str, Any]) -> None:
        """Draw the plan's object and look at it (ValidationError: not a valid request)."""
        req = request if isinstance(request, PlanRequest) else PlanRequest.from_dict(dict(request))
        self.request = req
        add_object(self.meshcat, OBJECT, req.obj, OBJECT_RGBA)
        set_camera(self.meshcat, req.obj.position)

    def cycle(self, record: Any) -> None:
        """Follow one cycle (a :class:`CycleRecord` or its JSON form); cheap when nobody watches:
        the record's few entries a view reads are kept for :meth:`finish`, nothing is drawn."""
        light = light_record(record)
        self._records.append(light)
        self.cycles_seen += 1
        for change in light.get("changes") or ():
            key = change.get("key")
            if key == keys.HAND_Q:
                self._q_new = change.get("new")
            elif key == keys.SHAPE:
                self._postulate = change.get("new")
        if self.meshcat.GetNumActiveConnections() == 0:
            return
        now = time.monotonic()
        if now - self._last_push >= 1.0 / MAX_UPDATES_PER_S:
            self._push(light)
            self._last_push = now

    @property
    def q(self) -> tuple[float, ...]:
        """The hand's latest configuration (the last ``hand_q`` seen, or the start)."""
        q = as_q(self._q_new, len(self._q0))
        return self._q0 if q is None else q

    def finish(self, result: Mapping[str, Any]) -> None:
        """Show how the plan ended: the final hand, the contacts with their friction cones, the
        postulate, the verdict; and the whole plan as the page's animation (play it from the
        controls' Animations folder)."""
        if self.request is None and isinstance(result.get("request"), Mapping):
            self.show_object(result["request"])
        if as_q(result.get("q_final"), len(self._q0)) is not None:
            self._q_new = result["q_final"]
        mc = self.meshcat
        self.drawing.pose_in(mc, self.q)
        self._draw_postulate()
        friction = result.get("friction", self.request.friction if self.request else None)
        add_contacts(mc, result.get("contacts"), friction)
        timeline = build_timeline(self._records, self._q0)
        if len(timeline.keyframes) > 1:
            anim = MeshcatAnimation(timeline.fps)
            animate_hand(anim, self.drawing, timeline)
            play_once(mc, anim, autoplay=False)
        self._show_label(
            f"{result.get('status')} after {result.get('cycles')} cycles; "
            f"good grasp: {'yes' if result.get('good_grasp') else 'no'}"
        )
        self.updates_sent += 1
        self.finished = True

    # --- drawing ---------------------------------------------------------------------------------
    def _push(self, light: Mapping[str, Any]) -> None:
        self.drawing.pose_in(self.meshcat, self.q)
        self._draw_postulate()
        self._show_label(
            f"cycle {light['seq']} {light['stage']}: {light['chosen'] or '-'} [{light['outcome'] or '-'}]"
        )
        self.updates_sent += 1

    def _draw_postulate(self) -> None:
        spec = postulated_object(self._postulate)
        if spec is None:
            self.meshcat.Delete(POSTULATE)
        else:
            add_object(self.meshcat, POSTULATE, drawn_postulate(spec), POSTULATE_RGBA)

    def _show_label(self, text: str) -> None:
        """The current cycle as a button label in the page's controls (top right)."""
        if self._label is not None:
            self.meshcat.DeleteButton(self._label)
        self.meshcat.AddButton(text)
        self._label = text

    def close(self) -> None:
        """Remove the drawing (the server stops when the view is garbage collected)."""
        self.meshcat.Delete(ROOT)
        self.meshcat.DeleteAddedControls()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


class StreamView:
    """A :class:`LiveView` fed by the service's messages (``EosClient.watch``), one goal at a time.

    :meth:`on_message` may be called from any thread (Zenoh's callbacks): it only queues.
    :meth:`pump` draws the queued messages in the view's thread. The view follows the goal
    whose messages arrive first until it is done, then the next goal that sends anything.
    """

    def __init__(self, view: LiveView) -> None:
        self.view = view
        self.goal: str | None = None
        self.inbox: queue.SimpleQueue[tuple[str, dict[str, Any]]] = queue.SimpleQueue()
        self.goals_done: list[str] = []
        self.rejected = 0
        self.last_rejection = ""

    def on_message(self, kind: str, msg: dict[str, Any]) -> None:
        """``EosClient.watch`` callback: queue the message (never blocks)."""
        self.inbox.put((kind, msg))

    def pump(self, timeout: float = 0.0) -> int:
        """Draw every queued message (waiting up to ``timeout`` s for the first); returns how many."""
        done = 0
        try:
            item = self.inbox.get(timeout=timeout) if timeout > 0 else self.inbox.get_nowait()
            while True:
                self._handle(*item)
                done += 1
                item = self.inbox.get_nowait()
        except queue.Empty:
            return done

    def _handle(self, kind: str, msg: dict[str, Any]) -> None:
        """Draw one message; one the view cannot read (a malformed request, record or result)
        is counted in :attr:`rejected` and skipped."""
        try:
            self._draw(kind, msg)
        except (ValidationError, TypeError, ValueError, KeyError) as exc:
            self.rejected += 1
            self.last_rejection = f"{kind} message of goal {msg.get('goal_id')!r}: {exc}"

    def _draw(self, kind: str, msg: dict[str, Any]) -> None:
        if not isinstance(msg, Mapping):
            raise TypeError(f"not a JSON object: {type(msg).__name__}")
        goal = msg.get("goal_id")
        if not isinstance(goal, str):
            return
        if self.goal is None:
            if goal in self.goals_done:
                return
            self.goal = goal
            request = msg.get("request")
            self.view.start(request if isinstance(request, Mapping) else None)
        if goal != self.goal:
            return
        if kind == "cycle":
            if not isinstance(msg.get("record"), Mapping):
                raise TypeError("a cycle message without a record object")
            self.view.cycle(msg["record"])
        elif kind == "status" and msg.get("state") == "done":
            self.goals_done.append(goal)
            del self.goals_done[:-GOALS_KEPT]
            self.goal = None  # done, even when its result cannot be drawn
            result = msg.get("result")
            self.view.finish(result if isinstance(result, Mapping) else {})
