"""Grasp memory for the learned sub-rating (paper §7): an SQLite file keyed by the postulated class
and d/h band, remembering the grasp that worked (the wrist relative to the centre, the finger
angles) and the tries and successes. Shared safely by processes: WAL journaling, a busy timeout,
every update one atomic UPSERT.
"""

from __future__ import annotations

import json
import math
import sqlite3
import threading
from dataclasses import dataclass
from pathlib import Path

from eos_svc.errors import ValidationError

#: width of a d/h size band
BAND_WIDTH = 0.1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS grasps (
    key TEXT PRIMARY KEY,
    shape TEXT NOT NULL,
    band INTEGER NOT NULL,
    tries INTEGER NOT NULL DEFAULT 0,
    successes INTEGER NOT NULL DEFAULT 0,
    offset TEXT,
    angles TEXT,
    grasp_cycles INTEGER,
    updated REAL NOT NULL DEFAULT (julianday('now'))
)
"""


def memory_key(shape: str, d_over_h: float) -> tuple[str, str, int]:
    """(key, shape, band) for a postulated class and estimated d/h."""
    if not math.isfinite(d_over_h) or d_over_h < 0:
        raise ValidationError("d_over_h", f"must be a finite ratio ≥ 0, got {d_over_h!r}")
    band = int(d_over_h / BAND_WIDTH)
    return f"{shape}/{band}", shape, band


@dataclass(frozen=True)
class RememberedGrasp:
    """A grasp that worked on objects of one ``key`` (``"<shape>/<band>"``): the ``tries`` that
    reached grasping and their ``successes``, the wrist's ``offset`` from the estimated centre (m,
    world), the finger ``angles`` at contact (rad) and the last success's ``grasp_cycles``."""

    key: str
    tries: int
    successes: int
    offset: tuple[float, float, float]
    angles: dict[str, float]
    grasp_cycles: int | None

    @property
    def reliability(self) -> float:
        """Laplace-smoothed success rate, (successes + 1) / (tries + 2): the learned sub-rating."""
        return (self.successes + 1.0) / (self.tries + 2.0)


class GraspMemory:
    """The SQLite-backed memory at ``path`` (created if missing; ``":memory:"``: a private one).
    Thread-safe (one connection per thread) and process-safe."""

    def __init__(self, path: str | Path) -> None:
        self.path = str(path)
        if self.path != ":memory:":
            Path(self.path).parent.mkdir(parents=True, exist_ok=True)
        self._local = threading.local()
        self._shared: sqlite3.Connection | None = None
        with self._connection() as db:
            db.execute(_SCHEMA)

    def _connection(self) -> sqlite3.Connection:
        if self.path == ":memory:":  # one private database: share the connection
            if self._shared is None:
                self._shared = sqlite3.connect(":memory:", check_same_thread=False, isolation_level=None)
            return self._shared
        db = getattr(self._local, "db", None)
        if db is None:
            db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
            db.execute("PRAGMA journal_mode=WAL")
            db.execute("PRAGMA busy_timeout=30000")
            self._local.db = db
        return db

    def recall(self, shape: str, d_over_h: float) -> RememberedGrasp | None:
        """The remembered successful grasp for this class and size band, if any."""
        key, _, _ = memory_key(shape, d_over_h)
        row = (
            self._connection()
            .execute(
                "SELECT key, tries, successes, offset, angles, grasp_cycles FROM grasps WHERE key = ?", (key,)
            )
            .fetchone()
        )
        if row is None or row[3] is None:
            return None
        return RememberedGrasp(
            key=row[0],
            tries=int(row[1]),
            successes=int(row[2]),
            offset=tuple(json.loads(row[3])),
            angles={k: float(v) for k, v in json.loads(row[4]).items()},
            grasp_cycles=None if row[5] is None else int(row[5]),
        )

    def record(
        self,
        shape: str,
        d_over_h: float,
        success: bool,
        offset: tuple[float, float, float] | None = None,
        angles: dict[str, float] | None = None,
        grasp_cycles: int | None = None,
    ) -> None:
        """Count one try for this key; on success remember its grasp (atomic UPSERT)."""
        key, shape, band = memory_key(shape, d_over_h)
        if success and (offset is None or angles is None):
            raise ValidationError(
                "offset, angles", "a successful grasp must say where the wrist and fingers were"
            )
        off = json.dumps([float(x) for x in offset]) if success and offset is not None else None
        ang = json.dumps({k: float(v) for k, v in angles.items()}) if success and angles is not None else None
        self._connection().execute(
            """
            INSERT INTO grasps (key, shape, band, tries, successes, offset, angles, grasp_cycles, updated)
            VALUES (?, ?, ?, 1, ?, ?, ?, ?, julianday('now'))
            ON CONFLICT(key) DO UPDATE SET
                tries = tries + 1,
                successes = successes + excluded.successes,
                offset = COALESCE(excluded.offset, offset),
                angles = COALESCE(excluded.angles, angles),
                grasp_cycles = COALESCE(excluded.grasp_cycles, grasp_cycles),
                updated = excluded.updated
            """,
            (key, shape, band, int(bool(success)), off, ang, grasp_cycles if success else None),
        )

    def entries(self) -> list[dict]:
        """Every row, for reports and tests."""
        rows = self._connection().execute(
            "SELECT key, shape, band, tries, successes, grasp_cycles FROM grasps ORDER BY key"
        )
        names = ("key", "shape", "band", "tries", "successes", "grasp_cycles")
        return [dict(zip(names, row, strict=True)) for row in rows]

    def close(self) -> None:
        """Close this thread's connection."""
        db = getattr(self._local, "db", None)
        if db is not None:
            db.close()
            self._local.db = None
        if self._shared is not None:
            self._shared.close()
            self._shared = None
