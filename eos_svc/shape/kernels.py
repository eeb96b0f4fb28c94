"""Nothing to load: the shape fit runs one numpy version and has no compiled kernels.

Kept only while the service (``service/server.py``) and ``eos experiment`` still call
:func:`load` / :func:`load_in_background`; both do nothing. Remove with those calls.
"""

from __future__ import annotations


def load() -> None:
    """Nothing to load."""


def load_in_background() -> None:
    """Nothing to load."""
