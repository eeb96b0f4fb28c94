"""Zenoh session configuration helpers (loopback peers by default, any config file otherwise)."""

from __future__ import annotations

import json
import socket
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import zenoh

#: default listening endpoint of ``eos serve``
DEFAULT_LISTEN = "tcp/127.0.0.1:7447"


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago (bind-port-0 trick)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def make_config(
    *,
    mode: str = "peer",
    listen: Sequence[str] = (),
    connect: Sequence[str] = (),
    lease_ms: int | None = None,
    base: str | Path | None = None,
) -> zenoh.Config:
    """A Zenoh configuration: a ``mode`` session (``peer``, ``client``, ``router``) with multicast
    scouting off, or the JSON5 file ``base``; ``listen``/``connect`` endpoints (e.g.
    ``"tcp/127.0.0.1:7447"``) and ``lease_ms`` (ms: a silent peer is dropped after it) override it."""
    if base is not None:
        conf = zenoh.Config.from_file(str(base))
    else:
        conf = zenoh.Config()
        conf.insert_json5("mode", json.dumps(mode))
        conf.insert_json5("scouting/multicast/enabled", "false")
    if listen:
        conf.insert_json5("listen/endpoints", json.dumps(list(listen)))
    if connect:
        conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    if lease_ms is not None:
        conf.insert_json5("transport/link/tx/lease", str(int(lease_ms)))
        conf.insert_json5("transport/link/tx/keep_alive", "4")
    return conf


def loopback(port: int) -> str:
    """The TCP endpoint ``tcp/127.0.0.1:<port>``."""
    return f"tcp/127.0.0.1:{port}"


def direct_callback(callback: Callable[[Any], None], drop: Callable[[], None] | None = None) -> Any:
    """A Zenoh callback handler run directly in Zenoh's own thread, for callbacks that never
    block nor call Zenoh (the default runs in a Python thread started per query, ≈ 1 ms each,
    and hangs interpreter shutdown while declared; ``docs/service.md``, "Server")."""
    try:
        return zenoh.handlers.Callback(callback, drop, indirect=False)
    except TypeError:  # pragma: no cover - a zenoh-python without the option
        return zenoh.handlers.Callback(callback, drop)
