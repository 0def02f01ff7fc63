"""The ledger's own failures — its file system full, not a database, locked beyond the busy
timeout, replaced while in use, read-only — are one line naming the ledger, what was being
done and what to do; a failed change is rolled back whole, and the same command run again
once the fault is gone resumes (issue 32 item 4).

A full file system is made with SQLite's own ``PRAGMA max_page_count`` on the batch's
connection (SQLite then fails exactly as on a full disk: SQLITE_FULL, "database or disk is
full"), so the test runs on every machine; ``benchmarks/trials_batch_faults.py`` fills a
real small tmpfs."""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path

import pytest
from batch_support import assert_complete, batches, make_wells, runs, summary

from pipeline.batch import ledger as ledger_module
from pipeline.batch.ledger import Ledger, LedgerError
from tests_support import gyropipe_cli

WELLS = [f"F{i}" for i in range(6)]


def test_a_full_ledger_stops_the_batch_in_one_line_and_the_same_command_resumes(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    make_wells(tmp_path / "in", WELLS)
    out = tmp_path / "out"
    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out, "--quiet")
    opened = Ledger._open

    def full_soon(self: Ledger) -> None:  # room for the schema and two more pages
        opened(self)
        pages = self._db.execute("PRAGMA page_count").fetchone()[0]
        self._db.execute(f"PRAGMA max_page_count = {pages + 2}")

    monkeypatch.setattr(Ledger, "_open", full_soon)
    failed = gyropipe_cli(*args, "--workers", "1")
    assert failed.returncode == 1, failed.output
    errors = [line for line in failed.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, failed.stderr
    assert errors[0].startswith(f"error: ledger {out / 'ledger.sqlite'}: cannot ")
    assert "database or disk is full (SQLITE_FULL); its file system is full" in errors[0]
    assert errors[0].endswith("then run the same command again: it resumes")
    with sqlite3.connect(out / "ledger.sqlite") as db:
        assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    before = runs(out / "ledger.sqlite")
    assert before and len(before) < len(WELLS)  # it stopped part way
    done_before = {r["well"]: r["id"] for r in before if r["status"] == "done"}

    monkeypatch.setattr(Ledger, "_open", opened)
    resumed = gyropipe_cli(*args)
    assert resumed.returncode == 0, resumed.output
    assert [b["status"] for b in batches(out / "ledger.sqlite")] == ["interrupted", "finished"]
    rows = runs(out / "ledger.sqlite")
    for well in WELLS:
        done = [r for r in rows if r["well"] == well and r["status"] == "done"]
        assert len(done) == 1, rows
        assert done_before.get(well, done[0]["id"]) == done[0]["id"]  # never run twice
        assert_complete(out / well)
    assert {w for w, r in summary(out).items() if r["status"] == "skipped"} == set(done_before)


def test_a_file_that_is_not_a_ledger_is_named_with_what_to_do(tmp_path: Path):
    (tmp_path / "ledger.sqlite").write_bytes(b"these are a user's notes, not a database\n" * 100)
    status = gyropipe_cli("status", tmp_path)
    assert status.returncode == 2
    assert status.stderr == (
        f"error: ledger {tmp_path / 'ledger.sqlite'}: cannot open it: file is not a database "
        "(SQLITE_NOTADB); the file is not a gyropipe ledger: give the right --ledger, or move "
        "the file away (a new ledger starts an empty run history)\n"
    )


def test_a_damaged_ledger_whose_message_is_not_text_is_named(tmp_path: Path):
    """SQLite's message about a damaged schema quotes the damaged name, whose bytes need not
    be UTF-8 (found by the fuzz suite's ledger kind: a flipped byte in the schema page)."""
    path = tmp_path / "ledger.sqlite"
    Ledger(path).close()
    with sqlite3.connect(path) as db:
        db.execute("PRAGMA writable_schema = ON")
        db.execute(
            "UPDATE sqlite_master SET name = CAST(X'DF41' AS TEXT), sql = 'CREATE garbage' "
            "WHERE name = 'file_hashes'"
        )
    status = gyropipe_cli("status", tmp_path)
    assert status.returncode == 2
    assert status.stderr == (
        f"error: ledger {path}: cannot open it: SQLite's message is not text (the file is "
        "damaged?); the file is damaged: restore it from a copy, or move it away (a new "
        "ledger starts an empty run history)\n"
    )


def test_a_ledger_locked_beyond_the_busy_timeout_is_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    path = tmp_path / "ledger.sqlite"
    Ledger(path).close()
    monkeypatch.setattr(ledger_module, "BUSY_TIMEOUT_MS", 50)
    ledger = Ledger(path)
    holder = sqlite3.connect(path, isolation_level=None)
    holder.execute("BEGIN IMMEDIATE")
    try:
        with pytest.raises(LedgerError) as caught:
            ledger.heartbeat(1)
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert str(caught.value).startswith(
        f"ledger {path}: cannot record the batch's heartbeat: database is locked (SQLITE_BUSY); "
        "another process held it locked"
    )
    ledger.heartbeat(1)  # the lock gone, it works again
    ledger.close()


def test_a_ledger_replaced_while_in_use_is_refused_not_written_blind(tmp_path: Path):
    path = tmp_path / "ledger.sqlite"
    ledger = Ledger(path)
    batch = ledger.start_batch("key", "p.yaml", "0" * 64, tmp_path, {})
    os.replace(path, tmp_path / "moved.sqlite")
    with pytest.raises(LedgerError, match="removed or replaced since it was opened"):
        ledger.heartbeat(batch.id)
    ledger.close()


def test_a_read_only_ledger_is_named(tmp_path: Path, read_only_dir: Path):
    """The ledger in a read-only directory (a read-only tmpfs, or chmod where that binds)."""
    ledger_path = read_only_dir / "ledger.sqlite"
    with pytest.raises(LedgerError) as caught:
        Ledger(ledger_path)
    assert str(caught.value).startswith(f"ledger {ledger_path}: cannot open it: ")
    assert "writable" in str(caught.value)
