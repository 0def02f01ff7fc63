"""``gyropipe batch`` owns only what it made (issue 32, items 1, 2, 3 and 5): a user's
directory at ``OUT/<well>`` is never deleted, no well id names the ledger or a summary file,
a ledger where the batch publishes is refused, and a device or FIFO named as an input fails
its well at once instead of hanging the batch."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from batch_support import assert_complete, make_wells, runs, summary

from tests_support import gyropipe_cli


def batch(survey: Path, manifest: Path, out: Path, *extra: str | Path):
    return gyropipe_cli(
        "batch", survey, "--manifest", manifest, "--out", out, "--workers", "1", *extra
    )


class Hung(Exception):
    pass


@contextlib.contextmanager
def deadline(seconds: int) -> Iterator[None]:
    """Raise :class:`Hung` in this (the batch's) process after ``seconds``: the old code
    blocked opening a FIFO or read /dev/zero for ever."""

    def hung(signum: int, frame: object) -> None:
        raise Hung(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def test_a_users_directory_at_a_wells_place_is_kept_and_that_well_fails(
    tmp_path: Path, survey: Path
):
    a, b = make_wells(tmp_path / "in", ["a", "b"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nA,{a}\nB,{b}\n")
    out = tmp_path / "out"
    (out / "A").mkdir(parents=True)
    (out / "A" / "notes.txt").write_text("my notes")
    result = batch(survey, manifest, out)
    assert result.returncode == 1, result.output
    assert (out / "A" / "notes.txt").read_text() == "my notes"
    assert sorted(p.name for p in (out / "A").iterdir()) == ["notes.txt"]
    rows = summary(out)
    assert rows["A"]["status"] == "failed"
    assert rows["A"]["detail"] == (
        f"output directory '{out / 'A'}' holds files that are not a previous run's "
        "(notes.txt); a run replaces its output directory whole: give a new or empty one"
    )
    assert rows["B"]["status"] == "done"  # one bad well never stops the batch
    assert_complete(out / "B")


def test_a_previous_batch_run_of_the_well_is_replaced(tmp_path: Path, survey: Path):
    (a,) = make_wells(tmp_path / "in", ["a"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nA,{a}\n")
    out = tmp_path / "out"
    assert batch(survey, manifest, out).returncode == 0
    first = assert_complete(out / "A")
    again = batch(survey, manifest, out)
    assert again.returncode == 0, again.output
    assert [r["status"] for r in runs(out / "ledger.sqlite")] == ["done", "done"]
    assert assert_complete(out / "A")["started"] != first["started"]


@pytest.mark.parametrize(
    "well_id",
    ["ledger.sqlite-wal", "ledger.sqlite-shm", "ledger.sqlite-journal", "LEDGER.SQLITE",
     "Summary.Json", "summary.csv", "Fleet.HTML"],
)  # fmt: skip
def test_a_well_id_naming_a_file_the_batch_keeps_is_refused(
    tmp_path: Path, survey: Path, well_id: str
):
    (a,) = make_wells(tmp_path / "in", ["a"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nA,{a}\n{well_id},{a}\n")
    out = tmp_path / "out"
    result = batch(survey, manifest, out)
    assert result.returncode == 2, result.output
    assert (
        f"error: {manifest}:3: well id {well_id!r} names a file the batch keeps in its output "
        "directory (reserved, up to case: fleet.html, ledger.sqlite, ledger.sqlite-journal, "
        "ledger.sqlite-shm, ledger.sqlite-wal, summary.csv, summary.json)"
    ) in result.stderr
    assert not out.exists()


def test_an_input_file_named_like_the_ledgers_wal_is_refused(tmp_path: Path, survey: Path):
    make_wells(tmp_path / "in", ["ledger.sqlite-WAL"])
    result = gyropipe_cli(
        "batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", tmp_path / "out"
    )
    assert result.returncode == 2, result.output
    path = tmp_path / "in" / "ledger.sqlite-WAL.csv"
    assert f"{path}: well id 'ledger.sqlite-WAL' names a file the batch keeps" in result.stderr


@pytest.mark.parametrize(
    ("ledger", "top"),
    [
        ("a/ledger.sqlite", "a"),  # inside well A's directory (up to case)
        ("A", "A"),  # the well's directory itself
        ("A-wal", "A-wal"),  # its write-ahead log would be
        (".gyropipe-batch/l.sqlite", ".gyropipe-batch"),
        ("summary.json", "summary.json"),
    ],
)
def test_a_ledger_where_the_batch_publishes_is_refused_up_front(
    tmp_path: Path, survey: Path, ledger: str, top: str
):
    a, w = make_wells(tmp_path / "in", ["a", "w"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nA,{a}\nA-wal,{w}\n")
    out = tmp_path / "out"
    result = batch(survey, manifest, out, "--ledger", out / ledger)
    assert result.returncode == 2, result.output
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert line.startswith(f"error: --ledger {out / ledger}: ")
    assert line.endswith(
        f" is at or inside {out / top}, which the batch replaces or writes: keep the ledger outside "
        "the wells' directories"
    )
    assert not out.exists()


def test_a_ledger_elsewhere_in_the_output_directory_is_used(tmp_path: Path, survey: Path):
    (a,) = make_wells(tmp_path / "in", ["a"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nA,{a}\n")
    out = tmp_path / "out"
    result = batch(survey, manifest, out, "--ledger", out / "ledgers" / "main.sqlite")
    assert result.returncode == 0, result.output
    assert [r["status"] for r in runs(out / "ledgers" / "main.sqlite")] == ["done"]
    assert_complete(out / "A")


def test_devices_fifos_and_sockets_as_inputs_fail_their_well_without_reading(
    tmp_path: Path, survey: Path
):
    (a,) = make_wells(tmp_path / "in", ["a"])
    fifo = tmp_path / "in" / "fifo.csv"
    os.mkfifo(fifo)
    sock_path = tmp_path / "in" / "s.csv"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(sock_path))
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nZERO,/dev/zero\nFIFO,{fifo}\nSOCK,{sock_path}\nA,{a}\n")
    out = tmp_path / "out"
    try:
        with deadline(60):
            result = batch(survey, manifest, out)
    finally:
        sock.close()
    assert result.returncode == 1, result.output
    rows = summary(out)
    for well, path, kind in [
        ("ZERO", "/dev/zero", "a character device"),
        ("FIFO", fifo, "a FIFO"),
        ("SOCK", sock_path, "a socket"),
    ]:
        assert rows[well]["status"] == "failed"
        assert rows[well]["detail"] == (
            f"input 'stations': cannot read '{path}': not a regular file ({kind})"
        )
        assert not (out / well).exists()
    assert rows["A"]["status"] == "done"
