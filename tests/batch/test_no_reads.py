"""The batch process reads no input: it stats each file, takes a hash the ledger remembers for
an unchanged stat, and leaves every read to the workers — the run's own hashes, or a check
(a task that only hashes) when the choice turns on a file it has no hash for. Driven through
the batch with an executor that runs each task in this process and records it, and an audit
hook telling which files the batch's own code opened and which the tasks opened."""

from __future__ import annotations

import hashlib
import io
import sqlite3
from pathlib import Path

import pytest
from batch_support import InProcess, Opens, change_one_azimuth, make_wells, runs

from pipeline.batch import filestate
from pipeline.batch.jobs import jobs_from_glob
from pipeline.batch.policy import Mode
from pipeline.batch.progress import JsonLines
from pipeline.batch.run import BatchOptions, BatchReport, run_batch
from pipeline.batch.worker import WellOutcome, WellTask
from pipeline.executing import ExecutorDef, ExecutorSetup
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec
from pipeline.well import WellMetadata


class Recording(InProcess):
    """Runs each task at once in this process, its opens counted as the worker's."""

    def __init__(self, setup: ExecutorSetup, opens: Opens, tasks: list[WellTask]) -> None:
        super().__init__(setup)
        self._opens = opens
        self._tasks = tasks

    def run(self, task: WellTask) -> WellOutcome:
        self._tasks.append(task)
        with self._opens.worker_code():
            return super().run(task)


def batch(
    survey: Path, pattern: Path, out: Path, *, only_changed: bool = False
) -> tuple[BatchReport, list[WellTask], Opens]:
    """A batch on the recording executor: its report, the tasks it handed out, the opens."""
    registry = load_registry()
    tasks: list[WellTask] = []
    with Opens() as opens:
        factory = lambda setup: Recording(setup, opens, tasks)  # noqa: E731
        registry.executors["recording"] = (
            ExecutorDef("recording", "this process, recorded", factory),
            "builtin.executors",
        )
        plan = build_plan(load_spec(survey), registry)
        jobs = jobs_from_glob(str(pattern), ["stations"], WellMetadata())
        options = BatchOptions(
            out_dir=out, workers=1, executor="recording", mode=Mode(only_changed=only_changed)
        )
        report = run_batch(plan, registry, jobs, options, JsonLines(io.StringIO()))
    return report, tasks, opens


def remembered(ledger: Path) -> dict[int, tuple[str, int]]:
    """The ledger's file hashes: inode → (sha256, ctime_ns)."""
    with sqlite3.connect(ledger) as db:
        rows = db.execute("SELECT ino, sha256, ctime_ns FROM file_hashes").fetchall()
    return {ino: (digest, ctime) for ino, digest, ctime in rows}


def test_the_batch_process_reads_no_input_and_a_stat_spares_the_hash(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    a, b, c = make_wells(tmp_path / "in", ["A", "B", "C"])
    inputs = {str(p) for p in (a, b, c)}
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)  # files just written count as settled

    report, tasks, opens = batch(survey, pattern, out)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        (w, "done", "new well") for w in "ABC"
    }
    assert [t.check for t in tasks] == [None] * 3  # runs only
    assert not inputs & set(opens.driver)
    assert inputs <= set(opens.worker)
    # the fleet page's figures of a run came back with it: of the published files, the
    # batch process reads only one well's, to see once per worker host that OUT is shared
    published = {str(out / w / name) for w in "ABC" for name in ("run.json", "batch.json")}
    assert len({Path(p).parent for p in published & set(opens.driver)}) == 1
    assert published <= set(opens.worker)
    assert (out / "fleet.html").is_file()
    digest = hashlib.sha256(a.read_bytes()).hexdigest()  # the three are copies
    assert remembered(out / "ledger.sqlite") == {
        p.stat().st_ino: (digest, p.stat().st_ctime_ns) for p in (a, b, c)
    }

    change_one_azimuth(b)
    report, tasks, opens = batch(survey, pattern, out, only_changed=True)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        ("A", "skipped", "unchanged"),
        ("B", "done", "input changed: stations"),
        ("C", "skipped", "unchanged"),
    }
    # A and C decided from their stat alone; B checked (hashed), then run
    assert [(t.well_id, t.check) for t in tasks] == [("B", [str(b)]), ("B", None)]
    assert not inputs & set(opens.driver)
    assert {p for p in opens.worker if p in inputs} == {str(b)}

    monkeypatch.undo()  # a file written just now is hashed again next time
    c.write_bytes(c.read_bytes())  # same bytes, a new ctime
    report, tasks, opens = batch(survey, pattern, out, only_changed=True)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        (w, "skipped", "unchanged") for w in "ABC"
    }
    assert [(t.well_id, t.check) for t in tasks] == [("C", [str(c)])]  # a check, no run
    assert not inputs & set(opens.driver)
    assert remembered(out / "ledger.sqlite")[c.stat().st_ino][1] != c.stat().st_ctime_ns
    # the check left no run behind: one run of A and C, two of B, nothing claimed
    assert sorted((r["well"], r["status"]) for r in runs(out / "ledger.sqlite")) == [
        ("A", "done"),
        ("B", "done"),
        ("B", "done"),
        ("C", "done"),
    ]
