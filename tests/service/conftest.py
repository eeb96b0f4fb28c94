"""Fixtures: real Zenoh sessions on loopback (multicast scouting off), one free port per test."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from eos_svc.service.client import EosClient
from eos_svc.service.demo_planner import root_plan
from eos_svc.service.server import PlanService
from eos_svc.service.session import free_port, loopback, make_config


@pytest.fixture(scope="session")
def grasp_planner() -> Callable[..., Any]:
    """The real grasp planner; EOS_TEST_PLANNER=root swaps in the core demo (transport only)."""
    if os.environ.get("EOS_TEST_PLANNER") == "root":
        return root_plan
    from eos_svc.agents.planner import plan

    return plan


def _default_planner() -> Callable[..., Any]:
    if os.environ.get("EOS_TEST_PLANNER") == "root":
        return root_plan
    from eos_svc.agents.planner import plan

    return plan


@pytest.fixture
def port() -> int:
    return free_port()


@pytest.fixture
def services() -> Iterator[Callable[..., PlanService]]:
    """Factory: start an in-process service instance (threads) on its own session; all stopped at the end.

    ``services(listen_port, connect_ports=(), **PlanService kwargs)``.
    """
    started: list[PlanService] = []

    def start(
        listen: int | None = None, connect: tuple[int, ...] = (), lease_ms: int | None = None, **kwargs: Any
    ) -> PlanService:
        kwargs.setdefault("planner", _default_planner())
        conf = make_config(
            listen=[loopback(listen)] if listen else [],
            connect=[loopback(p) for p in connect],
            lease_ms=lease_ms,
        )
        svc = PlanService.open(conf, **kwargs)
        started.append(svc)
        return svc

    yield start
    for svc in started:
        svc.stop()


@pytest.fixture
def clients() -> Iterator[Callable[..., EosClient]]:
    """Factory: a client connected to the given loopback ports; all closed at the end."""
    opened: list[EosClient] = []

    def open_client(*ports: int, **kwargs: Any) -> EosClient:
        client = EosClient.open(make_config(connect=[loopback(p) for p in ports]), **kwargs)
        opened.append(client)
        return client

    yield open_client
    for c in opened:
        c.close()
