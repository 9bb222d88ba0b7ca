"""The result store of a study: one SQLite database in the study's folder, in WAL mode.

SQLite because each finished run must be committed at once and survive a ``kill -9``: a WAL
commit is atomic and durable after it returns, readers never block the writer, and it needs no
server and no dependency (Parquet parts would need pyarrow and one file per run). Rows are keyed
by the SHA-256 of the run's exact inputs, so a resumed study skips what is done. One study at a
time may write to a folder: an exclusive ``flock`` on ``.lock`` (released by the kernel when the
process dies, however it dies) refuses a second one with a clear error. The writer removes
``.lock`` when it closes the store (a finished run, Ctrl-C, SIGTERM, an error); only a process
killed outright (``kill -9``) leaves it, unlocked and harmless: the next writer takes it.

Readers (``eyelume report``) never take that lock and never write: :func:`read_rows` opens the
database read-only (SQLite ``mode=ro``), so it reports what is committed while a study is still
running, and falls back to ``immutable=1`` (the main file only, without the write-ahead log's
uncheckpointed pages) in a folder it cannot write to (SQLite's ``mode=ro`` needs to create the
WAL index there).

Another program holding the database's write lock (an SQLite browser in a transaction, a backup
tool) makes a commit wait: SQLite's busy timeout (5 s), then once more up to ``lock_timeout_s``
(60 s by default); then :class:`StoreLocked` — the study stops at once, keeps what it committed,
and ``--resume`` continues. A file that is not an SQLite database (or a damaged one) is a
:class:`~eyelume.errors.StoreError` naming it.
"""

from __future__ import annotations

import fcntl
import json
import math
import os
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np

from eyelume.errors import StoreError
from eyelume.json_files import dumps, finite_or_null

__all__ = [
    "LOCK_TIMEOUT_S",
    "ResultStore",
    "StoreBusy",
    "StoreLocked",
    "check_store",
    "read_rows",
]

#: The file a writer holds an exclusive ``flock`` on (module docstring); removed when it ends.
LOCK_FILE = ".lock"

#: Seconds a commit waits for another program's write lock before the study stops.
LOCK_TIMEOUT_S = 60.0
_FIRST_WAIT_S = 5.0

_COLUMNS = "key, idx, study, overrides, metrics, seconds"


class StoreBusy(StoreError, RuntimeError):
    """Another study is writing to this folder (a :class:`~eyelume.errors.StoreError`)."""


class StoreLocked(StoreError):
    """Another program held the database's write lock longer than the store waits."""


def _damaged(path: Path, exc: sqlite3.Error) -> StoreError:
    return StoreError(
        f"not a readable study store ({exc}): move it away or use another folder", file=path
    )


def _loads(text: str, flag: bool = False) -> dict:
    """A stored dict; the non-JSON tokens NaN and ±Infinity (a store written before the store
    refused them, or by another program) read as None (not a finite number) and, with
    ``flag``, listed under ``"non_finite"`` as :meth:`ResultStore.put` lists them."""
    value = json.loads(text)
    bad = _non_finite(value)
    if not bad:
        return value
    value = finite_or_null(value)
    if flag and isinstance(value, dict):
        value["non_finite"] = sorted({*value.get("non_finite", []), *bad})
    return value


def _finite(value):
    return value if isinstance(value, int | float) and math.isfinite(value) else None


def _as_rows(cursor) -> list[dict]:
    return [
        {
            "key": key,
            "index": idx,
            "study": study,
            "overrides": _loads(ov),
            "metrics": _loads(me, flag=True),
            "seconds": _finite(sec),
        }
        for key, idx, study, ov, me, sec in cursor
    ]


def _non_finite(value, name: str = "") -> list[str]:
    """The dotted names of the non-finite floats (NaN, ±inf) inside ``value``."""
    if isinstance(value, dict):
        return [n for k, v in value.items() for n in _non_finite(v, f"{name}{k}.")]
    if isinstance(value, list | tuple):
        return [n for i, v in enumerate(value) for n in _non_finite(v, f"{name}{i}.")]
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return [name.rstrip(".")]
    return []


class ResultStore:
    """Finished runs of one study folder (module docstring); the one writer."""

    def __init__(self, folder: str | Path, lock_timeout_s: float = LOCK_TIMEOUT_S) -> None:
        self.folder = Path(folder)
        self.path = self.folder / "results.sqlite"
        self.lock_timeout_s = float(lock_timeout_s)
        self.on_wait: Callable[[str], None] | None = None
        self.folder.mkdir(parents=True, exist_ok=True)
        self._lock = self._take_lock()
        self._lock.seek(0)
        self._lock.truncate()
        self._lock.write(str(os.getpid()))
        self._lock.flush()
        try:
            self.db = sqlite3.connect(self.path, isolation_level=None, timeout=_FIRST_WAIT_S)
            self._write("PRAGMA journal_mode=WAL")
            self._write("PRAGMA synchronous=NORMAL")
            self._write(
                "CREATE TABLE IF NOT EXISTS runs (key TEXT PRIMARY KEY, idx INTEGER, study TEXT, "
                "overrides TEXT, metrics TEXT, seconds REAL)"
            )
        except StoreError:
            self._unlock()
            raise
        except sqlite3.DatabaseError as exc:
            self._unlock()
            raise _damaged(self.path, exc) from None

    def _write(self, sql: str, args: tuple = ()) -> None:
        """Execute a write; while another program holds the lock, wait (module docstring)."""
        try:
            self.db.execute(sql, args)
            return
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) and "busy" not in str(exc):
                raise
        if self.on_wait:
            self.on_wait(
                f"{self.path}: another program holds the write lock; waiting up to "
                f"{self.lock_timeout_s:g} s"
            )
        self.db.execute(f"PRAGMA busy_timeout = {int(self.lock_timeout_s * 1000)}")
        try:
            self.db.execute(sql, args)
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) and "busy" not in str(exc):
                raise
            waited = _FIRST_WAIT_S + self.lock_timeout_s
            raise StoreLocked(
                f"another program held the write lock for over {waited:g} s; the study "
                "stopped, the runs committed before are kept: --resume continues",
                file=self.path,
            ) from None
        finally:
            self.db.execute(f"PRAGMA busy_timeout = {int(_FIRST_WAIT_S * 1000)}")

    def done(self) -> set[str]:
        """Keys of the finished runs."""
        return {k for (k,) in self.db.execute("SELECT key FROM runs")}

    def has(self, key: str) -> bool:
        """Whether the run ``key`` is finished (one indexed look-up: a dataset of a million
        pictures asks picture by picture instead of holding every key)."""
        return self.db.execute("SELECT 1 FROM runs WHERE key = ?", (key,)).fetchone() is not None

    def count(self, below: int | None = None) -> int:
        """How many runs are finished (those of plan index < ``below`` when given)."""
        if below is None:
            return int(self.db.execute("SELECT COUNT(*) FROM runs").fetchone()[0])
        sql = "SELECT COUNT(*) FROM runs WHERE idx < ?"
        return int(self.db.execute(sql, (int(below),)).fetchone()[0])

    def studies(self) -> set[str]:
        """Names of the studies that wrote here."""
        return {s for (s,) in self.db.execute("SELECT DISTINCT study FROM runs")}

    def put(
        self, key: str, idx: int, study: str, overrides: dict, metrics: dict, seconds: float
    ) -> None:
        """Commit one finished run (atomic, durable on return); StoreLocked when another
        program holds the write lock too long.

        The store holds strict JSON and finite numbers only: a non-finite override is refused
        (StoreError: a run key must name real inputs), a non-finite metric is stored as null
        and flagged — its name listed in the metrics' ``"non_finite"`` entry, so a reader tells
        "not a finite number" from "not measured" — and non-finite seconds as NULL."""
        bad = _non_finite(overrides)
        if bad:
            raise StoreError(
                f"run {idx}: override {bad[0]!r} = {overrides.get(bad[0])!r} is not a finite "
                "number; nothing stored",
                file=self.path,
            )
        flagged = _non_finite(metrics)
        if flagged:
            metrics = {**metrics, "non_finite": flagged}
        self._write(
            "INSERT OR REPLACE INTO runs VALUES (?, ?, ?, ?, ?, ?)",
            (key, idx, study, dumps(overrides, indent=None), dumps(metrics, indent=None),
             _finite(seconds)),
        )  # fmt: skip

    def rows(self) -> list[dict]:
        """Every finished run, in plan order."""
        return _as_rows(self.db.execute(f"SELECT {_COLUMNS} FROM runs ORDER BY idx"))

    def each_row(self):
        """Every finished run in plan order, one at a time (a generator over the database's
        cursor: the rows are never all in memory)."""
        cursor = self.db.execute(f"SELECT {_COLUMNS} FROM runs ORDER BY idx")
        for row in cursor:
            yield from _as_rows([row])

    def _take_lock(self):
        """The folder's ``.lock``, opened and held (``flock``, exclusive): StoreBusy while
        another process holds it. A holder removes the file before it lets go
        (:meth:`_unlock`), so a lock taken on a file that is no longer the folder's ``.lock``
        (removed between our open and our flock) is dropped and the new file taken instead:
        two writers never hold locks on two different files."""
        path = self.folder / LOCK_FILE
        while True:
            f = open(path, "a+")  # noqa: SIM115 - held for the run
            try:
                fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                f.close()
                raise StoreBusy(
                    f"{self.folder}: another eyelume run (study or dataset) is writing here; "
                    "wait for it or use another --out"
                ) from None
            try:
                if os.stat(path).st_ino == os.fstat(f.fileno()).st_ino:
                    return f
            except FileNotFoundError:
                pass
            f.close()

    def _unlock(self) -> None:
        """Remove ``.lock`` while still holding it, then let go (:meth:`_take_lock`): a
        finished or interrupted run leaves no lock file. Only ``kill -9`` (or a crash of the
        interpreter) leaves one; the kernel has released its lock, so it stops nobody and the
        next run takes it and removes it in turn."""
        try:
            (self.folder / LOCK_FILE).unlink(missing_ok=True)
        except OSError:  # a folder made read-only meanwhile: the file stays, unlocked
            pass
        fcntl.flock(self._lock, fcntl.LOCK_UN)
        self._lock.close()

    def close(self) -> None:
        self.db.close()
        self._unlock()


def read_rows(folder: str | Path) -> tuple[list[dict], str | None]:
    """(every committed run in plan order, a note or None), read without writing or locking:
    SQLite ``mode=ro``, or ``immutable=1`` where the folder cannot be written (the note says
    so: runs still in the write-ahead log are then missing). StoreError for a missing or
    damaged store."""
    return _read(
        folder, lambda db: _as_rows(db.execute(f"SELECT {_COLUMNS} FROM runs ORDER BY idx"))
    )


def check_store(folder: str | Path) -> int:
    """The number of committed runs of the store in ``folder``, read as :func:`read_rows`
    reads it but without loading the runs (memory does not grow with the store: what the
    commands check before a ``--resume``). StoreError for a missing or damaged store."""
    return _read(folder, lambda db: db.execute("SELECT count(*) FROM runs").fetchone()[0])[0]


def _read(folder, query):
    """(query(connection), note): :func:`read_rows`'s read-only opening of results.sqlite."""
    path = Path(folder) / "results.sqlite"
    if not path.is_file():
        raise StoreError("no results.sqlite (run `eyelume study` first)", file=Path(folder))
    uri = path.absolute().as_uri()
    frozen = (
        f"{uri}?immutable=1",
        f"{path.parent} cannot be written: read results.sqlite as it is (runs not yet "
        "checkpointed from results.sqlite-wal, if any, are not shown)",
    )
    attempts = [(f"{uri}?mode=ro", None), frozen]
    if _read_only_fs(path.parent) or not os.access(path.parent, os.W_OK):
        attempts = [frozen]
    last: sqlite3.Error | None = None
    for target, note in attempts:
        try:
            db = sqlite3.connect(target, uri=True, timeout=_FIRST_WAIT_S)
            try:
                answer = query(db)
            finally:
                db.close()
            return answer, note
        except sqlite3.OperationalError as exc:
            if "no such table" in str(exc):
                raise _damaged(path, exc) from None
            last = exc  # e.g. mode=ro cannot create the WAL index here: try immutable
        except sqlite3.DatabaseError as exc:
            raise _damaged(path, exc) from None
    raise _damaged(path, last) from None


def _read_only_fs(folder: Path) -> bool:
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except OSError:
        return False
