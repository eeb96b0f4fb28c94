"""The live view: a MeshCat page on localhost following a plan, from the planner and over Zenoh."""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import threading
import time
import urllib.request

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.service.client import EosClient
from eos_svc.service.server import PlanService
from eos_svc.service.session import free_port, loopback, make_config
from eos_svc.view.live import LiveView, StreamView
from eos_svc.view.scene import CONTACTS, OBJECT

from .browser import find_chromium, screenshot, screenshot_command
from .pixels import colour_regions, distance


def _local(url: str) -> str:
    return url.replace("localhost", "127.0.0.1")


def test_plan_followed_by_a_live_view_nobody_watches():
    request = PlanRequest(seed=4)
    view = LiveView()
    view.start(request)
    result = plan(request, on_cycle=view.cycle)
    view.finish(result.to_dict())
    assert view.cycles_seen == result.cycles
    assert view.updates_sent == 1  # nobody connected: only the final state was drawn
    assert np.allclose(view.q, result.q_final, atol=1e-7)
    assert view.meshcat.HasPath(OBJECT)
    assert view.meshcat.GetButtonNames() == [f"{result.status} after {result.cycles} cycles; good grasp: yes"]
    touching = [f for f, c in result.contacts.items() if c["touching"]]
    assert touching and all(view.meshcat.HasPath(f"{CONTACTS}/{f}") for f in touching)
    with urllib.request.urlopen(_local(view.url), timeout=10) as reply:  # the page is served
        assert reply.status == 200 and "MeshCat" in reply.read().decode("utf-8", "replace")


@pytest.mark.skipif(find_chromium() is None, reason="Chromium not installed (make test installs it as root)")
def test_watcher_follows_a_remote_plan_over_zenoh_in_a_browser(tmp_path):
    """A plan on a real service (Zenoh on loopback) watched live: a headless Chromium is on the
    page while the plan runs (the view pushes cycles to it), and a second one, after the plan,
    sees the final grasp (hand closed on the object)."""
    port = free_port()
    service = PlanService.open(make_config(listen=[loopback(port)]), planner=plan)
    client = EosClient.open(make_config(connect=[loopback(port)]))
    stream = StreamView(LiveView())
    watching = client.watch(stream.on_message)
    profile = tempfile.TemporaryDirectory(prefix="eos-chromium-", ignore_cleanup_errors=True)
    browser = subprocess.Popen(
        screenshot_command(
            _local(stream.view.url), tmp_path / "during.png", profile.name, budget_ms=30000, offline=False
        ),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its own process group: stopped with its renderers below
    )
    try:
        client.wait_for_instances(1)
        end = time.monotonic() + 60
        while stream.view.meshcat.GetNumActiveConnections() == 0 and time.monotonic() < end:
            time.sleep(0.05)
        assert stream.view.meshcat.GetNumActiveConnections() > 0, "Chromium never opened the live page"
        # the plan runs in a thread while this one draws the stream, as `eos client watch --view`
        outcomes: list = []
        planning = threading.Thread(
            target=lambda: outcomes.append(client.plan(PlanRequest(seed=6), goal_id="watched-1"))
        )
        planning.start()
        end = time.monotonic() + 30
        while "watched-1" not in stream.goals_done and time.monotonic() < end:
            stream.pump(0.05)
        planning.join(timeout=30)
        (outcome,) = outcomes
    finally:
        watching.undeclare()
        if browser.poll() is None:
            os.killpg(browser.pid, signal.SIGKILL)
        browser.wait()
        profile.cleanup()
        client.close()
        service.stop()
    view = stream.view
    assert stream.goals_done == ["watched-1"]
    assert view.cycles_seen == outcome.result["cycles"]  # every cycle of the stream
    assert view.updates_sent >= 2  # pushed while the plan ran (throttled), then the end
    assert np.allclose(view.q, outcome.result["q_final"], atol=1e-7)
    assert view.request is not None and view.request.seed == 6  # from the running status
    assert view.meshcat.GetButtonNames()[0].startswith(f"{outcome.result['status']} after ")
    shot = colour_regions(screenshot(_local(view.url), tmp_path / "after.png", offline=False))
    assert shot["object"][0] > 2000 and shot["tip2"][0] > 100 and shot["tip3"][0] > 100
    assert distance(shot["tip2"][1], shot["object"][1]) < 120  # closed on the object


def test_stream_view_skips_messages_it_cannot_read():
    """Malformed messages (a bad request, a record that is not one, garbage) are counted and
    skipped; the next goal is drawn."""
    stream = StreamView(LiveView())
    bad_request = {"object": {"shape": "cone"}}
    for kind, msg in [
        ("status", {"goal_id": "g1", "state": "running", "request": bad_request}),
        ("cycle", {"goal_id": "g1", "seq": 1, "record": {"seq": "one", "changes": "x"}}),
        ("cycle", {"goal_id": "g1", "seq": 2, "record": ["not", "a", "record"]}),
        ("status", {"goal_id": "g1", "state": "done", "result": {"request": bad_request}}),
    ]:
        stream.on_message(kind, msg)
    stream.pump()
    assert stream.rejected == 4 and "'g1'" in stream.last_rejection
    request = PlanRequest(seed=2)
    result = plan(request)
    stream.on_message("status", {"goal_id": "g2", "state": "running", "request": request.to_dict()})
    for r in result.trace:
        stream.on_message("cycle", {"goal_id": "g2", "seq": r.seq, "record": r.to_dict()})
    stream.on_message("status", {"goal_id": "g2", "state": "done", "result": result.to_dict()})
    stream.pump()
    assert "g2" in stream.goals_done and stream.view.cycles_seen == result.cycles
    assert np.allclose(stream.view.q, result.q_final, atol=1e-7)
