"""The ledger's own failures — its file system full, not a database, locked beyond the busy
timeout, replaced while in use, read-only — are one line naming the ledger, what was being
done and what to do; a failed change is rolled back whole, and the same command run again
once the fault is gone resumes (issue 32 item 4).

A full file system is made with SQLite's own ``PRAGMA max_page_count`` on the batch's
connection (SQLite then fails exactly as on a full disk: SQLITE_FULL, "database or disk is
full"), so the test runs on every machine; ``benchmarks/trials_batch_faults.py`` fills a
real small tmpfs."""

from __future__ import annotations

import contextlib
import os
import sqlite3
from pathlib import Path

import pytest
from batch_support import assert_complete, batches, make_wells, runs, summary

from pipeline.batch import ledger as ledger_module
from pipeline.batch import ledger_file
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


def _another_applications_database(path: Path) -> None:
    db = sqlite3.connect(path, isolation_level=None)
    db.execute("CREATE TABLE contacts (name TEXT, phone TEXT)")
    db.execute("INSERT INTO contacts VALUES ('Ann', '555-0100')")
    db.close()


def _newer_ledger(path: Path) -> None:
    Ledger(path).close()
    db = sqlite3.connect(path, isolation_level=None)
    db.execute("PRAGMA user_version = 2")
    db.close()


NOT_A_LEDGER = (
    "the file is not a gyropipe ledger: give the right --ledger, or move the file away (a new "
    "ledger starts an empty run history)"
)
DAMAGED_LEDGERS = {
    "empty (truncated)": (
        lambda path: path.write_bytes(b""),
        "the file is empty (0 bytes: truncated?), so the run history and the fingerprints it "
        "held are lost; restore it from a copy, or remove it to start a new ledger (every well "
        "then runs again)",
    ),
    "a short text file": (
        lambda path: path.write_bytes(b"notes\n"),
        f"file is not a database (SQLITE_NOTADB); {NOT_A_LEDGER}",
    ),
    "another application's SQLite database": (
        _another_applications_database,
        f"it is an SQLite database, not a gyropipe ledger (no tables batches and runs); "
        f"{NOT_A_LEDGER}",
    ),
    "a ledger of a newer schema": (
        _newer_ledger,
        "its schema is version 2, made by a newer gyropipe; this one reads version 1: use "
        "that gyropipe (or give another --ledger)",
    ),
}


@pytest.mark.parametrize("kind", DAMAGED_LEDGERS)
def test_an_existing_file_that_is_no_ledger_is_refused_never_taken_for_a_new_one(
    tmp_path: Path, survey: Path, kind: str
):
    """A truncated ledger opened as a new, empty one would lose the run history and the
    fingerprints without a word, and run every well again: each such file is one line
    naming it and what to do; the batch runs nothing and leaves the file as it was."""
    make_wells(tmp_path / "in", ["W1"])
    out = tmp_path / "out"
    out.mkdir()
    path = out / "ledger.sqlite"
    make, reason = DAMAGED_LEDGERS[kind]
    make(path)
    before = path.read_bytes()
    batch = gyropipe_cli("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    assert batch.returncode == 1, batch.output
    assert batch.stderr.splitlines()[-1] == f"error: ledger {path}: cannot open it: {reason}"
    assert not (out / "W1").exists()
    status = gyropipe_cli("status", out)
    assert status.returncode == 2
    assert status.stderr == f"error: ledger {path}: cannot open it: {reason}\n"
    assert path.read_bytes() == before
    assert sorted(p.name for p in out.iterdir()) == ["ledger.sqlite"]  # nothing made aside


def test_a_new_ledger_is_made_aside_and_one_made_there_meanwhile_is_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """A missing ledger is made aside and linked in place whole: no other batch finds a file
    there without its tables (it would refuse it as truncated); one that another batch made
    there meanwhile is the ledger, its runs kept."""
    path = tmp_path / "ledger.sqlite"
    theirs = tmp_path / "theirs.sqlite"
    Ledger(theirs).close()
    db = sqlite3.connect(theirs, isolation_level=None)
    db.execute(
        "INSERT INTO batches (key, status, pipeline_file, pipeline_sha256, out_dir, options, "
        "host, pid, started, heartbeat) VALUES ('k', 'finished', 'p', 's', 'o', '{}', 'h', 1, "
        "0, 0)"
    )
    db.close()
    made = ledger_file.migrate

    def meanwhile(db: sqlite3.Connection, at: Path) -> None:
        assert not path.exists()  # nothing at its place while it is made
        os.link(theirs, path)  # another batch's ledger appears there
        made(db, at)

    monkeypatch.setattr(ledger_file, "migrate", meanwhile)
    ledger = Ledger(path)
    try:
        assert [b.key for b in ledger.batches()] == ["k"]
    finally:
        ledger.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ledger.sqlite", "theirs.sqlite"]


def test_a_new_ledger_is_renamed_in_place_where_the_file_system_has_no_hard_links(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    def no_links(source: object, target: object) -> None:
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(ledger_file.os, "link", no_links)
    path = tmp_path / "ledger.sqlite"
    Ledger(path).close()
    assert [p.name for p in tmp_path.iterdir()] == ["ledger.sqlite"]
    with contextlib.closing(sqlite3.connect(path)) as db:
        assert db.execute("SELECT count(*) FROM runs").fetchone()[0] == 0


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
