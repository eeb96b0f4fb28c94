"""A batch's output directory: Parquet files of finished rows and a manifest of done keys.

Layout of the directory::

    manifest.jsonl         one line per committed file: {"file": ..., "rows": n, "keys": [...]}
    part-000001.parquet    rows, in the order they finished (schema: :data:`SCHEMA`)
    part-000002.parquet    ...

A file is committed in three steps: written as ``part-N.parquet.tmp`` and synced, renamed to
``part-N.parquet``, then its line appended to the manifest and synced. The manifest line is the
commit: on opening, a torn last line is cut off and every part file the manifest does not name
(a driver killed between the steps) is removed, so its rows are planned again and no key is ever
in two committed files. One driver at a time: the directory is locked while a store is open.
"""

from __future__ import annotations

import fcntl
import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

MANIFEST = "manifest.jsonl"
LOCK = ".lock"

_VECTOR = pa.list_(pa.float64())
#: the columns of every row (see :mod:`eos_svc.batch.rows`; SI units, times in s)
SCHEMA = pa.schema(
    [
        ("key", pa.string()),
        ("label", pa.string()),
        ("condition", pa.int64()),
        ("hand", pa.string()),
        ("seed", pa.int64()),
        ("world", pa.string()),
        ("request", pa.string()),  # JSON: PlanRequest.to_dict()
        ("status", pa.string()),
        ("reason", pa.string()),
        ("good_grasp", pa.bool_()),
        ("force_closure", pa.bool_()),
        ("epsilon", pa.float64()),
        ("friction", pa.float64()),
        ("wrist_pose", _VECTOR),  # the wrist joints of q_final: x, y, z (m), roll, pitch, yaw (rad)
        ("q_final", _VECTOR),  # the whole hand configuration (the hand model's joint order)
        (
            "contacts",
            pa.list_(
                pa.struct(
                    [
                        ("finger", pa.string()),
                        ("touching", pa.bool_()),
                        ("distance_m", pa.float64()),
                        ("point", _VECTOR),  # world frame, m
                        ("normal", _VECTOR),
                    ]
                )
            ),
        ),
        ("cycles", pa.int64()),
        ("cycles_per_stage", pa.string()),  # JSON: stage -> cycles
        ("final_stage", pa.string()),
        ("validated", pa.bool_()),
        ("held", pa.bool_()),
        ("validation_reason", pa.string()),
        ("max_displacement_m", pa.float64()),
        ("validation", pa.string()),  # JSON: GraspValidation.to_dict()
        ("plan_s", pa.float64()),
        ("validation_s", pa.float64()),
        ("task_s", pa.float64()),
        ("worker", pa.string()),  # host:pid of the worker that planned it
    ]
)


class DatasetStore:
    """The output directory of one batch, open for writing (a context manager).

    Args:
        root: the directory (created if missing).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        self._lock = open(self.root / LOCK, "w")  # noqa: SIM115 - held while the store is open
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as exc:
            self._lock.close()
            raise RuntimeError(f"{self.root} is in use by another batch (its lock {LOCK} is held)") from exc
        self.entries = read_manifest(self.root, repair=True)
        self.done: set[str] = {k for entry in self.entries for k in entry["keys"]}
        named = {entry["file"] for entry in self.entries}
        for path in self.root.glob("part-*.parquet*"):
            if path.name not in named:  # written but never committed: its rows are planned again
                path.unlink()
        self._next = 1 + max((int(e["file"][5:11]) for e in self.entries), default=0)

    def __enter__(self) -> DatasetStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Release the directory."""
        if not self._lock.closed:
            fcntl.flock(self._lock, fcntl.LOCK_UN)
            self._lock.close()

    def write(self, batch: list[dict[str, Any]]) -> Path | None:
        """Commit ``batch`` (rows of keys not done yet) as one Parquet file; its path.

        Raises:
            ValueError: a row whose key is done already, or a key twice in ``batch``.
        """
        if not batch:
            return None
        keys = [row["key"] for row in batch]
        if len(set(keys)) != len(keys) or self.done.intersection(keys):
            raise ValueError("a row whose key is written already: refused, it would be a duplicate")
        name = f"part-{self._next:06d}.parquet"
        final = self.root / name
        tmp = final.with_name(name + ".tmp")
        table = pa.Table.from_pylist(batch, schema=SCHEMA)
        with open(tmp, "wb") as f:
            pq.write_table(table, f)
            f.flush()
            os.fsync(f.fileno())
        tmp.rename(final)
        entry = {"file": name, "rows": len(batch), "keys": keys}
        with open(self.root / MANIFEST, "a", encoding="utf-8") as f:
            f.write(json.dumps(entry) + "\n")
            f.flush()
            os.fsync(f.fileno())
        _sync_dir(self.root)
        self.entries.append(entry)
        self.done.update(keys)
        self._next += 1
        return final


def read_manifest(root: str | Path, repair: bool = False) -> list[dict[str, Any]]:
    """The committed entries of a directory's manifest (none if it has none).

    A last line without its newline (a driver killed while appending it) is not committed; with
    ``repair`` it is cut off the file.
    """
    path = Path(root) / MANIFEST
    if not path.exists():
        return []
    text = path.read_text(encoding="utf-8")
    complete, _, torn = text.rpartition("\n")
    if torn and repair:
        with open(path, "r+", encoding="utf-8") as f:
            f.truncate(len(complete) + 1 if complete else 0)
    return [json.loads(line) for line in complete.splitlines() if line.strip()]


def read_rows(root: str | Path, columns: Iterable[str] | None = None) -> pa.Table:
    """Every committed row of a batch directory, as one table (the manifest's files, in order)."""
    files = [Path(root) / e["file"] for e in read_manifest(root)]
    cols = None if columns is None else list(columns)
    if not files:
        return SCHEMA.empty_table() if cols is None else SCHEMA.empty_table().select(cols)
    return pa.concat_tables(pq.read_table(f, columns=cols, schema=SCHEMA) for f in files)


def _sync_dir(path: Path) -> None:
    """Make the directory's entries (the rename) durable."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
