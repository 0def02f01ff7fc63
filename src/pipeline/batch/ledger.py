"""The run ledger: an SQLite database recording every batch and every well run.

Consistency with several batches on one ledger (processes on one or more machines):

- WAL journal, ``synchronous=FULL`` (a committed row survives a power cut), a busy timeout,
  and every change in one ``BEGIN IMMEDIATE`` transaction; the batch groups its changes
  (:meth:`Ledger.group`): one transaction records the outcomes that came back together
  and claims the wells that take their place, so a kill at any point leaves the ledger as
  it was after the last commit, and the next batch settles the rest as below;
- a well is *claimed* by inserting its ``running`` run row; a unique partial index allows
  one ``running`` row per well, and the claim decides run-or-skip inside the same
  transaction, so two batches never run one well at the same time and never both run it
  when one of them would skip it;
- a claim belongs to its batch process, which refreshes a heartbeat; a claim whose batch
  process is gone (same host: its pid no longer exists; any host: no heartbeat for
  :data:`LEASE_S`) is settled by the next batch that meets it: ``done`` if the run had
  published its complete outputs before the process died (``batch.json`` names the ledger
  and the run), else ``interrupted``;
- a claim whose choice turns on files whose hash the batch process does not know is a
  *check* (note :data:`CHECKING`): its worker only hashes the files, and the claim is then
  dropped (the well is skipped) or made a run, in one commit, before the run is handed
  out — so a check publishes nothing, and one whose batch died is dropped, not counted;
- a run is marked ``done`` only after its outputs are published and on disk;
- the ``file_hashes`` table remembers the SHA-256 a worker found for a file's stat key
  (:mod:`pipeline.batch.filestate`): a cache, never the record of a run;
- the ``publications`` table remembers, per done run, the hashes of the ``batch.json`` and
  ``run.json`` a worker found it published with, and its fleet figures: with the stat keys
  of those two files in ``file_hashes``, the batch process knows a well's publication
  without reading a file in it.

Only the batch process opens the ledger; workers never do.

Every failure of the ledger itself — its file system full or read-only, locked beyond the
busy timeout, not a database or damaged, removed or replaced while in use — is a
:class:`LedgerError` naming the ledger, what was being done and what to do; an existing file
is never taken for a new ledger (:mod:`~pipeline.batch.ledger_file`). A failed change
is rolled back whole, so the ledger stays as it was and the same command run again resumes.
A row that does not parse (:func:`~pipeline.batch.records.run_row`) is left out and told in
:attr:`Ledger.problems`; a well whose latest rows are unreadable runs again.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import socket
import sqlite3
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Concatenate, ParamSpec, TypeAlias, TypeVar

from pipeline.errors import file_errors
from pipeline.hashing import FileKey
from pipeline.processes import process_alive

from .filestate import HashCache
from .fingerprint import Fingerprint, completed_json
from .ledger_file import BUSY_TIMEOUT_MS, GONE, check, make_ledger, migrate
from .ledger_file import LedgerError as LedgerError  # where it has always been imported from
from .policy import Check, Run, Skip, WellState
from .publish import MARKER, Publication, read_published
from .records import BadRow, BatchRow, RunRow, batch_row, decode_text, rejection, run_row
from .worker import WellOutcome

LEASE_S = 60.0
"""A batch whose heartbeat is older than this is presumed dead (heartbeat every LEASE_S/6)."""
CHECKING = "checking: its files are hashed to decide whether it runs"
"""the note of a claim that is a check (module docstring)"""

P = ParamSpec("P")
R = TypeVar("R")
T = TypeVar("T")


Method: TypeAlias = "Callable[Concatenate[Ledger, P], R]"


def _guarded(doing: str) -> Callable[[Method[P, R]], Method[P, R]]:
    """A :class:`Ledger` method whose SQLite failures are :class:`LedgerError` (``doing``)."""

    def wrap(method: Method[P, R]) -> Method[P, R]:
        def guarded(ledger: Ledger, /, *args: P.args, **kwargs: P.kwargs) -> R:
            try:
                return method(ledger, *args, **kwargs)
            except (sqlite3.Error, UnicodeDecodeError) as exc:
                raise LedgerError(ledger.path, doing, exc) from None

        functools.update_wrapper(guarded, method)
        return guarded

    return wrap


@dataclass(frozen=True)
class Claimed:
    run_id: int
    reasons: list[str]
    check: Check | None = None
    """a check: its worker hashes files, then the claim is dropped or made a run"""


@dataclass(frozen=True)
class Skipped:
    reason: str


@dataclass(frozen=True)
class Busy:
    """Another live batch holds the well."""

    batch: int
    host: str
    pid: int


Decide = Callable[[WellState], Run | Skip | Check]


class Ledger:
    """An open ledger file (module docstring)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.problems: list[str] = []
        """rows that did not parse, as warning lines (each told once; the caller drains it)"""
        self._told: set[tuple[str, int, str]] = set()
        self._depth = 0
        """open :meth:`_write` blocks (more than one inside :meth:`group`)"""
        with file_errors("create the ledger's directory", path.parent):
            path.parent.mkdir(parents=True, exist_ok=True)
        make_ledger(path)
        try:
            self._db = sqlite3.connect(path, timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None)
        except sqlite3.Error as exc:
            raise LedgerError(path, "open it", exc) from None
        self._db.row_factory = sqlite3.Row
        self._db.text_factory = decode_text
        try:
            self._open()
        except BaseException:
            self._db.close()
            raise

    @_guarded("open it")
    def _open(self) -> None:
        self._db.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        check(self._db, self.path)
        self._db.execute("PRAGMA journal_mode = WAL")
        self._db.execute("PRAGMA synchronous = FULL")
        self._db.execute("PRAGMA foreign_keys = ON")
        self._identity = _identity(self.path)
        with self._write():
            self.ledger_id = migrate(self._db, self.path)
            """the ledger's identity (:mod:`~pipeline.batch.ledger_file`)"""
        self._hashes = HashCache(self._db)

    def close(self) -> None:
        self._db.close()

    @contextlib.contextmanager
    def _write(self) -> Iterator[None]:
        """One write transaction, taken before any read (``BEGIN IMMEDIATE``), on the file
        that was opened (not one put in its place); rolled back whole if anything fails.
        Inside :meth:`group`, part of the group's transaction."""
        if self._depth:
            self._depth += 1
            try:
                yield
            finally:
                self._depth -= 1
            return
        self._db.execute("BEGIN IMMEDIATE")
        self._depth = 1
        try:
            if _identity(self.path) != self._identity:
                raise LedgerError(self.path, "write", GONE)
            yield
            self._db.execute("COMMIT")
        except BaseException:
            with contextlib.suppress(sqlite3.Error):  # SQLite may have rolled back already
                if self._db.in_transaction:
                    self._db.execute("ROLLBACK")
            raise
        finally:
            self._depth = 0

    @contextlib.contextmanager
    def group(self) -> Iterator[None]:
        """The changes made inside, in one transaction: all committed, or none."""
        try:
            with self._write():
                yield
        except sqlite3.Error as exc:
            raise LedgerError(self.path, "record the batch's progress", exc) from None

    def _note(self, kind: str, row: sqlite3.Row, bad: BadRow) -> None:
        """Tell a row that does not parse once (``kind`` run or batch)."""
        key = (kind, int(row["id"]), bad.column)
        if key not in self._told:
            self._told.add(key)
            well = row["well"] if kind == "run" else None
            of = f" of well {well!r}" if isinstance(well, str) else ""
            self.problems.append(
                f"ledger {self.path}: {kind} {row['id']}{of}: {bad}; the row is left out"
            )

    def _runs(self, rows: Iterable[sqlite3.Row]) -> list[RunRow]:
        """The rows that parse (the others told in :attr:`problems`)."""
        return self._parsed("run", rows, run_row)

    def _batches(self, rows: Iterable[sqlite3.Row]) -> list[BatchRow]:
        return self._parsed("batch", rows, batch_row)

    def _parsed(
        self, kind: str, rows: Iterable[sqlite3.Row], parse: Callable[[dict[str, Any]], T]
    ) -> list[T]:
        parsed = []
        for row in rows:
            try:
                parsed.append(parse(dict(zip(row.keys(), row, strict=True))))
            except BadRow as bad:
                self._note(kind, row, bad)
        return parsed

    # batches -----------------------------------------------------------------------------

    @_guarded("record the batch's start")
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

    @_guarded("record the batch's heartbeat")
    def heartbeat(self, batch_id: int) -> None:
        with self._write():
            self._db.execute(
                "UPDATE batches SET heartbeat = ? WHERE id = ?", (time.time(), batch_id)
            )

    @_guarded("record the batch's end")
    def end_batch(self, batch_id: int, status: str, counts: dict[str, int]) -> None:
        """Close a batch (finished or interrupted); its runs still claimed become interrupted."""
        now = time.time()
        with self._write():
            self._db.execute(
                "UPDATE batches SET status = ?, finished = ?, heartbeat = ?, counts = ? "
                "WHERE id = ?",
                (status, now, now, json.dumps(counts), batch_id),
            )
            self._settle_runs(batch_id)

    @_guarded("read a batch")
    def batch(self, batch_id: int) -> BatchRow | None:
        """Batch ``batch_id``; None if there is none or its row does not parse."""
        rows = self._db.execute("SELECT * FROM batches WHERE id = ?", (batch_id,)).fetchall()
        parsed = self._batches(rows)
        return parsed[0] if parsed else None

    @_guarded("read the batches")
    def batches(self) -> list[BatchRow]:
        return self._batches(self._db.execute("SELECT * FROM batches ORDER BY id").fetchall())

    @_guarded("settle the batches that had stopped")
    def sweep(self) -> list[BatchRow]:
        """Mark batches whose process is gone as interrupted and settle their claimed runs
        (module docstring); a running batch whose row does not parse counts as gone.
        Returns the batches swept that parse."""
        swept = []
        with self._write():
            rows = self._db.execute("SELECT * FROM batches WHERE status = 'running'").fetchall()
            for row in rows:
                parsed = self._batches([row])
                if not parsed or not alive(parsed[0]):
                    self._interrupt(int(row["id"]))
                    swept += parsed
        return swept

    @_guarded("read the batches")
    def resume_since(self, key: str, batch_id: int) -> int | None:
        """The first batch of the trailing chain of interrupted batches with ``key`` before
        ``batch_id`` (the same command killed, possibly several times), if any."""
        since = None
        for row in self._db.execute(
            "SELECT id, status FROM batches WHERE key = ? AND id < ? ORDER BY id DESC",
            (key, batch_id),
        ).fetchall():
            if row["status"] != "interrupted":
                break
            since = int(row["id"])
        return since

    # runs --------------------------------------------------------------------------------

    @_guarded("claim a well")
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
                self._interrupt(int(held["batch"]))
            decision = decide(self._state(well))
            if isinstance(decision, Skip):
                return Skipped(decision.reason)
            check = decision if isinstance(decision, Check) else None
            reasons = decision.reasons if isinstance(decision, Run) else []
            cursor = self._db.execute(
                "INSERT INTO runs (well, batch, status, reasons, fingerprint, versions, out_dir, "
                "started, note) VALUES (?, ?, 'running', ?, ?, ?, ?, ?, ?)",
                (
                    well,
                    batch.id,
                    json.dumps(reasons),
                    fingerprint.to_json(),
                    json.dumps(versions, sort_keys=True),
                    str(out_dir),
                    time.time(),
                    CHECKING if check is not None else None,
                ),
            )
            return Claimed(int(cursor.lastrowid or 0), reasons, check)

    @_guarded("record a well's check")
    def checked(self, run_id: int, reasons: list[str] | None) -> bool:
        """A check's end: the claim dropped (``reasons`` None: the well is skipped), or made
        the run of the well for ``reasons``. False if the claim is no longer a check: the
        batch was taken for dead meanwhile (silent past :data:`LEASE_S`) and its check
        dropped — its id may be another claim's now, which stays as it is."""
        with self._write():
            if reasons is None:
                cursor = self._db.execute(
                    "DELETE FROM runs WHERE id = ? AND status = 'running' AND note = ?",
                    (run_id, CHECKING),
                )
            else:
                cursor = self._db.execute(
                    "UPDATE runs SET reasons = ?, note = NULL "
                    "WHERE id = ? AND status = 'running' AND note = ?",
                    (json.dumps(reasons), run_id, CHECKING),
                )
            return cursor.rowcount == 1

    @_guarded("read the file hashes")
    def known_hash(self, key: FileKey) -> str | None:
        """The SHA-256 remembered for a file's stat key (:mod:`~pipeline.batch.filestate`)."""
        return self._hashes.get(key)

    @_guarded("remember file hashes")
    def remember(self, entries: list[tuple[str, FileKey, str]]) -> None:
        """Remember (path, stat key, SHA-256) of files a worker hashed."""
        if entries:
            with self._write():
                self._hashes.put(entries)

    @_guarded("remember a publication")
    def published(
        self, publication: Publication, figures: str | None, files: Iterable[str] = ()
    ) -> None:
        """Remember how a worker found run ``publication.run_id`` published, with its fleet
        figures (JSON, :func:`~pipeline.batch.fleet.figures_json`; None: keep the ones
        remembered), and forget the hashes remembered for ``files`` (its ``batch.json`` and
        ``run.json``: an earlier run's there are replaced)."""
        with self._write():
            self._hashes.forget(files)
            self._db.execute(
                "INSERT INTO publications (run, marker_sha256, manifest_sha256, figures) "
                "VALUES (?, ?, ?, ?) ON CONFLICT (run) DO UPDATE SET "
                "marker_sha256 = excluded.marker_sha256, "
                "manifest_sha256 = excluded.manifest_sha256, "
                "figures = COALESCE(excluded.figures, figures)",
                (
                    publication.run_id,
                    publication.marker_sha256,
                    publication.manifest_sha256,
                    figures,
                ),
            )

    @_guarded("record a well's outcome")
    def finish(
        self,
        outcome: WellOutcome,
        error: str | None = None,
        fingerprint: Fingerprint | None = None,
        reasons: list[str] | None = None,
    ) -> None:
        """Record a worker's outcome (``error`` overrides a done outcome that the batch
        process found inconsistent); a done run whose survey failed acceptance is noted
        ``rejected: …`` (:attr:`RunRow.verdict`). ``fingerprint`` and ``reasons``, when
        given, replace the claim's (the run's own hashes, the files it read through
        parameters, and why it ran in their light)."""
        status = "failed" if error or outcome.status != "done" else "done"
        manifest = outcome.manifest
        with self._write():
            self._db.execute(
                "UPDATE runs SET status = ?, finished = ?, inputs = ?, outputs = ?, "
                "calibration = ?, drift = ?, error = ?, note = ?, wall_time_s = ?, "
                "run_time_s = ?, process_time_s = ?, peak_rss_bytes = ?, worker = ?, "
                "fingerprint = COALESCE(?, fingerprint), reasons = COALESCE(?, reasons) "
                "WHERE id = ? AND well = ?",
                (
                    status,
                    time.time(),
                    json.dumps(manifest.get("inputs", {})),
                    json.dumps(manifest.get("outputs", [])),
                    json.dumps(outcome.calibration),
                    None if outcome.drift is None else json.dumps(outcome.drift),
                    error or outcome.error,
                    rejection(manifest) if status == "done" else None,
                    outcome.wall_time_s,
                    outcome.run_time_s,
                    outcome.process_time_s,
                    outcome.peak_rss_bytes or None,
                    outcome.worker or None,
                    fingerprint.to_json() if fingerprint is not None else None,
                    json.dumps(reasons) if reasons is not None else None,
                    outcome.run_id,
                    outcome.well_id,  # (an id reused after its batch's check was dropped)
                ),
            )

    @_guarded("read a run")
    def run(self, run_id: int) -> RunRow | None:
        parsed = self._runs(self._db.execute("SELECT * FROM runs WHERE id = ?", (run_id,)))
        return parsed[0] if parsed else None

    @_guarded("read a well's runs")
    def history(self, well: str) -> list[RunRow]:
        return self._runs(
            self._db.execute("SELECT * FROM runs WHERE well = ? ORDER BY id", (well,))
        )

    @_guarded("read the wells' runs")
    def latest_runs(self) -> list[RunRow]:
        """The latest run of every well, by well id (a well whose latest row does not parse
        is left out)."""
        return self._runs(
            self._db.execute(
                "SELECT * FROM runs WHERE id IN (SELECT MAX(id) FROM runs GROUP BY well) "
                "ORDER BY well"
            )
        )

    @_guarded("read the claimed runs")
    def running_ids(self) -> set[int]:
        return {int(r[0]) for r in self._db.execute("SELECT id FROM runs WHERE status = 'running'")}

    # internals (inside a write transaction) ----------------------------------------------

    def _interrupt(self, batch_id: int) -> None:
        self._db.execute(
            "UPDATE batches SET status = 'interrupted' WHERE id = ? AND status = 'running'",
            (batch_id,),
        )
        self._settle_runs(batch_id)

    def _settle_runs(self, batch_id: int) -> None:
        """The runs batch ``batch_id`` still claims, its process gone: done if the run had
        published (``batch.json`` names this ledger and the row's id; read from the row's id
        and out_dir only, so a damaged row is settled too), else interrupted; a check (which
        publishes nothing) is dropped."""
        self._db.execute(
            "DELETE FROM runs WHERE batch = ? AND status = 'running' AND note = ?",
            (batch_id, CHECKING),
        )
        for row in self._db.execute(
            "SELECT id, out_dir, fingerprint FROM runs WHERE batch = ? AND status = 'running'",
            (batch_id,),
        ).fetchall():
            out_dir = row["out_dir"]
            published = read_published(Path(out_dir)) if isinstance(out_dir, str) else None
            if published is not None and published.publication.is_run(self.ledger_id, row["id"]):
                self._recover(int(row["id"]), Path(out_dir), published.manifest, row["fingerprint"])
                self.published(published.publication, None)
            else:
                self._db.execute(
                    "UPDATE runs SET status = 'interrupted', finished = ?, "
                    "error = 'interrupted: its batch process ended before the run finished' "
                    "WHERE id = ?",
                    (time.time(), row["id"]),
                )

    def _recover(
        self, run_id: int, out_dir: Path, manifest: dict[str, Any], fingerprint: object
    ) -> None:
        """A claimed run that published before its batch process ended: done, its
        fingerprint completed by its ``run.json`` (its input hashes, the files it read; kept
        as it was where the row's fingerprint or the manifest does not parse)."""
        stages = manifest.get("stages")
        times = [s.get("wall_time_s") for s in stages] if isinstance(stages, list) else []
        self._db.execute(
            "UPDATE runs SET status = 'done', finished = ?, inputs = ?, outputs = ?, "
            "note = ?, wall_time_s = ?, process_time_s = ?, fingerprint = ? WHERE id = ?",
            (
                (out_dir / MARKER).stat().st_mtime,
                json.dumps(manifest.get("inputs", {})),
                json.dumps(manifest.get("outputs", [])),
                "recovered: its outputs were published before its batch process ended",
                _number(manifest.get("wall_time_s")),
                sum(t for t in times if isinstance(t, int | float)),
                completed_json(fingerprint, manifest),
                run_id,
            ),
        )

    def _state(self, well: str) -> WellState:
        """The well's latest finished run and its last done run that parse (a row that does
        not is left out: with it the well runs again)."""
        finished = self._runs(
            self._db.execute(
                "SELECT * FROM runs WHERE well = ? AND status != 'running' ORDER BY id DESC "
                "LIMIT 1",
                (well,),
            )
        )
        done = self._runs(
            self._db.execute(
                "SELECT * FROM runs WHERE well = ? AND status = 'done' ORDER BY id DESC LIMIT 1",
                (well,),
            )
        )
        latest = finished[0] if finished else None
        last_done = done[0] if done else None
        publication, figures = None, None
        if last_done is not None:
            row = self._db.execute(
                "SELECT * FROM publications WHERE run = ?", (last_done.id,)
            ).fetchone()
            if row is not None and all(
                isinstance(row[k], str) for k in ("marker_sha256", "manifest_sha256")
            ):
                publication = Publication(
                    last_done.id, row["marker_sha256"], row["manifest_sha256"]
                )
                figures = row["figures"] if isinstance(row["figures"], str) else None
        return WellState(latest, last_done, None, publication, figures)


def alive(batch: BatchRow) -> bool:
    """Whether a batch's process still runs (module docstring)."""
    if time.time() - batch.heartbeat > LEASE_S:
        return False
    return batch.host != socket.gethostname() or process_alive(batch.pid)


def _identity(path: Path) -> tuple[int, int] | None:
    """The file ``path`` names (device, inode); None if there is none."""
    try:
        found = os.stat(path)
    except OSError:
        return None
    return found.st_dev, found.st_ino


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, int | float) else None
