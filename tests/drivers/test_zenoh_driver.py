"""The hand driver over Zenoh: a second process serves the world (kinematic or Drake), this
process plans through :class:`ZenohDriver` and never holds the object."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import zenoh

from eos_svc.agents import PlanRequest, plan
from eos_svc.drivers.zenoh_driver import ZenohDriver
from eos_svc.kinematics.errors import KinematicsError
from eos_svc.service.session import free_port, loopback, make_config

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def session() -> Iterator[zenoh.Session]:
    port = free_port()
    server = subprocess.Popen(
        [sys.executable, "-m", "eos_svc.drivers.zenoh_server", "--name", "sim", "--listen", loopback(port)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert server.stdout is not None
        assert "serving hand" in server.stdout.readline()
        s = zenoh.open(make_config(connect=[loopback(port)]))
        try:
            yield s
        finally:
            s.close()
    finally:
        server.terminate()
        server.wait(timeout=10)


def test_a_plan_through_a_hand_served_by_another_process_succeeds(session: zenoh.Session) -> None:
    request = PlanRequest(seed=1)
    driver = ZenohDriver(session, "sim", request)
    result = plan(request, driver=driver)
    assert result.status == "success" and result.good_grasp
    local = plan(request)
    # the same kinematic world: the search and EP2 draw from two generators, so the cycles may
    # differ, but the grip is judged on the same true object
    assert result.precision_grip and local.precision_grip


def test_the_drake_world_served_from_another_process_reports_a_pressed_touch(session: zenoh.Session) -> None:
    request = PlanRequest(seed=1, world="drake")
    kinematic = plan(PlanRequest(seed=1))
    driver = ZenohDriver(session, "sim", request)
    q = np.array(kinematic.q_final)
    hand = driver.hand
    for finger in hand.finger_names:
        q[hand.finger_q_index(finger)] -= 0.3
    driver.move_joints(q)
    for _ in range(40):
        step = driver.close_finger_step(hand.opposing_finger, 0.02)
        if step.event != "moved":
            break
    assert step.event == "touched" and step.touch is not None and step.touch.force > 0.0
    assert driver.clock() > 0.2  # simulated time went by in the serving process
    report = driver.report()
    assert report is not None and report["name"] == "drake"


def test_a_refused_call_names_the_field(session: zenoh.Session) -> None:
    driver = ZenohDriver(session, "sim", PlanRequest(seed=2))
    with pytest.raises(KinematicsError) as err:
        driver.move_joints(np.zeros(3))  # the hand has 15 joints
    assert err.value.field
