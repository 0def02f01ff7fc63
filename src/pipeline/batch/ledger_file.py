"""The ledger's file (:mod:`pipeline.batch.ledger`): its schema and identity, how a new one
is made and an existing one is told to be a ledger, and the errors of both.

A new ledger is made whole beside its place and hard-linked there, so that no process ever
sees a ledger file without its tables: an existing file that is empty (truncated, ``>
ledger.sqlite``), not SQLite, another application's SQLite database or a ledger of a newer
schema is refused with a :class:`LedgerError` saying what to do, never taken for a new
ledger (its history and fingerprints would be lost, and every well run again unsaid). The
file made beside it, ``.ledger.sqlite.<pid>.<host>.<hex>.new``, is removed once linked; one a
batch killed meanwhile left is removed by the next opening of the ledger once provably dead:
its process, on this host, no longer runs (:func:`pipeline.processes.owner_alive`), or, made
on another host (or unnamed, by an earlier version), it is older than :data:`LEFTOVER_AGE_S`.

Each ledger has an identity, a random UUID made with it (a ledger of an earlier version gets
one when it is first opened): a run is known by (ledger id, run id), as run ids are each
ledger's own row ids and two ledgers may publish into one output directory.
"""

from __future__ import annotations

import contextlib
import glob
import os
import socket
import sqlite3
import time
import uuid
from pathlib import Path

from pipeline.errors import GyropipeError
from pipeline.processes import owner_alive

from . import filestate

SCHEMA_VERSION = 1
BUSY_TIMEOUT_MS = 60_000
LEFTOVER_AGE_S = 3600.0
"""Age, s, past which a ledger half made by a process on another host is dead (one is
made in milliseconds; a process elsewhere cannot be asked whether it runs)."""
ASIDE_SUFFIXES = (".new", ".new-wal", ".new-shm", ".new-journal")
"""The endings of the files of a ledger made beside its place (SQLite's beside its own)."""

SCHEMA = """
CREATE TABLE IF NOT EXISTS batches (
    id INTEGER PRIMARY KEY,
    key TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('running', 'finished', 'interrupted')),
    pipeline_file TEXT NOT NULL,
    pipeline_sha256 TEXT NOT NULL,
    out_dir TEXT NOT NULL,
    options TEXT NOT NULL,
    host TEXT NOT NULL,
    pid INTEGER NOT NULL,
    started REAL NOT NULL,
    heartbeat REAL NOT NULL,
    finished REAL,
    counts TEXT NOT NULL DEFAULT '{}'
);
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY,
    well TEXT NOT NULL,
    batch INTEGER NOT NULL REFERENCES batches(id),
    status TEXT NOT NULL CHECK (status IN ('running', 'done', 'failed', 'interrupted')),
    reasons TEXT NOT NULL,
    fingerprint TEXT NOT NULL,
    versions TEXT NOT NULL,
    out_dir TEXT NOT NULL,
    started REAL NOT NULL,
    finished REAL,
    inputs TEXT NOT NULL DEFAULT '{}',
    outputs TEXT NOT NULL DEFAULT '[]',
    calibration TEXT NOT NULL DEFAULT '[]',
    drift TEXT,
    error TEXT,
    note TEXT,
    wall_time_s REAL,
    run_time_s REAL,
    process_time_s REAL,
    peak_rss_bytes INTEGER,
    worker TEXT
);
CREATE UNIQUE INDEX IF NOT EXISTS one_running_run_per_well ON runs (well)
    WHERE status = 'running';
CREATE INDEX IF NOT EXISTS runs_by_well ON runs (well, id);
CREATE INDEX IF NOT EXISTS batches_by_key ON batches (key, id);
CREATE TABLE IF NOT EXISTS publications (
    run INTEGER PRIMARY KEY,
    marker_sha256 TEXT NOT NULL,
    manifest_sha256 TEXT NOT NULL,
    figures TEXT
);
CREATE TABLE IF NOT EXISTS ledger (
    one INTEGER PRIMARY KEY CHECK (one = 1),
    id TEXT NOT NULL
);
"""
LEDGER_TABLES = frozenset({"batches", "runs"})
"""tables every ledger has had: a database without them is not a ledger"""
ADDED_COLUMNS = (("runs", "drift", "TEXT"),)
"""(table, column, type) of the columns an earlier version's tables lack: each is added
null, which reads as not recorded (a row an earlier version wrote, or writes still: the
schema version is unchanged, as that version reads and writes the table as before)"""

ADVICE = {
    "SQLITE_FULL": "its file system is full: free space there (or give --ledger on another "
    "file system), then run the same command again: it resumes",
    "SQLITE_READONLY": "it cannot be written: make the file and its directory writable (or "
    "give --ledger elsewhere)",
    "SQLITE_CANTOPEN": "it cannot be opened: check that its directory exists and is writable",
    "SQLITE_PERM": "permission denied: make the file and its directory writable",
    "SQLITE_BUSY": f"another process held it locked for more than {BUSY_TIMEOUT_MS // 1000} s: "
    "run again once that process is done",
    "SQLITE_LOCKED": "it is locked by another connection: run again once that is done",
    "SQLITE_NOTADB": "the file is not a gyropipe ledger: give the right --ledger, or move the "
    "file away (a new ledger starts an empty run history)",
    "SQLITE_CORRUPT": "the file is damaged: restore it from a copy, or move it away (a new "
    "ledger starts an empty run history)",
    "SQLITE_IOERR_SHMSIZE": "its file system is full: free space there, then run the same "
    "command again: it resumes",
    "SQLITE_IOERR": "an I/O error writing it (its file system full or failing?): free space or "
    "check the disk, then run the same command again: it resumes",
}
"""What to do, by SQLite's primary result code (``sqlite3.Error.sqlite_errorname``)."""
GONE = (
    "the file was removed or replaced since it was opened; the runs recorded since are lost: "
    "restore it (or start again with a new --out)"
)
EMPTY = (
    "the file is empty (0 bytes: truncated?), so the run history and the fingerprints it "
    "held are lost; restore it from a copy, or remove it to start a new ledger (every well "
    "then runs again)"
)


class LedgerError(GyropipeError):
    """The ledger cannot be read or written (module docstring of
    :mod:`pipeline.batch.ledger`): names the ledger file, what was being done, SQLite's
    reason and what to do."""

    def __init__(
        self, path: Path, doing: str, cause: sqlite3.Error | OSError | UnicodeDecodeError | str
    ) -> None:
        self.path = path
        if isinstance(cause, str):
            reason = cause
        elif isinstance(cause, UnicodeDecodeError):  # SQLite quoting a damaged name
            reason = (
                f"SQLite's message is not text (the file is damaged?); {ADVICE['SQLITE_CORRUPT']}"
            )
        else:
            name = getattr(cause, "sqlite_errorname", None) or ""
            primary = "_".join(name.split("_")[:2])
            advice = ADVICE.get(name) or ADVICE.get(primary, "check the file and its file system")
            reason = f"{cause}{f' ({name})' if name else ''}; {advice}"
        super().__init__(f"ledger {path}: cannot {doing}: {reason}")


def make_ledger(path: Path) -> None:
    """Make a new ledger at ``path`` if there is no file there (module docstring); one made
    there meanwhile by another process is left as it is, the ones killed batches left half
    made beside it removed. Raises :class:`LedgerError` if an existing file there is empty."""
    remove_leftovers(path)
    try:
        if path.stat().st_size == 0:
            raise LedgerError(path, "open it", EMPTY)
        return
    except FileNotFoundError:
        pass
    except OSError as exc:
        raise LedgerError(path, "open it", exc) from None
    aside = path.with_name(  # unique on every host
        f".{path.name}.{os.getpid()}.{socket.gethostname()}.{uuid.uuid4().hex}.new"
    )
    try:
        with contextlib.closing(sqlite3.connect(aside, isolation_level=None)) as db:
            db.execute("PRAGMA journal_mode = WAL")
            db.execute("BEGIN IMMEDIATE")
            migrate(db, path)
            db.execute("COMMIT")
        _put_in_place(aside, path)
    except (sqlite3.Error, OSError) as exc:
        raise LedgerError(path, "open it", exc) from None
    finally:
        for leftover in (aside, *(aside.with_name(aside.name + s) for s in ("-wal", "-shm"))):
            with contextlib.suppress(OSError):
                leftover.unlink()


def remove_leftovers(path: Path) -> list[Path]:
    """Remove the files of ledgers made beside ``path`` whose maker is provably dead (module
    docstring); returns them. A file that cannot be removed is left."""
    removed = []
    prefix = f".{path.name}."
    for entry in path.parent.glob(glob.escape(prefix) + "*.new*"):
        stem = next((entry.name[: -len(s)] for s in ASIDE_SUFFIXES if entry.name.endswith(s)), "")
        pid, _, rest = stem[len(prefix) :].partition(".")
        host = rest.rpartition(".")[0]
        try:
            if pid.isdigit() and host == socket.gethostname():
                dead = not owner_alive(int(pid), entry)
            else:
                dead = time.time() - entry.stat().st_mtime > LEFTOVER_AGE_S
            if stem and dead:
                entry.unlink()
                removed.append(entry)
        except OSError:
            continue
    return removed


def _put_in_place(aside: Path, path: Path) -> None:
    """Link the ledger made ``aside`` at ``path`` unless one is there (another batch made
    it meanwhile: that one is the ledger); on a file system without hard links (FAT, some
    SMB mounts), renamed there if there is still none."""
    try:
        os.link(aside, path)
    except FileExistsError:
        pass
    except OSError:
        if not path.exists():
            os.rename(aside, path)


def check(db: sqlite3.Connection, path: Path) -> None:
    """Refuse an existing file open in ``db`` that is not a ledger this version can use —
    another application's database, a newer schema — with a :class:`LedgerError` naming
    ``path``; read before anything is written to it (not even its journal mode)."""
    version = db.execute("PRAGMA user_version").fetchone()[0]
    if version > SCHEMA_VERSION:
        raise LedgerError(
            path,
            "open it",
            f"its schema is version {version}, made by a newer gyropipe; this one reads "
            f"version {SCHEMA_VERSION}: use that gyropipe (or give another --ledger)",
        )
    tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    if version not in (0, SCHEMA_VERSION) or not LEDGER_TABLES.issubset(tables):
        raise LedgerError(
            path,
            "open it",
            "it is an SQLite database, not a gyropipe ledger (no tables batches and runs); "
            f"{ADVICE['SQLITE_NOTADB']}",
        )


def migrate(db: sqlite3.Connection, path: Path) -> str:
    """Bring the ledger ``path`` open in ``db`` (inside a write transaction) to this
    version's schema — the tables, indexes and columns (:data:`ADDED_COLUMNS`) an earlier
    version did not have are made, and its identity where it has none — and return its
    identity."""
    for statement in (SCHEMA + ";" + filestate.SCHEMA).split(";"):
        if statement.strip():
            db.execute(statement)
    for table, column, kind in ADDED_COLUMNS:
        if column not in {r[1] for r in db.execute(f"PRAGMA table_info({table})")}:
            db.execute(f"ALTER TABLE {table} ADD COLUMN {column} {kind}")
    db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
    db.execute("INSERT OR IGNORE INTO ledger (one, id) VALUES (1, ?)", (str(uuid.uuid4()),))
    found = db.execute("SELECT id FROM ledger").fetchone()[0]
    if not isinstance(found, str) or not found:
        raise LedgerError(path, "open it", f"its identity is damaged; {ADVICE['SQLITE_CORRUPT']}")
    return found
