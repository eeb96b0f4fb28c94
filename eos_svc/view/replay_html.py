"""A plan as one self-contained HTML file: Drake MeshCat's static page with the plan animated
and a panel of the cycle under the time cursor (``eos plan --html``; the page: ``docs/view.md``).
"""

from __future__ import annotations

import html
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.geometry import Meshcat, MeshcatAnimation
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
    drawn_postulate,
    new_meshcat,
    play_once,
    postulated_object,
    set_camera,
    vec,
)
from eos_svc.view.timeline import Timeline, build_timeline, changes_of

#: two poses closer than this (max |entry| of the 4×4 difference) are the same keyframe
POSE_EPS = 1e-9


def _same(a: Any, b: Any) -> bool:
    return bool(np.max(np.abs(a - b)) <= POSE_EPS)


def animate_hand(anim: MeshcatAnimation, drawing: HandDrawing, timeline: Timeline) -> int:
    """Put the hand's keyframes in ``anim``: a key per part only where its pose changes, plus a
    hold key where it starts moving after a rest (no drift across it); returns the keys written."""
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
        add_object(meshcat, path, drawn_postulate(spec), POSTULATE_RGBA)
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
    """A plan drawn and animated in ``meshcat``: its ``timeline``, what the page's panel shows
    (``info``: title, duration, one entry per cycle), how many postulates and contacts were drawn."""

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
    """Draw and animate a plan (its request, its cycle records' JSON form in order, its result's
    JSON form or None: then the contacts of the end agent's verdict) in a new MeshCat instance;
    ``hand`` default hand3x3. Raises ValidationError for a request that is not valid."""
    req = request if isinstance(request, PlanRequest) else PlanRequest.from_dict(dict(request))
    hand = hand or default_hand()
    records = list(records)
    drawing = HandDrawing(hand)
    timeline = build_timeline(records, hand.neutral())
    meshcat = new_meshcat(port=0)  # never one of the ports a live view would use
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
    play_once(meshcat, anim, autoplay=True)
    set_camera(meshcat, req.obj.position)
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
    """The self-contained HTML page of a plan (arguments as :func:`plan_scene`): MeshCat's static
    page with the plan panel (``panel.html``, ``panel.js`` beside this module, the plan's JSON)."""
    scene = plan_scene(request, records, result, hand)
    page = scene.meshcat.StaticHtml()
    data = json.dumps(scene.info, allow_nan=False).replace("</", "<\\/")
    here = resources.files("eos_svc.view")
    title = html.escape(str(scene.info["title"]))
    panel = (
        "\n"
        + here.joinpath("panel.html").read_text(encoding="utf-8").replace("@TITLE@", title)
        + f'<script type="application/json" id="eos-plan">{data}</script>\n'
        + f"<script>\n{here.joinpath('panel.js').read_text(encoding='utf-8')}</script>\n"
    )
    at = page.rfind("</body>")
    return page[:at] + panel + page[at:]


def write_plan_html(
    path: str | Path,
    request: Mapping[str, Any] | PlanRequest,
    records: Iterable[Mapping[str, Any]],
    result: Mapping[str, Any] | None = None,
    hand: HandModel | None = None,
) -> Path:
    """Write :func:`plan_page` to ``path`` (UTF-8; OSError when it cannot); returns the path."""
    out = Path(path)
    out.write_text(plan_page(request, records, result, hand), encoding="utf-8")
    return out


def write_result_html(result: Any, path: str | Path, hand: HandModel | None = None) -> Path:
    """Write the page of a :class:`~eos_svc.agents.PlanResult` (ValueError: it kept no trace)."""
    trace: Sequence[Any] = result.trace
    if not trace and result.cycles:
        raise ValueError("the result holds no trace: plan with keep_trace=True to draw it")
    return write_plan_html(path, result.request, [r.to_dict() for r in trace], result.to_dict(), hand)
