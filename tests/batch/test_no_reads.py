"""The batch process reads no input: it stats each file, takes a hash the ledger remembers for
an unchanged stat, and leaves every read to the workers — the run's own hashes, or a check
(a task that only hashes) when the choice turns on a file it has no hash for. Driven through
the batch with an executor that runs each task in this process and records it, and an audit
hook telling which files the batch's own code opened and which the tasks opened."""

from __future__ import annotations

import hashlib
import io
import re
import sqlite3
import time
from pathlib import Path

import pytest
from batch_support import (
    InProcess,
    Opens,
    assert_complete,
    change_one_azimuth,
    make_wells,
    runs,
    summary,
)
from test_parameter_files import clearance_pipeline, make_fleet

from pipeline.batch import filestate
from pipeline.batch.jobs import WellJob, jobs_from_glob, jobs_from_manifest
from pipeline.batch.policy import Mode
from pipeline.batch.progress import JsonLines
from pipeline.batch.run import BatchOptions, BatchReport, run_batch
from pipeline.batch.worker import WellOutcome, WellTask
from pipeline.executing import ExecutorDef, ExecutorSetup
from pipeline.graph import Plan, build_plan
from pipeline.plugins import load_registry
from pipeline.registry import Registry
from pipeline.spec import load_spec
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli


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
    plan = build_plan(load_spec(survey), registry)
    jobs = jobs_from_glob(str(pattern), ["stations"], WellMetadata())
    return run_recorded(plan, registry, jobs, out, only_changed)


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
    # the inputs of A and C known from their stat alone, their outputs published since the
    # last look: a worker looks at them (a check hashing nothing); B checked, then run
    assert [(t.well_id, t.check) for t in tasks] == [
        ("A", []), ("B", [str(b)]), ("B", None), ("C", [])
    ]  # fmt: skip
    assert not inputs & set(opens.driver)
    assert {p for p in opens.worker if p in inputs} == {str(b)}
    # of the published files, only those of the well run (once per worker host: OUT shared)
    assert {Path(p).parent for p in published & set(opens.driver)} == {out / "B"}

    monkeypatch.undo()  # a file written just now is hashed again next time
    c.write_bytes(c.read_bytes())  # same bytes, a new ctime
    report, tasks, opens = batch(survey, pattern, out, only_changed=True)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        (w, "skipped", "unchanged") for w in "ABC"
    }
    # A known whole from the stat of its files; B published by its run since; C's input
    assert [(t.well_id, t.check) for t in tasks] == [("B", []), ("C", [str(c)])]
    assert not inputs & set(opens.driver)
    assert not published & set(opens.driver)
    assert remembered(out / "ledger.sqlite")[c.stat().st_ino][1] != c.stat().st_ctime_ns
    # the check left no run behind: one run of A and C, two of B, nothing claimed
    assert sorted((r["well"], r["status"]) for r in runs(out / "ledger.sqlite")) == [
        ("A", "done"),
        ("B", "done"),
        ("B", "done"),
        ("C", "done"),
    ]


def test_files_named_by_parameters_are_known_by_their_stat_like_inputs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """The offset wells, profile and tool-model files a run read are remembered by the stat
    the batch process sees after the run (unchanged since before its task was made): the
    next batch hashes none of them again, and a changed one re-runs exactly its well."""
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)
    monkeypatch.chdir(tmp_path)
    wells = make_fleet(tmp_path)
    registry = load_registry()
    plan = build_plan(load_spec(clearance_pipeline(tmp_path)), registry)  # (the pipeline's
    jobs = jobs_from_manifest(wells, ["reference", "offsets"], WellMetadata())  # validation)
    named = {str(tmp_path / n) for n in ("profile.yaml", "offsets/a.csv", "offsets/b.csv")}
    named |= {str(tmp_path / "models" / n) for n in ("acme.yaml", "base.yaml")}

    report, tasks, opens = run_recorded(plan, registry, jobs, tmp_path / "out")
    assert {(r.well, r.status) for r in report.results} == {("W1", "done"), ("W2", "done")}
    assert named <= set(opens.worker)
    assert not named & set(opens.driver)

    time.sleep(0.01)  # the published files' change times lie before the next batch's looks
    report, tasks, opens = run_recorded(plan, registry, jobs, tmp_path / "out", True)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        ("W1", "skipped", "unchanged"),
        ("W2", "skipped", "unchanged"),
    }
    # no parameter file hashed again: the checks only look at the published directories
    assert [(t.well_id, t.check) for t in tasks] == [("W1", []), ("W2", [])]
    assert not named & set(opens.driver)
    assert not named & set(opens.worker)

    change_one_azimuth(tmp_path / "offsets" / "b.csv")
    report, tasks, opens = run_recorded(plan, registry, jobs, tmp_path / "out", True)
    assert {(r.well, r.status, r.detail) for r in report.results} == {
        ("W1", "skipped", "unchanged"),
        ("W2", "done", "offset file offsets/b.csv changed"),
    }
    offsets_b = str(tmp_path / "offsets" / "b.csv")
    assert [(t.well_id, t.check) for t in tasks] == [("W2", [offsets_b]), ("W2", None)]
    assert not named & set(opens.driver)


def run_recorded(
    plan: Plan, registry: Registry, jobs: list[WellJob], out: Path, only_changed: bool = False
) -> tuple[BatchReport, list[WellTask], Opens]:
    """``jobs`` of a built ``plan`` on the recording executor: the report, tasks, opens."""
    tasks: list[WellTask] = []
    with Opens() as opens:
        factory = lambda setup: Recording(setup, opens, tasks)  # noqa: E731
        registry.executors["recording"] = (
            ExecutorDef("recording", "this process, recorded", factory),
            "builtin.executors",
        )
        options = BatchOptions(
            out_dir=out, workers=1, executor="recording", mode=Mode(only_changed=only_changed)
        )
        report = run_batch(plan, registry, jobs, options, JsonLines(io.StringIO()))
    return report, tasks, opens


def test_an_unchanged_batch_reads_no_well_s_outputs_in_the_batch_process(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    """Through the CLI, in this process (the local pool's workers are other processes: what
    the audit hook sees is the batch process's): once a worker has looked at each well's
    published files, an all-unchanged ``--only-changed`` batch opens none of OUT/<well>'s
    files; a well whose output is gone or whose ``batch.json`` is damaged still runs again."""
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)
    make_wells(tmp_path / "in", ["A", "B", "C"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"

    def cli_batch(*flags: str) -> tuple[dict[str, tuple[str, str]], set[str]]:
        with Opens() as opens:
            result = gyropipe_cli(
                "batch", survey, "--inputs", pattern, "--out", out, "--workers", "1", *flags
            )
        assert result.returncode == 0, result.output
        wells = {p for p in opens.driver if Path(p).parent.parent == out}
        return {w: (r["status"], r["detail"]) for w, r in summary(out).items()}, wells

    assert cli_batch()[0] == {w: ("done", "new well") for w in "ABC"}
    unchanged = {w: ("skipped", "unchanged") for w in "ABC"}
    time.sleep(0.01)
    assert cli_batch("--only-changed")[0] == unchanged  # each publication looked at by a worker
    assert cli_batch("--only-changed") == (unchanged, set())  # known from the stat alone
    # the skipped wells' figures on the batch's page are the ledger's, as read from OUT
    status = gyropipe_cli("status", out, "--html", tmp_path / "status.html")
    assert status.returncode == 0, status.output
    shown = figure_cells((out / "fleet.html").read_text())
    assert shown == figure_cells((tmp_path / "status.html").read_text())
    assert len(shown) == 3 and all(cells[0] != "—" for cells in shown)

    (out / "B" / "trajectory.csv").unlink()  # an output gone: told from its stat
    with open(out / "C" / "batch.json", "a") as fh:  # damaged: its hash is not known
        fh.write("}")
    found, read = cli_batch("--only-changed")
    assert found == {
        "A": ("skipped", "unchanged"),
        "B": ("done", "outputs missing"),
        "C": ("done", "outputs missing"),
    }
    assert {Path(p).parent.name for p in read} <= {"B", "C"}  # (a run's, once per host)
    assert_complete(out / "B")
    assert_complete(out / "C")


def figure_cells(page: str) -> list[list[str]]:
    """Per well row of a fleet page, its numeric figure cells (TD MD, TD TVD, max DLS)."""
    rows = re.findall(r"<tr class=\"s-[a-z]+\">(.*?)</tr>", page)
    return [re.findall(r'<td class="n">([^<]*)(?:<div|</td>)', row)[:3] for row in rows]
