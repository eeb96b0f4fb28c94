"""PerHandCache: built once per owners and key, the same object afterwards, bounded, one build
when threads race, and never another object's value for a recycled id."""

from __future__ import annotations

import threading
import time

import pytest

from eos_svc.kinematics.hand_cache import PerHandCache


class Owner:
    pass


def test_built_once_per_owners_and_key_then_the_same_object():
    cache: PerHandCache[list[int]] = PerHandCache(keep=4)
    a, b = Owner(), Owner()
    builds: list[str] = []

    def build(tag: str) -> list[int]:
        builds.append(tag)
        return [len(builds)]

    first = cache.get((a,), lambda: build("a"))
    assert cache.get((a,), lambda: build("again")) is first
    assert cache.get((b,), lambda: build("b")) is not first
    assert cache.get((a,), lambda: build("a1"), "finger1") is not first  # another key
    assert builds == ["a", "b", "a1"]


def test_owners_are_compared_by_identity_not_only_by_id():
    cache: PerHandCache[str] = PerHandCache(keep=4)
    a, sweeps1, sweeps2 = Owner(), Owner(), Owner()
    assert cache.get((a, sweeps1), lambda: "one") == "one"
    assert cache.get((a, sweeps2), lambda: "two") == "two"
    # an entry whose kept owners are other objects at the same ids is rebuilt
    k = next(iter(cache._entries))
    cache._entries[k] = ((Owner(), Owner()), "stale")
    assert cache.get((a, sweeps1), lambda: "fresh") == "fresh"


def test_bounded_oldest_dropped_first():
    cache: PerHandCache[int] = PerHandCache(keep=2)
    owners = [Owner() for _ in range(3)]
    for i, o in enumerate(owners):
        cache.get((o,), lambda i=i: i)
    assert len(cache) == 2
    assert cache.get((owners[0],), lambda: 99) == 99  # dropped, rebuilt
    assert cache.get((owners[2],), lambda: -1) == 2  # kept
    with pytest.raises(ValueError, match="keep"):
        PerHandCache(keep=0)


def test_one_build_when_threads_race():
    cache: PerHandCache[object] = PerHandCache(keep=4)
    hand = Owner()
    builds: list[int] = []
    got: list[object] = []

    def build() -> object:
        builds.append(1)
        time.sleep(0.05)  # long enough for every thread to arrive while it builds
        return object()

    threads = [threading.Thread(target=lambda: got.append(cache.get((hand,), build))) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(builds) == 1 and len(got) == 6 and all(g is got[0] for g in got)
