"""The states the batch process's stat keys and checks bring (``file_hashes``, claims noted
``checking: …``), driven through the CLI on real files and a real ledger: a file replaced
by another of the same size and modification time, hard links listed as two wells, an
input deleted and made again, a ledger of the version before ``file_hashes``,
``--rerun-failed`` with hashes pending, and a batch killed while its checks are out or
inside the transaction that turns checks into runs. In each the next batch leaves every
well done exactly once, and no well whose content changed is skipped as unchanged."""

from __future__ import annotations

import io
import json
import os
import signal
import sqlite3
import subprocess
import time
from pathlib import Path

import pytest
from batch_support import (
    InProcess,
    assert_complete,
    change_one_azimuth,
    corrupt,
    log_events,
    make_wells,
    runs,
    spawn,
    summary,
)

from pipeline.batch import filestate
from pipeline.batch.fingerprint import PENDING, Fingerprint
from pipeline.batch.jobs import jobs_from_glob
from pipeline.batch.ledger import Claimed, Ledger
from pipeline.batch.policy import Check, Mode, Run, Skip
from pipeline.batch.progress import JsonLines
from pipeline.batch.publish import WORK_DIR, clean_work_dir
from pipeline.batch.run import BatchOptions, run_batch
from pipeline.batch.worker import WellOutcome, WellTask
from pipeline.executing import ExecutorDef, ExecutorSetup
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import STAGING_PREFIX
from pipeline.spec import load_spec
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli

TIMEOUT_S = 90


def batch(survey: Path, pattern: Path, out: Path, *args: str) -> dict[str, tuple[str, str]]:
    """One batch through the CLI (in process); (status, detail) by well."""
    result = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, *args)
    assert result.returncode in (0, 1), result.output
    return {w: (r["status"], r["detail"]) for w, r in summary(out).items()}


def same_size_and_times(path: Path, text: str) -> None:
    """Write ``text`` (as long as what ``path`` holds) and set its times back as they were."""
    before = path.stat()
    assert len(text.encode()) == before.st_size
    path.write_text(text)
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert (path.stat().st_size, path.stat().st_mtime_ns) == (before.st_size, before.st_mtime_ns)


def other_azimuth(path: Path) -> str:
    """``path``'s text with the last station's azimuth changed, same length."""
    text = path.read_text()
    head, _, last = text.rstrip("\n").rpartition("\n")
    md, inc, azi = last.split(",")
    new = f"{float(azi) + 1:.2f}".rjust(len(azi), "0")
    assert len(new) == len(azi) and new != azi
    return f"{head}\n{md},{inc},{new}\n"


def published_azimuth(well_dir: Path) -> float:
    """The azimuth of the last station of the trajectory a well published (deg)."""
    return float((well_dir / "trajectory.csv").read_text().splitlines()[-1].split(",")[2])


def done_per_well(out: Path) -> dict[str, int]:
    found: dict[str, int] = {}
    for row in runs(out / "ledger.sqlite"):
        assert row["status"] != "running", row
        if row["status"] == "done":
            found[row["well"]] = found.get(row["well"], 0) + 1
    return found


def test_a_file_replaced_by_one_of_the_same_size_and_times_runs_again(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)  # the first batch's hashes remembered
    a, b, c = make_wells(tmp_path / "in", ["A", "B", "C"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    with sqlite3.connect(out / "ledger.sqlite") as db:
        assert db.execute("SELECT count(*) FROM file_hashes").fetchone()[0] == 3

    same_size_and_times(a, other_azimuth(a))  # in place
    replacement = tmp_path / "B.new"  # a new file renamed over B, B's times given
    replacement.write_text(other_azimuth(b))
    os.utime(replacement, ns=(b.stat().st_atime_ns, b.stat().st_mtime_ns))
    replacement.replace(b)
    text = other_azimuth(c)  # deleted, then made again (its inode may be reused)
    times = c.stat()
    c.unlink()
    c.write_text(text)
    os.utime(c, ns=(times.st_atime_ns, times.st_mtime_ns))

    assert batch(survey, pattern, out, "--only-changed") == {
        w: ("done", "input changed: stations") for w in "ABC"
    }
    for well, path in zip("ABC", (a, b, c), strict=True):
        assert published_azimuth(out / well) == float(path.read_text().rstrip().split(",")[-1])
    assert batch(survey, pattern, out, "--only-changed") == {
        w: ("skipped", "unchanged") for w in "ABC"
    }


def test_hard_links_listed_as_two_wells_change_together(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)
    (first,) = make_wells(tmp_path / "in", ["L1"])
    second = tmp_path / "in" / "L2.csv"
    os.link(first, second)
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    with sqlite3.connect(out / "ledger.sqlite") as db:
        assert db.execute("SELECT count(*) FROM file_hashes").fetchone()[0] == 1  # one inode
    assert batch(survey, pattern, out, "--only-changed") == {
        w: ("skipped", "unchanged") for w in ("L1", "L2")
    }
    change_one_azimuth(first)  # rewritten in place: both names see it
    assert batch(survey, pattern, out, "--only-changed") == {
        w: ("done", "input changed: stations") for w in ("L1", "L2")
    }
    assert done_per_well(out) == {"L1": 2, "L2": 2}


def test_a_ledger_without_file_hashes_is_taken_and_hashes_by_checks(
    tmp_path: Path, survey: Path, monkeypatch: pytest.MonkeyPatch
):
    """The ledger of the version before the cache: the table is made again, and every well
    whose choice turns on a hash is checked, not skipped blind."""
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)
    _, b = make_wells(tmp_path / "in", ["A", "B"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    with sqlite3.connect(out / "ledger.sqlite") as db:
        assert db.execute("SELECT count(*) FROM file_hashes").fetchone()[0] == 2
        db.execute("DROP TABLE file_hashes")
    change_one_azimuth(b)
    assert batch(survey, pattern, out, "--only-changed") == {
        "A": ("skipped", "unchanged"),
        "B": ("done", "input changed: stations"),
    }
    assert done_per_well(out) == {"A": 1, "B": 2}
    with sqlite3.connect(out / "ledger.sqlite") as db:  # learnt again from the checks
        learnt = db.execute("SELECT path FROM file_hashes").fetchall()
    # the inputs, and A's batch.json and run.json as its check found them published (B's
    # were replaced by its run since: not remembered until they settle)
    assert sorted(Path(p).relative_to(tmp_path).as_posix() for (p,) in learnt) == [
        "in/A.csv",
        "in/B.csv",
        "out/A/batch.json",
        "out/A/run.json",
    ]


def test_rerun_failed_with_hashes_pending_runs_the_failed_well_only(tmp_path: Path, survey: Path):
    ok, broken = make_wells(tmp_path / "in", ["ok", "broken"])
    corrupt(broken)
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    ok.write_bytes(ok.read_bytes())  # a new ctime: its hash is pending
    make_wells(tmp_path / "in", ["broken"])  # fixed
    found = batch(survey, pattern, out, "--rerun-failed")
    assert found["ok"] == ("skipped", "last run did not fail")
    assert found["broken"][0] == "done"
    assert found["broken"][1].startswith("previous run failed; input changed: stations")
    assert done_per_well(out) == {"ok": 1, "broken": 1}


@pytest.mark.process("the batch SIGKILLs itself while checks are out or being recorded")
@pytest.mark.parametrize("step", ["submitted:1", "commit:2"], ids=["checks-out", "checks-recorded"])
def test_a_batch_killed_around_its_checks_leaves_each_well_once_and_no_stale_skip(
    tmp_path: Path, survey: Path, step: str
):
    names = [f"K{i}" for i in range(4)]
    paths = make_wells(tmp_path / "in", names)
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    for path in paths[:2]:  # K0, K1: same bytes, new ctime (checked, then skipped)
        path.write_bytes(path.read_bytes())
    for path in paths[2:]:  # K2, K3: new content (checked, then run)
        change_one_azimuth(path)
    args = ("batch", survey, "--inputs", pattern, "--out", out, "--workers", "1")
    log = tmp_path / "killed.log"
    proc = spawn(
        *args, "--only-changed", "--quiet", stderr=log, env={"GYROPIPE_TEST_CRASH_AT": step}
    )
    assert proc.wait(TIMEOUT_S) == -signal.SIGKILL, log.read_text()
    left = [r["note"] for r in runs(out / "ledger.sqlite") if r["status"] == "running"]
    assert left and all(note.startswith("checking: ") for note in left)  # checks were out

    final = spawn(*args, "--only-changed", stderr=tmp_path / "final.log")
    assert final.wait(TIMEOUT_S) == 0, (tmp_path / "final.log").read_text()
    rows = runs(out / "ledger.sqlite")
    assert "running" not in {r["status"] for r in rows}
    assert done_per_well(out) == {"K0": 1, "K1": 1, "K2": 2, "K3": 2}
    for well, path in zip(names, paths, strict=True):
        assert_complete(out / well)
        assert published_azimuth(out / well) == float(path.read_text().rstrip().split(",")[-1])
        history = json.loads(gyropipe_cli("history", well, "--dir", out, "--json").stdout)
        assert [(r["id"], r["status"]) for r in history["runs"]] == [
            (r["id"], r["status"]) for r in rows if r["well"] == well
        ]
    assert batch(survey, pattern, out, "--only-changed") == {
        w: ("skipped", "unchanged") for w in names
    }


def wait_zombie(pid: int) -> None:
    """Wait until child ``pid`` has ended (not waited for: a zombie)."""
    deadline = time.monotonic() + TIMEOUT_S
    while Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z":
        assert time.monotonic() < deadline
        time.sleep(0.005)


def test_the_staging_of_a_worker_that_ended_unreaped_is_removed(tmp_path: Path):
    """A killed batch's workers are orphans; until init reaps them (seconds, or never under
    a container's init that does not) they are zombies, which have ended: their staging
    goes with the next batch's clean-up, not left behind for good."""
    zombie = subprocess.Popen(["true"])  # ended, not waited for: a zombie
    wait_zombie(zombie.pid)
    work = tmp_path / WORK_DIR
    ours = work / f"W.7.{zombie.pid}.staging"  # the batch's staging of run 7 in that worker
    runners = work / f".W.7.{zombie.pid}.staging{STAGING_PREFIX}{zombie.pid}-0a1b2c3d"
    live = work / f"W.8.{os.getpid()}.staging"  # a live worker's: kept
    for path in (ours, runners, live):
        path.mkdir(parents=True)
    try:
        removed = clean_work_dir(tmp_path, active_runs=set())
    finally:
        zombie.wait()
    assert sorted(removed) == sorted([ours, runners])
    assert [p.name for p in work.iterdir()] == [live.name]


def test_a_batch_whose_process_ended_unreaped_is_settled_at_once(tmp_path: Path):
    """Killed, and not yet waited for by whoever started it: a zombie has ended, so its
    claims are settled by the next batch now, not after the heartbeat's 60 s lease."""
    ledger = Ledger(tmp_path / "ledger.sqlite")
    try:
        dead = ledger.start_batch("key", "p.yaml", "0" * 64, tmp_path, {})
        zombie = subprocess.Popen(["true"])
        try:
            wait_zombie(zombie.pid)
            with sqlite3.connect(tmp_path / "ledger.sqlite") as db:
                db.execute("UPDATE batches SET pid = ? WHERE id = ?", (zombie.pid, dead.id))
            assert [b.id for b in ledger.sweep()] == [dead.id]
        finally:
            zombie.wait()
        assert [b.status for b in ledger.batches()] == ["interrupted"]
    finally:
        ledger.close()


@pytest.mark.process("two batch processes share one ledger at once")
def test_two_batches_checking_the_same_wells_run_each_changed_well_once(
    tmp_path: Path, survey: Path
):
    names = [f"C{i}" for i in range(8)]
    paths = make_wells(tmp_path / "in", names)
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    for path in paths[::2]:  # C0, C2…: same bytes, new ctime
        path.write_bytes(path.read_bytes())
    for path in paths[1::2]:  # C1, C3…: new content
        change_one_azimuth(path)
    args = ("batch", survey, "--inputs", pattern, "--out", out, "--workers", "1")
    procs = [
        spawn(*args, "--only-changed", "--quiet", stderr=tmp_path / f"b{i}.log") for i in range(2)
    ]
    codes = [p.wait(TIMEOUT_S) for p in procs]
    assert codes == [0, 0], [(tmp_path / f"b{i}.log").read_text() for i in range(2)]
    assert done_per_well(out) == {w: 1 + i % 2 for i, w in enumerate(names)}
    ran: list[str] = []
    for i in range(2):
        wells = [
            e for e in log_events((tmp_path / f"b{i}.log").read_text()) if e["event"] == "well"
        ]
        assert sorted(e["well"] for e in wells) == names  # each batch accounts for every well
        ran += [e["well"] for e in wells if e["status"] == "done"]
        skipped = {e["detail"] for e in wells if e["status"] == "skipped"}
        assert skipped <= {"unchanged", *(f"done by batch {b} meanwhile" for b in (2, 3))}
    assert sorted(ran) == names[1::2]  # each changed well run by one batch only
    for well, path in zip(names, paths, strict=True):
        assert published_azimuth(out / well) == float(path.read_text().rstrip().split(",")[-1])


def test_a_check_settled_by_another_batch_is_not_made_a_run_on_a_reused_row(tmp_path: Path):
    """A batch silent past its lease (stopped, suspended) is taken for dead and its check
    dropped; SQLite then gives the dropped row's id to the next claim, another well's. The
    stopped batch, going on, must neither rewrite that row nor run its well under that id."""
    fingerprint = Fingerprint({"stations": PENDING}, "p" * 64, {}, "0", {}, {})
    ledger = Ledger(tmp_path / "ledger.sqlite")
    other = Ledger(tmp_path / "ledger.sqlite")
    try:
        stopped = ledger.start_batch("a", "p.yaml", "0" * 64, tmp_path, {})
        check = Check(["stations"], [], 1, Skip("unchanged"))
        claim = ledger.claim("W", stopped, fingerprint, {}, tmp_path / "W", lambda _: check)
        assert isinstance(claim, Claimed) and claim.check == check
        with sqlite3.connect(tmp_path / "ledger.sqlite") as db:  # silent for two leases
            db.execute("UPDATE batches SET heartbeat = heartbeat - 120 WHERE id = ?", (stopped.id,))
        assert [b.id for b in other.sweep()] == [stopped.id]
        later = other.start_batch("b", "p.yaml", "0" * 64, tmp_path, {})
        taken = other.claim("X", later, fingerprint, {}, tmp_path / "X", lambda _: Run(["new"]))
        assert isinstance(taken, Claimed) and taken.run_id == claim.run_id  # the id reused

        assert ledger.checked(claim.run_id, ["input changed: stations"]) is False
        assert ledger.checked(claim.run_id, None) is False
        ledger.finish(WellOutcome("W", claim.run_id, "done", manifest={"inputs": {}}))
        (row,) = runs(tmp_path / "ledger.sqlite")
        assert (row["well"], row["status"], row["reasons"]) == ("X", "running", '["new"]')
    finally:
        ledger.close()
        other.close()


class TakenForDead(InProcess):
    """Runs each task in this process; before the first check, another batch takes this one
    for dead (its heartbeat aged past the lease), settles it and claims a new well ``X``."""

    def __init__(self, setup: ExecutorSetup, ledger: Path) -> None:
        super().__init__(setup)
        self._ledger = ledger
        self.taken: int | None = None

    def run(self, task: WellTask) -> WellOutcome:
        if task.check is not None and self.taken is None:
            with sqlite3.connect(self._ledger) as db:
                db.execute("UPDATE batches SET heartbeat = heartbeat - 120")
            other = Ledger(self._ledger)
            try:
                assert [b.id for b in other.sweep()] == [task.batch_id]
                later = other.start_batch("b", "p.yaml", "0" * 64, self._ledger.parent, {})
                fingerprint = Fingerprint({}, "p" * 64, {}, "0", {}, {})
                new = Run(["new well"])
                claim = other.claim(
                    "X", later, fingerprint, {}, self._ledger.parent / "X", lambda _: new
                )
                assert isinstance(claim, Claimed)
                self.taken = claim.run_id
            finally:
                other.close()
        return super().run(task)


def test_a_batch_taken_for_dead_while_checking_does_not_run_the_well_under_a_lost_claim(
    tmp_path: Path, survey: Path
):
    (path,) = make_wells(tmp_path / "in", ["W"])
    pattern, out = tmp_path / "in" / "*.csv", tmp_path / "out"
    batch(survey, pattern, out)
    change_one_azimuth(path)  # W is checked (its hash unknown), and would run
    registry = load_registry()
    executors: list[TakenForDead] = []

    def factory(setup: ExecutorSetup) -> TakenForDead:
        executors.append(TakenForDead(setup, out / "ledger.sqlite"))
        return executors[-1]

    registry.executors["taken"] = (ExecutorDef("taken", "test", factory), "builtin.executors")
    plan = build_plan(load_spec(survey), registry)
    jobs = jobs_from_glob(str(pattern), ["stations"], WellMetadata())
    options = BatchOptions(out, 1, executor="taken", mode=Mode(only_changed=True))
    report = run_batch(plan, registry, jobs, options, JsonLines(io.StringIO()))
    assert [(r.well, r.status) for r in report.results] == [("W", "interrupted")]
    assert "settled by another batch" in report.results[0].detail
    (executor,) = executors
    rows = {r["id"]: r for r in runs(out / "ledger.sqlite")}
    assert (rows[executor.taken]["well"], rows[executor.taken]["status"]) == ("X", "running")
    assert json.loads((out / "W" / "batch.json").read_text())["run_id"] == 1  # the first run's
