"""The shipped access-control example: a client may ask and read, never serve or publish under eos/@v1.

A Python session in router mode loads config/router-acl.json5 (ACL + user/password
authentication); a service instance joins as user ``planner``, clients as ``alice``.
Each denial is shown by its absence of effect, next to a control where the same
operation by a planner does have an effect.
"""

from __future__ import annotations

import json
import queue
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from eos_svc.agents.planner import plan
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.client import EosClient
from eos_svc.service.server import PlanService
from eos_svc.service.session import loopback

CONFIG = Path(__file__).resolve().parents[2] / "config"


def load(name: str, port: int, *, listen: bool = False) -> zenoh.Config:
    conf = zenoh.Config.from_file(str(CONFIG / name))
    conf.insert_json5("listen/endpoints" if listen else "connect/endpoints", json.dumps([loopback(port)]))
    return conf


@pytest.fixture
def router(port: int) -> Iterator[zenoh.Session]:
    conf = load("router-acl.json5", port, listen=True)
    conf.insert_json5("transport/auth/usrpwd/dictionary_file", json.dumps(str(CONFIG / "eos-users.txt")))
    session = zenoh.open(conf)
    yield session
    session.close()


@pytest.fixture
def planner(router: zenoh.Session, port: int) -> Iterator[PlanService]:
    svc = PlanService.open(load("planner-client.json5", port), planner=plan, instance="real")
    yield svc
    svc.stop()


def test_client_may_plan_and_read_cycles(planner, port):
    with EosClient.open(load("user-client.json5", port)) as client:
        assert client.wait_for_instances(1) == ["real"]
        out = client.plan(PlanRequest(), goal_id="acl-ok")
        assert out.result["status"] == "success" and out.complete
        assert client.cancel("not-running") is False  # the cancel query goes through (nothing to cancel)


def test_client_cannot_impersonate_a_planner(planner, port):
    with (
        EosClient.open(load("user-client.json5", port)) as alice,
        zenoh.open(load("user-client.json5", port)) as rogue,
    ):
        alice.wait_for_instances(1)
        rogue_queries: queue.SimpleQueue[str] = queue.SimpleQueue()

        def rogue_answer(q: zenoh.Query) -> None:
            rogue_queries.put(str(q.key_expr))
            q.reply(
                q.key_expr, b'{"schema":1,"goal_id":"x","instance":"rogue","result":{"status":"success"}}'
            )

        pfx = alice.prefix
        # a fake instance (token + queryable), a queryable shadowing the real one, fake cycles
        fake_token = rogue.liveliness().declare_token(proto.instance_key(pfx, "fake"))
        fake_q = rogue.declare_queryable(proto.plan_key(pfx, "fake"), rogue_answer)
        shadow_q = rogue.declare_queryable(proto.plan_key(pfx, "real"), rogue_answer)
        seen: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        sub = alice.session.declare_subscriber(proto.goal_keys(pfx), lambda s: seen.put(s.payload.to_bytes()))
        time.sleep(0.5)
        rogue.put(proto.cycle_key(pfx, "victim"), b'{"seq":1,"record":{}}')

        assert alice.discover(timeout=0.5) == ["real"], "the rogue's liveliness token is visible"
        assert alice.instances() == ["real"]
        assert list(alice.session.get(proto.plan_key(pfx, "fake"), payload=b"{}", timeout=1.0)) == []
        # ask the real instance with target ALL: only the real service answers
        replies = list(
            alice.session.get(
                proto.plan_key(pfx, "real"),
                target=zenoh.QueryTarget.ALL,
                payload=proto.encode_request("acl-2", PlanRequest()),
                timeout=5.0,
            )
        )
        assert len(replies) == 1 and replies[0].ok is not None
        assert json.loads(replies[0].ok.payload.to_bytes())["instance"] == "real"
        time.sleep(0.3)
        assert rogue_queries.empty(), "a query reached the rogue queryable"
        cycles = []
        while not seen.empty():
            cycles.append(json.loads(seen.get()))
        assert all(m.get("instance") == "real" for m in cycles), "the rogue's put reached a subscriber"
        for entity in (sub, shadow_q, fake_q, fake_token):
            entity.undeclare()


def test_control_the_same_operations_by_a_planner_take_effect(planner, port):
    """Without the client restriction (user planner) the same rogue operations do reach alice."""
    with (
        EosClient.open(load("user-client.json5", port)) as alice,
        zenoh.open(load("planner-client.json5", port)) as insider,
    ):
        alice.wait_for_instances(1)
        token = insider.liveliness().declare_token(proto.instance_key(alice.prefix, "second"))
        seen: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        sub = alice.session.declare_subscriber(
            proto.goal_keys(alice.prefix), lambda s: seen.put(s.payload.to_bytes())
        )
        time.sleep(0.5)
        insider.put(proto.cycle_key(alice.prefix, "victim"), b'{"seq":1}')
        assert alice.wait_for_instances(2, timeout=3) == ["real", "second"]
        assert json.loads(seen.get(timeout=3)) == {"seq": 1}
        sub.undeclare()
        token.undeclare()


def test_unknown_user_cannot_join(router, port):
    conf = load("user-client.json5", port)
    conf.insert_json5("transport/auth/usrpwd/password", '"wrong"')
    with pytest.raises(zenoh.ZError):
        zenoh.open(conf)
