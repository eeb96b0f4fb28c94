"""The Parquet store: committed files, a manifest of done keys, repair after a killed driver."""

from __future__ import annotations

from pathlib import Path

import pytest

from eos_svc.batch import rows
from eos_svc.batch.expansion import PlanKey
from eos_svc.batch.spec import ValidateSpec
from eos_svc.batch.store import MANIFEST, DatasetStore, read_manifest, read_rows


def row(key: str) -> dict:
    plan_key = PlanKey(key, "label", 0, "hand3x3", 1, {"seed": 1}, "kinematic", ValidateSpec())
    return {**rows.key_columns(plan_key, "host:1"), **rows.empty_columns(rows.REFUSED, "x: y"), "task_s": 0.0}


def test_rows_written_are_read_back_and_their_keys_are_done(tmp_path: Path) -> None:
    with DatasetStore(tmp_path) as store:
        store.write([row("a"), row("b")])
        store.write([row("c")])
    assert read_rows(tmp_path).column("key").to_pylist() == ["a", "b", "c"]
    with DatasetStore(tmp_path) as store:
        assert store.done == {"a", "b", "c"}
        assert store.write([row("d")]).name == "part-000003.parquet"  # type: ignore[union-attr]


def test_a_key_written_already_is_refused(tmp_path: Path) -> None:
    with DatasetStore(tmp_path) as store:
        store.write([row("a")])
        with pytest.raises(ValueError, match="duplicate"):
            store.write([row("b"), row("a")])
        with pytest.raises(ValueError, match="duplicate"):
            store.write([row("c"), row("c")])
    assert read_rows(tmp_path).num_rows == 1


def test_a_file_never_committed_and_a_torn_manifest_line_are_undone(tmp_path: Path) -> None:
    with DatasetStore(tmp_path) as store:
        store.write([row("a")])
        store.write([row("b")])
    manifest = tmp_path / MANIFEST
    lines = manifest.read_text().splitlines(keepends=True)
    manifest.write_text(lines[0] + lines[1][:20])  # killed while appending the second line
    (tmp_path / "part-000009.parquet.tmp").write_bytes(b"half")  # killed while writing a file
    assert [e["file"] for e in read_manifest(tmp_path)] == ["part-000001.parquet"]
    with DatasetStore(tmp_path) as store:
        assert store.done == {"a"}
        assert sorted(p.name for p in tmp_path.glob("part-*")) == ["part-000001.parquet"]
        store.write([row("b")])
    assert read_rows(tmp_path).column("key").to_pylist() == ["a", "b"]


def test_one_driver_at_a_time(tmp_path: Path) -> None:
    with DatasetStore(tmp_path), pytest.raises(RuntimeError, match="in use"):
        DatasetStore(tmp_path)
