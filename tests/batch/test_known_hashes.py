"""A worker takes an input's SHA-256 for ``run.json`` from the task — the stat key the batch
process saw and the settled hash the ledger holds for it — where its own key of the file is
the same, and reads the file for it otherwise. Through the command line in this process, on
an executor that runs each task here, with every hash a worker takes recorded
(``hashlib.file_digest``, which :func:`pipeline.hashing.sha256_file` reads the file into)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from batch_support import InProcess, make_wells, summary

from pipeline.batch import filestate
from pipeline.batch.worker import WellOutcome, WellTask, run_well
from pipeline.executing import ExecutorDef
from pipeline.hashing import file_key
from pipeline.plugins import shared_registry
from tests_support import gyropipe_cli

SET = ("--set", "trajectory.vs_azimuth=37.5")


class Hashed:
    """The files hashed (``hashlib.file_digest``) and the tasks run, in this process."""

    def __init__(self) -> None:
        self.paths: list[str] = []
        self.tasks: list[WellTask] = []
        self.ref: Any = None


@pytest.fixture
def hashed(monkeypatch: pytest.MonkeyPatch) -> Iterator[Hashed]:
    """Executor ``here`` (each task run at once in this process) registered for the command
    line, and every ``hashlib.file_digest`` of a file recorded by its path."""
    found = Hashed()
    digest = hashlib.file_digest

    def recording(fileobj: Any, name: Any) -> Any:
        found.paths.append(os.readlink(f"/proc/self/fd/{fileobj.fileno()}"))
        return digest(fileobj, name)

    class Here(InProcess):
        def run(self, task: WellTask) -> WellOutcome:
            found.tasks.append(task)
            found.ref = self.ref
            return super().run(task)

    monkeypatch.setattr(hashlib, "file_digest", recording)
    executors = shared_registry().executors
    executors["here"] = (ExecutorDef("here", "this process", Here), "builtin.executors")
    yield found
    del executors["here"]


def batch(pattern: Path, out: Path, survey: Path, *flags: str) -> dict[str, Any]:
    result = gyropipe_cli(
        "batch", survey, "--inputs", pattern, "--out", out, "--executor", "here", *flags
    )
    assert result.returncode == 0, result.output
    return {w: (r["status"], r["detail"]) for w, r in summary(out).items()}


def recorded_sha256(out: Path, well: str) -> str:
    return str(json.loads((out / well / "run.json").read_text())["inputs"]["stations"]["sha256"])


def remembered(ledger: Path) -> dict[int, tuple[str, int]]:
    """The ledger's file hashes: inode → (sha256, ctime_ns)."""
    with sqlite3.connect(ledger) as db:
        rows = db.execute("SELECT ino, sha256, ctime_ns FROM file_hashes").fetchall()
    return {ino: (digest, ctime) for ino, digest, ctime in rows}


def test_a_reprocessing_batch_takes_known_hashes_and_hashes_a_rewritten_input(
    tmp_path: Path, survey: Path, hashed: Hashed, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)  # files just written count as settled
    a, b = make_wells(tmp_path / "in", ["A", "B"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    assert batch(pattern, out, survey) == {w: ("done", "new well") for w in "AB"}
    assert {str(a), str(b)} <= set(hashed.paths)  # unknown: hashed by the worker

    # (1) a parameter changed, the inputs not: run again, their hashes known, unread
    hashed.paths.clear()
    changed = "params changed: trajectory.vs_azimuth 0.0→37.5"
    assert batch(pattern, out, survey, "--only-changed", *SET) == {
        w: ("done", changed) for w in "AB"
    }
    digest = hashlib.sha256(a.read_bytes()).hexdigest()  # (b is a copy)
    assert recorded_sha256(out, "A") == recorded_sha256(out, "B") == digest
    assert not {str(a), str(b)} & set(hashed.paths)

    # (2) rewritten with the same size (a new ctime): hashed afresh, the new hash recorded
    data = a.read_bytes()
    at = data.rindex(b"5")
    a.write_bytes(data[:at] + b"6" + data[at + 1 :])
    new = hashlib.sha256(a.read_bytes()).hexdigest()
    assert new != digest and a.stat().st_size == len(data)
    hashed.paths.clear()
    assert batch(pattern, out, survey, *SET) == {
        "A": ("done", "input changed: stations"),
        "B": ("done", "unchanged, run requested"),
    }
    assert hashed.paths.count(str(a)) == 1 and str(b) not in hashed.paths
    assert recorded_sha256(out, "A") == new and recorded_sha256(out, "B") == digest
    assert remembered(out / "ledger.sqlite")[a.stat().st_ino] == (new, a.stat().st_ctime_ns)


def test_a_fresh_input_is_hashed_again_and_a_task_s_stale_key_is_not_trusted(
    tmp_path: Path, survey: Path, hashed: Hashed
):
    (a,) = make_wells(tmp_path / "in", ["A"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    digest = hashlib.sha256(a.read_bytes()).hexdigest()
    # (3) written just now (younger than SETTLED_S): not remembered, so hashed again
    for _ in range(2):
        hashed.paths.clear()
        batch(pattern, out, survey, *SET)
        assert hashed.paths.count(str(a)) == 1
        assert recorded_sha256(out, "A") == digest
    assert remembered(out / "ledger.sqlite") == {}
    assert hashed.tasks[-1].known == {}

    # a task whose key is not the file's: its hash is not taken
    key = file_key(a)
    stale = key._replace(ctime_ns=key.ctime_ns - 1)
    task = dataclasses.replace(
        hashed.tasks[-1], run_id=hashed.tasks[-1].run_id + 1, known={str(a): (stale, "0" * 64)}
    )
    hashed.paths.clear()
    outcome = run_well(task, hashed.ref)
    assert outcome.status == "done", outcome.error
    assert outcome.manifest["inputs"]["stations"]["sha256"] == digest
    assert hashed.paths.count(str(a)) == 1


def test_a_failed_run_hashes_its_input_once_and_takes_a_known_hash_unread(
    tmp_path: Path, survey: Path, hashed: Hashed
):
    (a,) = make_wells(tmp_path / "in", ["A"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(pattern, out, survey)
    last = hashed.tasks[-1]

    # the input damaged: the run fails in a stage, the file read for its hash once only
    a.write_text(a.read_text().replace("\n1", "\nnot-a-number", 1))
    hashed.paths.clear()
    outcome = run_well(dataclasses.replace(last, run_id=last.run_id + 1), hashed.ref)
    assert outcome.status == "failed"
    assert outcome.hashes == {str(a): hashlib.sha256(a.read_bytes()).hexdigest()}
    assert hashed.paths.count(str(a)) == 1

    # failed before anything ran (a stranger's file in OUT/A): the task's settled hash for
    # the file's key is taken as is, unread
    (out / "A" / "notes.txt").write_text("mine")
    known = {str(a): (file_key(a), "0" * 64)}
    hashed.paths.clear()
    outcome = run_well(dataclasses.replace(last, run_id=last.run_id + 2, known=known), hashed.ref)
    assert outcome.status == "failed" and "notes.txt" in outcome.error
    assert outcome.hashes == {str(a): "0" * 64}
    assert hashed.paths == []
