"""The plan as a self-contained HTML page: its content, and how headless Chromium renders it."""

from __future__ import annotations

import json
import re

import pytest

from eos_svc.agents import PlanRequest, keys, plan
from eos_svc.view import write_plan_html, write_result_html
from eos_svc.view.replay_html import plan_scene
from eos_svc.view.scene import CONTACTS, OBJECT, POSTULATE

from .browser import dump_dom, find_chromium, screenshot
from .pixels import colour_regions, distance, mean_difference

needs_chromium = pytest.mark.skipif(
    find_chromium() is None, reason="Chromium not installed (make test installs it with apt-get as root)"
)


@pytest.fixture(scope="module")
def result():
    return plan(PlanRequest(seed=1))


@pytest.fixture(scope="module")
def page(result, tmp_path_factory):
    return write_result_html(result, tmp_path_factory.mktemp("html") / "plan.html")


def test_page_is_self_contained_and_lists_every_cycle(page, result):
    text = page.read_text(encoding="utf-8")
    assert page.stat().st_size < 5_000_000
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", text)  # nothing loaded from elsewhere
    assert re.findall(r'fetch\("([a-z]+):', text) and set(re.findall(r'fetch\("([a-z]+):', text)) == {"data"}
    embedded = re.search(r'<script type="application/json" id="eos-plan">(.*?)</script>', text)
    info = json.loads(embedded.group(1))
    assert [c["seq"] for c in info["cycles"]] == list(range(1, result.cycles + 1))
    assert [(c["stage"], c["chosen"]) for c in info["cycles"]] == [(r.stage, r.chosen) for r in result.trace]
    assert info["cycles"][-1]["outcome"] == "finished" and result.status in info["title"]
    assert info["duration"] == pytest.approx(info["cycles"][-1]["t1"])


#: a postulated object in the request's JSON form (the postulate's ``object``), off the truth
GUESS = {
    "shape": "ellipsoid",
    "radii": [0.033, 0.028, 0.03],
    "position": [0.212, 0.02, -0.014],
    "rpy": [0, 0, 0.3],
}


def with_postulated_object(records):
    """The records with ``GUESS`` as the ``object`` of every sized postulate; the first such cycle."""
    first = None
    for record in records:
        for change in record["changes"]:
            if change["key"] == keys.SHAPE and change["new"]["grasp_radius"] is not None:
                change["new"] = {**change["new"], "object": GUESS, "pose_known": False}
                first = first or record["seq"]
    return records, first


def test_scene_holds_the_object_the_contacts_and_the_postulate(result):
    """A postulate carrying an ``object`` is drawn (every plan now carries one); one without is not."""
    records = [r.to_dict() for r in result.trace]
    scene = plan_scene(result.request, records, result.to_dict())
    assert scene.meshcat.HasPath(OBJECT)
    assert scene.contacts == 3 and all(scene.meshcat.HasPath(f"{CONTACTS}/finger{i}") for i in (1, 2, 3))
    if not any(c["key"] == keys.SHAPE and "object" in c["new"] for r in records for c in r["changes"]):
        assert scene.postulates == 0 and not scene.meshcat.HasPath(POSTULATE)
    records, _ = with_postulated_object(records)
    scene = plan_scene(result.request, records, result.to_dict())
    assert scene.postulates >= 1 and scene.meshcat.HasPath(f"{POSTULATE}/1")


@needs_chromium
def test_chromium_shows_the_postulate_from_its_cycle_on(result, tmp_path):
    records, first = with_postulated_object([r.to_dict() for r in result.trace])
    page = write_plan_html(tmp_path / "postulate.html", result.request, records, result.to_dict())
    before = colour_regions(screenshot(f"{page.as_uri()}#cycle={first - 1}", tmp_path / "before.png"))
    after = colour_regions(screenshot(f"{page.as_uri()}#cycle={first}", tmp_path / "after.png"))
    assert before["postulate"][0] < 50 < 200 < after["postulate"][0]  # translucent yellow appears
    assert after["object"][0] < 0.8 * before["object"][0]  # over the blue object


def union(a, b):
    """Two colour regions (pixel count, centroid) as one."""
    (na, ca), (nb, cb) = a, b
    if not nb:
        return a
    if not na:
        return b
    return na + nb, tuple((na * x + nb * y) / (na + nb) for x, y in zip(ca, cb, strict=True))


@needs_chromium
def test_chromium_draws_the_hand_and_the_object_and_steps_the_animation(page, result, tmp_path):
    # from the first information cycle (the search's sweeps cross the whole workspace, out of
    # this close-up camera's frame) to the last
    first_info = next(r.seq for r in result.trace if r.stage == "information")
    start = screenshot(f"{page.as_uri()}#cycle={first_info}", tmp_path / "start.png")
    end = screenshot(f"{page.as_uri()}#cycle={result.cycles}", tmp_path / "end.png")
    a, b = colour_regions(start), colour_regions(end)
    for shot in (a, b):
        # the true object seen through the translucent postulate (drawn 1 % larger) takes its hue
        shot["object"] = union(shot["object"], shot["postulate"])
        assert shot["object"][0] > 2000  # the sphere, tens of pixels across
        assert shot["tip2"][0] > 200 and shot["tip3"][0] > 200  # two fingertips
    assert b["tip1"][0] > 50  # the third one, beside the others at the end
    # the object does not move (it is ~120 px across; fingertips and the contact cone hide parts)
    assert distance(a["object"][1], b["object"][1]) < 15.0
    # the hand closes on it: the fingertips end near the object's centre
    for tip in ("tip2", "tip3"):
        assert distance(b[tip][1], b["object"][1]) < 0.6 * distance(a[tip][1], a["object"][1])
    assert mean_difference(start, end) > 1.0


@needs_chromium
def test_chromium_shows_the_cycle_under_the_cursor(page, result):
    dom = dump_dom(f"{page.as_uri()}#cycle=16")
    assert 'data-eos-ready="1"' in dom and 'data-eos-cycle="16"' in dom
    record = result.trace[15]
    shown = re.search(r'<div id="eos-cycle">(.*?)</div>', dom).group(1)
    assert shown == f"cycle 16/{result.cycles}  {record.stage}  {record.chosen} [{record.outcome.value}]"
