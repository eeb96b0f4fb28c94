"""The grasp memory: SQLite, survives restarts, consistent under concurrent writers."""

from __future__ import annotations

import multiprocessing as mp

import pytest

from eos_svc.agents.memory import GraspMemory, memory_key


def test_key_bands():
    assert memory_key("sphere", 0.53) == ("sphere/5", "sphere", 5)
    assert memory_key("sphere", 0.59)[0] == memory_key("sphere", 0.5)[0]
    assert memory_key("cylinder", 0.53)[0] != memory_key("sphere", 0.53)[0]
    with pytest.raises(ValueError, match="d_over_h"):
        memory_key("sphere", float("nan"))


def test_record_and_recall_survive_a_restart(tmp_path):
    path = tmp_path / "memory.sqlite"
    memory = GraspMemory(path)
    assert memory.recall("sphere", 0.5) is None
    memory.record("sphere", 0.5, False)
    assert memory.recall("sphere", 0.5) is None  # a failure alone remembers no grasp
    memory.record("sphere", 0.52, True, (0.1, 0.0, 0.0), {"finger1": 0.2}, 12)
    memory.close()
    again = GraspMemory(path)
    entry = again.recall("sphere", 0.55)
    assert entry is not None
    assert (entry.tries, entry.successes) == (2, 1)
    assert entry.offset == (0.1, 0.0, 0.0) and entry.angles == {"finger1": 0.2}
    assert entry.reliability == pytest.approx(0.5)
    assert again.recall("sphere", 0.65) is None


def test_success_requires_the_grasp():
    memory = GraspMemory(":memory:")
    with pytest.raises(ValueError, match="offset"):
        memory.record("sphere", 0.5, True)


def _writer(path: str, n: int, success: bool) -> None:
    memory = GraspMemory(path)
    for i in range(n):
        memory.record(
            "box",
            0.4,
            success,
            (0.0, 0.0, float(i)) if success else None,
            {"finger1": 0.1} if success else None,
            5,
        )
    memory.close()


def test_concurrent_processes_lose_no_count(tmp_path):
    path = str(tmp_path / "shared.sqlite")
    GraspMemory(path).close()
    ctx = mp.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(path, 40, i % 2 == 0)) for i in range(4)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    entry = GraspMemory(path).recall("box", 0.4)
    assert entry is not None
    assert entry.tries == 160 and entry.successes == 80
