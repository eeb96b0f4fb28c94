"""A plan as one self-contained HTML file: Drake MeshCat's static page with the plan animated.

    from eos_svc.agents import plan
    from eos_svc.view import write_result_html
    write_result_html(plan(), "plan.html")           # or: eos plan --html plan.html

The page (Drake's ``Meshcat.StaticHtml()``: three.js, the MeshCat viewer and the scene in one
file, no network) plays the whole plan once: the hand moving through every cycle (search moves,
EP1's rolls, the wrist approach, each finger closing), the object, the postulated object (when
the postulate carries one) and, from the end agent's verdict on, the contacts with their force
directions and friction cones. A panel at the top left shows the cycle under the time cursor
(number, stage, chosen agent, outcome, what it did), a play/pause button and a time slider.
The page reads its URL fragment: ``#t=SECONDS`` or ``#cycle=N`` (the end of cycle N) opens it
paused at that time.
"""

from __future__ import annotations

import html
import json
import logging
from collections.abc import Iterable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.geometry import Meshcat, MeshcatAnimation, MeshcatParams
from pydrake.math import RigidTransform, RotationMatrix

from eos_svc.agents.planner import default_hand
from eos_svc.kinematics import HandModel
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.view.scene import (
    CONTACTS,
    OBJECT,
    OBJECT_RGBA,
    POSTULATE,
    POSTULATE_RGBA,
    HandDrawing,
    add_contacts,
    add_object,
    postulated_object,
    set_camera,
    vec,
)
from eos_svc.view.timeline import Timeline, build_timeline, changes_of

#: two poses closer than this (max |entry| of the 4×4 difference) are the same keyframe
POSE_EPS = 1e-9


@contextmanager
def quiet_drake() -> Any:
    """Silence Drake's INFO log lines (e.g. "Meshcat listening ...") for a moment."""
    logger = logging.getLogger("drake")
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield
    finally:
        logger.setLevel(level)


def export_meshcat() -> Meshcat:
    """A MeshCat instance used only to build a page (its server on localhost, on an ephemeral
    port: it never takes one of the 7000–7099 a live view would use)."""
    params = MeshcatParams()
    params.host = "localhost"
    params.port = 0
    params.show_stats_plot = False
    with quiet_drake():
        return Meshcat(params)


def _same(a: Any, b: Any) -> bool:
    return bool(np.max(np.abs(a - b)) <= POSE_EPS)


def animate_hand(anim: MeshcatAnimation, drawing: HandDrawing, timeline: Timeline) -> int:
    """Put the hand's keyframes in ``anim``: a key per part only where its pose changes, plus
    a hold key where it starts moving after a rest (so it does not drift across the rest).

    Returns:
        the number of transform keys written.
    """
    paths = [p.path for p in drawing.parts]
    last: list[tuple[int, Any] | None] = [None] * len(paths)
    prev_frame = -1
    written = 0
    for frame, q in timeline.keyframes:
        poses = drawing.poses(q)
        for i, pose in enumerate(poses):
            matrix = pose.GetAsMatrix4()
            seen = last[i]
            if seen is not None and _same(seen[1], matrix):
                continue
            if seen is not None and prev_frame > seen[0]:
                anim.SetTransform(prev_frame, paths[i], RigidTransform(seen[1]))
                written += 1
            anim.SetTransform(frame, paths[i], pose)
            last[i] = (frame, matrix)
            written += 1
        prev_frame = frame
    return written


def _postulates(meshcat: Meshcat, anim: MeshcatAnimation, timeline: Timeline) -> int:
    """Draw each distinct postulated object, visible from its cycle to the next postulate's."""
    shown: list[tuple[int, ObjectSpec | None]] = [(f, postulated_object(s)) for f, s in timeline.postulates]
    drawn = 0
    for k, (frame, spec) in enumerate(shown):
        if spec is None:
            continue
        path = f"{POSTULATE}/{k}"
        add_object(meshcat, path, spec, POSTULATE_RGBA)
        anim.SetProperty(0, path, "visible", False)
        anim.SetProperty(frame, path, "visible", True)
        if k + 1 < len(shown):
            anim.SetProperty(shown[k + 1][0], path, "visible", False)
        drawn += 1
    return drawn


def _animate_object(anim: MeshcatAnimation, timeline: Timeline, records: Sequence[Mapping[str, Any]]) -> int:
    """Move the true object to its recorded pose at the end of every cycle that moved it (the
    Drake world's ``object_pose`` entries: x, y, z, quaternion w, x, y, z); returns how many."""
    moved = 0
    for record in records:
        pose = changes_of(record).get(keys.OBJECT_POSE)
        if not isinstance(pose, Sequence) or len(pose) != 7:
            continue
        try:
            end = timeline.span_end_s(int(record["seq"]))
        except (KeyError, TypeError, ValueError):
            continue
        x, y, z, qw, qx, qy, qz = (float(v) for v in pose)
        rotation = RotationMatrix(Quaternion(np.array([qw, qx, qy, qz]) / np.linalg.norm([qw, qx, qy, qz])))
        anim.SetTransform(round(end * timeline.fps), OBJECT, RigidTransform(rotation, vec((x, y, z))))
        moved += 1
    return moved


def _result_text(request: PlanRequest, result: Mapping[str, Any] | None) -> str:
    obj = request.obj
    head = f"{obj.shape} d = {obj.diameter * 1000:.1f} mm at {tuple(round(x, 3) for x in obj.position)}"
    head += f", seed {request.seed}"
    if result is None:
        return head + " — no result (the recording was interrupted)"
    return (
        f"{head} — {result.get('status')}: {result.get('reason', '')} "
        f"({result.get('cycles')} cycles; good grasp: {'yes' if result.get('good_grasp') else 'no'})"
    )


@dataclass
class PlanScene:
    """A plan drawn and animated in a MeshCat instance (before it is written as a page).

    Attributes:
        meshcat: the instance holding the scene and the animation.
        timeline: the plan's timeline.
        info: what the page's panel shows (title, duration, one entry per cycle).
        postulates: postulated objects drawn; contacts: touching contacts drawn.
    """

    meshcat: Meshcat
    timeline: Timeline
    info: dict[str, Any]
    postulates: int
    contacts: int


def plan_scene(
    request: Mapping[str, Any] | PlanRequest,
    records: Iterable[Mapping[str, Any]],
    result: Mapping[str, Any] | None = None,
    hand: HandModel | None = None,
) -> PlanScene:
    """Draw and animate a plan in a new MeshCat instance.

    Args:
        request: the plan request (JSON form or :class:`PlanRequest`).
        records: the cycle records in their JSON form, in order.
        result: the plan result's JSON form (its ``contacts`` and ``friction`` are drawn), or
            None (the contacts come from the end agent's verdict in the records, if any).
        hand: the hand planned with (default hand3x3).

    Raises:
        ValidationError: the request is not a valid plan request.
    """
    req = request if isinstance(request, PlanRequest) else PlanRequest.from_dict(dict(request))
    hand = hand or default_hand()
    records = list(records)
    drawing = HandDrawing(hand)
    timeline = build_timeline(records, hand.neutral())
    meshcat = export_meshcat()
    drawing.add_to(meshcat)
    drawing.pose_in(meshcat, timeline.keyframes[0][1])
    add_object(meshcat, OBJECT, req.obj, OBJECT_RGBA)
    anim = MeshcatAnimation(timeline.fps)
    animate_hand(anim, drawing, timeline)
    _animate_object(anim, timeline, records)
    postulates = _postulates(meshcat, anim, timeline)
    verdict = timeline.verdict
    contacts = (result or {}).get("contacts") or (verdict[1].get("contacts") if verdict else None)
    friction = (result or {}).get("friction", req.friction)
    drawn = add_contacts(meshcat, contacts, friction)
    if drawn:
        anim.SetProperty(0, CONTACTS, "visible", False)
        anim.SetProperty(verdict[0] if verdict else timeline.frames, CONTACTS, "visible", True)
    anim.set_autoplay(True)
    anim.set_loop_mode(MeshcatAnimation.LoopMode.kLoopOnce)
    anim.set_clamp_when_finished(True)
    meshcat.SetAnimation(anim)
    set_camera(meshcat, req.obj.position)
    meshcat.SetProperty("/Grid", "visible", False)
    meshcat.SetProperty("/Axes", "visible", False)
    info = {
        "title": _result_text(req, result),
        "duration": timeline.duration_s,
        "fps": timeline.fps,
        "cycles": [s.to_dict(timeline.fps) for s in timeline.spans],
    }
    return PlanScene(meshcat, timeline, info, postulates, len(drawn))


def plan_page(
    request: Mapping[str, Any] | PlanRequest,
    records: Iterable[Mapping[str, Any]],
    result: Mapping[str, Any] | None = None,
    hand: HandModel | None = None,
) -> str:
    """The self-contained HTML page of a plan (arguments as :func:`plan_scene`)."""
    scene = plan_scene(request, records, result, hand)
    return inject_panel(scene.meshcat.StaticHtml(), scene.info)


def inject_panel(page: str, info: Mapping[str, Any]) -> str:
    """``page`` with the plan panel (HTML, CSS, script and the plan's JSON) before ``</body>``."""
    data = json.dumps(info, allow_nan=False).replace("</", "<\\/")
    panel = (
        PANEL_HTML.replace("@TITLE@", html.escape(str(info.get("title", ""))))
        + f'<script type="application/json" id="eos-plan">{data}</script>\n'
        + f"<script>{PANEL_JS}</script>\n"
    )
    at = page.rfind("</body>")
    if at < 0:
        raise ValueError("not a MeshCat page: no </body>")
    return page[:at] + panel + page[at:]


def write_plan_html(
    path: str | Path,
    request: Mapping[str, Any] | PlanRequest,
    records: Iterable[Mapping[str, Any]],
    result: Mapping[str, Any] | None = None,
    hand: HandModel | None = None,
) -> Path:
    """Write :func:`plan_page` to ``path`` (UTF-8); returns the path.

    Raises:
        OSError: the file cannot be written.
    """
    out = Path(path)
    out.write_text(plan_page(request, records, result, hand), encoding="utf-8")
    return out


def write_result_html(result: Any, path: str | Path, hand: HandModel | None = None) -> Path:
    """Write the page of a :class:`~eos_svc.agents.PlanResult` (its trace must be kept).

    Raises:
        ValueError: the result has no trace (planned with ``keep_trace=False``).
    """
    trace: Sequence[Any] = result.trace
    if not trace and result.cycles:
        raise ValueError("the result holds no trace: plan with keep_trace=True to draw it")
    return write_plan_html(path, result.request, [r.to_dict() for r in trace], result.to_dict(), hand)


PANEL_HTML = """
<div id="eos-panel">
  <div id="eos-title">@TITLE@</div>
  <div id="eos-controls">
    <button id="eos-play" type="button">pause</button>
    <input id="eos-time" type="range" min="0" max="1" step="0.0625" value="0">
    <span id="eos-clock">0.0 s</span>
  </div>
  <div id="eos-cycle"></div>
  <div id="eos-detail"></div>
  <div id="eos-legend"><b style="color:#4c9be8">&#9632;</b> object (truth)
    <b style="color:#ffd91a">&#9632;</b> postulate
    <b style="color:#e8a33c">&#9632;</b><b style="color:#58b85c">&#9632;</b><b
    style="color:#b565c9">&#9632;</b> fingertips
    <b style="color:#d62728">&#9632;</b> contacts, force lines, friction cones</div>
</div>
<style>
  #eos-panel { position: fixed; left: 8px; top: 8px; width: 440px; padding: 8px 10px;
    background: rgba(255, 255, 255, 0.88); border-radius: 6px; font: 12px/1.35 sans-serif;
    color: #222; z-index: 10; }
  #eos-title { font-weight: bold; margin-bottom: 4px; }
  #eos-controls { display: flex; gap: 6px; align-items: center; margin: 4px 0; }
  #eos-time { flex: 1; }
  #eos-cycle { font-family: monospace; font-size: 13px; }
  #eos-detail { margin-top: 2px; min-height: 3em; }
  #eos-legend { margin-top: 4px; color: #555; }
</style>
"""

PANEL_JS = """
(function () {
  var plan = JSON.parse(document.getElementById("eos-plan").textContent);
  var slider = document.getElementById("eos-time");
  var button = document.getElementById("eos-play");
  slider.max = String(plan.duration);
  slider.step = String(1 / plan.fps);
  var target = null;
  function parseHash() {
    var h = window.location.hash.replace(/^#/, "");
    var m = /(?:^|&)t=([0-9.]+)/.exec(h);
    if (m) { return parseFloat(m[1]); }
    m = /(?:^|&)cycle=([0-9]+)/.exec(h);
    if (m) {
      var n = parseInt(m[1], 10);
      for (var i = 0; i < plan.cycles.length; i++) {
        if (plan.cycles[i].seq === n) { return plan.cycles[i].t1; }
      }
      return plan.duration;
    }
    return null;
  }
  function animator() {
    if (typeof viewer === "undefined" || !viewer.animator) { return null; }
    return viewer.animator.actions.length ? viewer.animator : null;
  }
  function now(a) {
    return a.actions.reduce(function (m, x) { return Math.max(m, x.time); }, 0);
  }
  function cycleAt(t) {
    var lo = 0, hi = plan.cycles.length - 1, found = -1;
    while (lo <= hi) {
      var mid = (lo + hi) >> 1;
      // cycle k covers (t0, t1]: at its t1 the cycle is done and shown
      if (plan.cycles[mid].t0 < t - 1e-9) { found = mid; lo = mid + 1; } else { hi = mid - 1; }
    }
    return found < 0 ? null : plan.cycles[found];
  }
  function show(t) {
    var c = cycleAt(t);
    slider.value = String(t);
    document.getElementById("eos-clock").textContent = t.toFixed(1) + " / " + plan.duration.toFixed(1) + " s";
    document.getElementById("eos-cycle").textContent = c === null ? "before the first cycle" :
      "cycle " + c.seq + "/" + plan.cycles.length + "  " + c.stage + "  " + (c.chosen || "-") +
      " [" + (c.outcome || "-") + "]";
    document.getElementById("eos-detail").textContent = c === null ? "" : c.detail;
    document.body.dataset.eosCycle = c === null ? "0" : String(c.seq);
  }
  function seek(a, t) {
    a.pause();
    a.seek(t);
    a.display_progress(t);
    button.textContent = "play";
    show(t);
  }
  var ready = false;
  window.setInterval(function () {
    var a = animator();
    if (a === null) { return; }
    if (!ready) {
      ready = true;
      target = parseHash();
      if (target !== null) { seek(a, target); }
      document.body.dataset.eosReady = "1";
    }
    if (a.playing) { show(now(a)); button.textContent = "pause"; } else { button.textContent = "play"; }
  }, 100);
  window.addEventListener("hashchange", function () {
    var a = animator(), t = parseHash();
    if (a !== null && t !== null) { seek(a, t); }
  });
  slider.addEventListener("input", function () {
    var a = animator();
    if (a !== null) { seek(a, parseFloat(slider.value)); }
  });
  button.addEventListener("click", function () {
    var a = animator();
    if (a === null) { return; }
    if (a.playing) { a.pause(); return; }
    if (now(a) >= plan.duration - 1e-6) { a.reset(); }
    a.play();
  });
})();
"""
