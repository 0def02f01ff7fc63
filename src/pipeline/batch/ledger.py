"""The run ledger: an SQLite database recording every batch and every well run.

Consistency with several batches on one ledger (processes on one or more machines):

- WAL journal, ``synchronous=FULL`` (a committed row survives a power cut), a busy timeout,
  and every change in one ``BEGIN IMMEDIATE`` transaction;
- a well is *claimed* by inserting its ``running`` run row; a unique partial index allows
  one ``running`` row per well, and the claim decides run-or-skip inside the same
  transaction, so two batches never run one well at the same time and never both run it
  when one of them would skip it;
- a claim belongs to its batch process, which refreshes a heartbeat; a claim whose batch
  process is gone (same host: its pid no longer exists; any host: no heartbeat for
  :data:`LEASE_S`) is settled by the next batch that meets it: ``done`` if the run had
  published its complete outputs before the process died (``batch.json`` names the run),
  else ``interrupted``;
- a run is marked ``done`` only after its outputs are published and on disk.

Only the batch process opens the ledger; workers never do.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sqlite3
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .fingerprint import Fingerprint
from .jobs import BatchConfigError
from .policy import Run, Skip, WellState
from .publish import read_published
from .records import BatchRow, RunRow, rejection
from .worker import WellOutcome

SCHEMA_VERSION = 1
LEASE_S = 60.0
"""A batch whose heartbeat is older than this is presumed dead (heartbeat every LEASE_S/6)."""
BUSY_TIMEOUT_MS = 60_000

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
"""

JSON_RUN_COLUMNS = ("reasons", "versions", "inputs", "outputs", "calibration")


@dataclass(frozen=True)
class Claimed:
    run_id: int
    reasons: list[str]


@dataclass(frozen=True)
class Skipped:
    reason: str


@dataclass(frozen=True)
class Busy:
    """Another live batch holds the well."""

    batch: int
    host: str
    pid: int


Decide = Callable[[WellState], Run | Skip]


class Ledger:
    """An open ledger file (module docstring)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._db = sqlite3.connect(path, timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None)
            self._db.row_factory = sqlite3.Row
            self._db.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
            self._db.execute("PRAGMA journal_mode = WAL")
            self._db.execute("PRAGMA synchronous = FULL")
            self._db.execute("PRAGMA foreign_keys = ON")
            with self._write():
                version = self._db.execute("PRAGMA user_version").fetchone()[0]
                if version not in (0, SCHEMA_VERSION):
                    raise BatchConfigError(
                        f"{path}: ledger schema version {version}, this gyropipe uses "
                        f"{SCHEMA_VERSION}"
                    )
                for statement in SCHEMA.split(";"):
                    if statement.strip():
                        self._db.execute(statement)
                self._db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
        except sqlite3.DatabaseError as exc:
            raise BatchConfigError(f"{path}: not a usable ledger: {exc}") from None

    def close(self) -> None:
        self._db.close()

    @contextlib.contextmanager
    def _write(self) -> Iterator[None]:
        """One write transaction, taken before any read (``BEGIN IMMEDIATE``)."""
        self._db.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            self._db.execute("ROLLBACK")
            raise
        self._db.execute("COMMIT")

    # batches -----------------------------------------------------------------------------

    def start_batch(
        self,
        key: str,
        pipeline_file: str,
        pipeline_sha256: str,
        out_dir: Path,
        options: dict[str, Any],
    ) -> BatchRow:
        now = time.time()
        with self._write():
            cursor = self._db.execute(
                "INSERT INTO batches (key, status, pipeline_file, pipeline_sha256, out_dir, "
                "options, host, pid, started, heartbeat) "
                "VALUES (?, 'running', ?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    key,
                    pipeline_file,
                    pipeline_sha256,
                    str(out_dir),
                    json.dumps(options, sort_keys=True),
                    socket.gethostname(),
                    os.getpid(),
                    now,
                    now,
                ),
            )
        batch = self.batch(int(cursor.lastrowid or 0))
        assert batch is not None
        return batch

    def heartbeat(self, batch_id: int) -> None:
        with self._write():
            self._db.execute(
                "UPDATE batches SET heartbeat = ? WHERE id = ?", (time.time(), batch_id)
            )

    def end_batch(self, batch_id: int, status: str, counts: dict[str, int]) -> None:
        """Close a batch (finished or interrupted); its runs still claimed become interrupted."""
        now = time.time()
        with self._write():
            self._db.execute(
                "UPDATE batches SET status = ?, finished = ?, heartbeat = ?, counts = ? "
                "WHERE id = ?",
                (status, now, now, json.dumps(counts), batch_id),
            )
            for row in self._db.execute(
                "SELECT * FROM runs WHERE batch = ? AND status = 'running'", (batch_id,)
            ).fetchall():
                self._settle(_run(row))

    def batch(self, batch_id: int) -> BatchRow | None:
        row = self._db.execute("SELECT * FROM batches WHERE id = ?", (batch_id,)).fetchone()
        return _batch(row) if row is not None else None

    def batches(self) -> list[BatchRow]:
        return [_batch(r) for r in self._db.execute("SELECT * FROM batches ORDER BY id")]

    def sweep(self) -> list[BatchRow]:
        """Mark batches whose process is gone as interrupted and settle their claimed runs
        (module docstring). Returns the batches swept."""
        swept = []
        with self._write():
            for row in self._db.execute(
                "SELECT * FROM batches WHERE status = 'running'"
            ).fetchall():
                batch = _batch(row)
                if not alive(batch):
                    self._interrupt(batch)
                    swept.append(batch)
        return swept

    def resume_since(self, key: str, batch_id: int) -> int | None:
        """The first batch of the trailing chain of interrupted batches with ``key`` before
        ``batch_id`` (the same command killed, possibly several times), if any."""
        since = None
        for row in self._db.execute(
            "SELECT id, status FROM batches WHERE key = ? AND id < ? ORDER BY id DESC",
            (key, batch_id),
        ):
            if row["status"] != "interrupted":
                break
            since = int(row["id"])
        return since

    # runs --------------------------------------------------------------------------------

    def claim(
        self,
        well: str,
        batch: BatchRow,
        fingerprint: Fingerprint,
        versions: dict[str, Any],
        out_dir: Path,
        decide: Decide,
    ) -> Claimed | Skipped | Busy:
        """Atomically: settle a dead claim on ``well``, decide, and claim it if it runs."""
        with self._write():
            held = self._db.execute(
                "SELECT batch FROM runs WHERE well = ? AND status = 'running'", (well,)
            ).fetchone()
            if held is not None:
                owner = self.batch(int(held["batch"]))
                if owner is not None and alive(owner):
                    return Busy(owner.id, owner.host, owner.pid)
                if owner is not None:
                    self._interrupt(owner)
            decision = decide(self._state(well))
            if isinstance(decision, Skip):
                return Skipped(decision.reason)
            cursor = self._db.execute(
                "INSERT INTO runs (well, batch, status, reasons, fingerprint, versions, out_dir, "
                "started) VALUES (?, ?, 'running', ?, ?, ?, ?, ?)",
                (
                    well,
                    batch.id,
                    json.dumps(decision.reasons),
                    fingerprint.to_json(),
                    json.dumps(versions, sort_keys=True),
                    str(out_dir),
                    time.time(),
                ),
            )
            return Claimed(int(cursor.lastrowid or 0), decision.reasons)

    def finish(
        self,
        outcome: WellOutcome,
        error: str | None = None,
        fingerprint: Fingerprint | None = None,
    ) -> None:
        """Record a worker's outcome (``error`` overrides a done outcome that the batch
        process found inconsistent); a done run whose survey failed acceptance is noted
        ``rejected: …`` (:attr:`RunRow.verdict`). ``fingerprint``, when given, replaces the
        claim's (it adds the files the run read through parameters)."""
        status = "failed" if error or outcome.status != "done" else "done"
        manifest = outcome.manifest
        with self._write():
            self._db.execute(
                "UPDATE runs SET status = ?, finished = ?, inputs = ?, outputs = ?, "
                "calibration = ?, error = ?, note = ?, wall_time_s = ?, run_time_s = ?, "
                "process_time_s = ?, peak_rss_bytes = ?, worker = ?, "
                "fingerprint = COALESCE(?, fingerprint) WHERE id = ?",
                (
                    status,
                    time.time(),
                    json.dumps(manifest.get("inputs", {})),
                    json.dumps(manifest.get("outputs", [])),
                    json.dumps(outcome.calibration),
                    error or outcome.error,
                    rejection(manifest) if status == "done" else None,
                    outcome.wall_time_s,
                    outcome.run_time_s,
                    outcome.process_time_s,
                    outcome.peak_rss_bytes or None,
                    outcome.worker or None,
                    fingerprint.to_json() if fingerprint is not None else None,
                    outcome.run_id,
                ),
            )

    def run(self, run_id: int) -> RunRow | None:
        row = self._db.execute("SELECT * FROM runs WHERE id = ?", (run_id,)).fetchone()
        return _run(row) if row is not None else None

    def history(self, well: str) -> list[RunRow]:
        return [
            _run(r)
            for r in self._db.execute("SELECT * FROM runs WHERE well = ? ORDER BY id", (well,))
        ]

    def latest_runs(self) -> list[RunRow]:
        """The latest run of every well, by well id."""
        return [
            _run(r)
            for r in self._db.execute(
                "SELECT * FROM runs WHERE id IN (SELECT MAX(id) FROM runs GROUP BY well) "
                "ORDER BY well"
            )
        ]

    def running_ids(self) -> set[int]:
        return {int(r[0]) for r in self._db.execute("SELECT id FROM runs WHERE status = 'running'")}

    # internals (inside a write transaction) ----------------------------------------------

    def _interrupt(self, batch: BatchRow) -> None:
        self._db.execute(
            "UPDATE batches SET status = 'interrupted' WHERE id = ? AND status = 'running'",
            (batch.id,),
        )
        for row in self._db.execute(
            "SELECT * FROM runs WHERE batch = ? AND status = 'running'", (batch.id,)
        ).fetchall():
            self._settle(_run(row))

    def _settle(self, run: RunRow) -> None:
        """A claimed run whose batch is gone: done if it published, else interrupted."""
        published = read_published(Path(run.out_dir))
        if published is not None and published.run_id == run.id:
            manifest = published.manifest
            self._db.execute(
                "UPDATE runs SET status = 'done', finished = ?, inputs = ?, outputs = ?, "
                "note = ?, wall_time_s = ?, process_time_s = ?, fingerprint = ? WHERE id = ?",
                (
                    (Path(run.out_dir) / "batch.json").stat().st_mtime,
                    json.dumps(manifest.get("inputs", {})),
                    json.dumps(manifest.get("outputs", [])),
                    "recovered: its outputs were published before its batch process ended",
                    manifest.get("wall_time_s"),
                    sum(s["wall_time_s"] for s in manifest.get("stages", [])),
                    run.fingerprint.reading_manifest(manifest).to_json(),
                    run.id,
                ),
            )
        else:
            self._db.execute(
                "UPDATE runs SET status = 'interrupted', finished = ?, "
                "error = 'interrupted: its batch process ended before the run finished' "
                "WHERE id = ?",
                (time.time(), run.id),
            )

    def _state(self, well: str) -> WellState:
        latest = self._db.execute(
            "SELECT * FROM runs WHERE well = ? AND status != 'running' ORDER BY id DESC LIMIT 1",
            (well,),
        ).fetchone()
        done = self._db.execute(
            "SELECT * FROM runs WHERE well = ? AND status = 'done' ORDER BY id DESC LIMIT 1",
            (well,),
        ).fetchone()
        last_done = _run(done) if done is not None else None
        published = None if last_done is None else read_published(Path(last_done.out_dir))
        return WellState(
            _run(latest) if latest is not None else None,
            last_done,
            published is not None and last_done is not None and published.run_id == last_done.id,
        )


def alive(batch: BatchRow) -> bool:
    """Whether a batch's process still runs (module docstring)."""
    if time.time() - batch.heartbeat > LEASE_S:
        return False
    if batch.host != socket.gethostname():
        return True
    try:
        os.kill(batch.pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _run(row: sqlite3.Row) -> RunRow:
    values = dict(zip(row.keys(), row, strict=True))
    for key in JSON_RUN_COLUMNS:
        values[key] = json.loads(values[key])
    values["fingerprint"] = Fingerprint.from_json(values["fingerprint"])
    return RunRow(**values)


def _batch(row: sqlite3.Row) -> BatchRow:
    values = dict(zip(row.keys(), row, strict=True))
    values["options"] = json.loads(values["options"])
    values["counts"] = json.loads(values["counts"])
    return BatchRow(**values)
