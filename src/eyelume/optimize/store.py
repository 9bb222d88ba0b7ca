"""The result store of a study: one SQLite database in the study's folder, in WAL mode.

SQLite because each finished run must be committed at once and survive a ``kill -9``: a WAL
commit is atomic and durable after it returns, readers never block the writer, and it needs no
server and no dependency (Parquet parts would need pyarrow and one file per run). Rows are keyed
by the SHA-256 of the run's exact inputs, so a resumed study skips what is done. One study at a
time may write to a folder: an exclusive ``flock`` on ``.lock`` (released by the kernel when the
process dies, however it dies) refuses a second one with a clear error.
"""

from __future__ import annotations

import fcntl
import json
import os
import sqlite3
from pathlib import Path

from eyelume.errors import StoreError

__all__ = ["ResultStore", "StoreBusy"]


class StoreBusy(StoreError, RuntimeError):
    """Another study is writing to this folder (a :class:`~eyelume.errors.StoreError`)."""


class ResultStore:
    """Finished runs of one study folder (module docstring)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self._lock = open(self.folder / ".lock", "a+")  # noqa: SIM115 - held for the run
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            raise StoreBusy(
                f"{self.folder}: another study is writing here; wait for it or use another --out"
            ) from None
        self._lock.seek(0)
        self._lock.truncate()
        self._lock.write(str(os.getpid()))
        self._lock.flush()
        self.db = sqlite3.connect(self.folder / "results.sqlite", isolation_level=None)
        self.db.execute("PRAGMA journal_mode=WAL")
        self.db.execute("PRAGMA synchronous=NORMAL")
        self.db.execute(
            "CREATE TABLE IF NOT EXISTS runs (key TEXT PRIMARY KEY, idx INTEGER, study TEXT, "
            "overrides TEXT, metrics TEXT, seconds REAL)"
        )

    def done(self) -> set[str]:
        """Keys of the finished runs."""
        return {k for (k,) in self.db.execute("SELECT key FROM runs")}

    def studies(self) -> set[str]:
        """Names of the studies that wrote here."""
        return {s for (s,) in self.db.execute("SELECT DISTINCT study FROM runs")}

    def put(
        self, key: str, idx: int, study: str, overrides: dict, metrics: dict, seconds: float
    ) -> None:
        """Commit one finished run (atomic, durable on return)."""
        self.db.execute(
            "INSERT OR REPLACE INTO runs VALUES (?, ?, ?, ?, ?, ?)",
            (key, idx, study, json.dumps(overrides), json.dumps(metrics), seconds),
        )

    def rows(self) -> list[dict]:
        """Every finished run, in plan order."""
        out = []
        for key, idx, study, ov, me, sec in self.db.execute(
            "SELECT key, idx, study, overrides, metrics, seconds FROM runs ORDER BY idx"
        ):
            out.append(
                {
                    "key": key,
                    "index": idx,
                    "study": study,
                    "overrides": json.loads(ov),
                    "metrics": json.loads(me),
                    "seconds": sec,
                }
            )
        return out

    def close(self) -> None:
        self.db.close()
        fcntl.flock(self._lock, fcntl.LOCK_UN)
        self._lock.close()
