"""Crash safety and concurrency with real processes: a batch SIGKILLed mid-run and started
again (twice), a worker process killed by the OS, a run that published just before its batch
died, and two batches on one ledger at once."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from batch_support import (
    STATIONS,
    assert_complete,
    batches,
    children,
    gone,
    log_events,
    make_wells,
    no_staging_left,
    runs,
    spawn,
    summary,
)

from pipeline.batch.executors import LocalExecutor
from pipeline.batch.ledger import Ledger
from pipeline.batch.publish import WORK_DIR, staging_owner
from pipeline.batch.worker import WellOutcome, WellTask
from pipeline.executing import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec
from tests_support import gyropipe_cli

TIMEOUT_S = 90


def wait_for(condition: Callable[[], bool], proc: subprocess.Popen[str] | None = None) -> None:
    """Poll ``condition`` every 5 ms; fail if ``proc`` ends first or after TIMEOUT_S."""
    deadline = time.monotonic() + TIMEOUT_S
    while not condition():
        if proc is not None and proc.poll() is not None:
            pytest.fail(f"the batch ended (exit {proc.returncode}) before the kill")
        if time.monotonic() > deadline:
            pytest.fail("timed out")
        time.sleep(0.005)


def done_runs(ledger: Path) -> dict[str, dict[str, object]]:
    """Done runs by well, read-only (retries while the batch holds a lock)."""
    if not ledger.exists():
        return {}
    try:
        with sqlite3.connect(f"file:{ledger}?mode=ro", uri=True) as db:
            db.row_factory = sqlite3.Row
            rows = db.execute("SELECT * FROM runs WHERE status = 'done'").fetchall()
    except sqlite3.Error:
        return {}
    return {r["well"]: dict(r) for r in rows}


def runs_by_well(ledger: Path) -> dict[str, dict[str, object]]:
    """Done runs by well, once the batch is dead (its ledger readable for certain: a read
    failing here must not pass for "nothing done", which would skip waiting for workers)."""
    return {r["well"]: r for r in runs(ledger) if r["status"] == "done"}


def published_unrecorded(out: Path) -> dict[str, int]:
    """Wells whose claimed ('running') run had published its outputs when the batch died."""
    found = {}
    for row in runs(out / "ledger.sqlite"):
        marker = out / row["well"] / "batch.json"
        published = marker.exists() and json.loads(marker.read_text())["run_id"] == row["id"]
        if row["status"] == "running" and published:
            found[row["well"]] = int(row["id"])
    return found


@pytest.mark.process("the batch is SIGKILLed mid-run")
def test_sigkilled_batch_restarted_completes_and_recomputes_nothing(tmp_path: Path, survey: Path):
    names = [f"W{i:02d}" for i in range(16)]
    make_wells(tmp_path / "in", names)
    out = tmp_path / "out"
    ledger = out / "ledger.sqlite"
    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out, "--workers", "1")

    finished_before: dict[str, int] = {}
    for attempt, kill_after in enumerate((2, 7)):
        proc = spawn(*args, "--quiet", stderr=tmp_path / f"kill{attempt}.log")
        wait_for(lambda n=kill_after: len(done_runs(ledger)) >= n, proc)
        workers = children(proc.pid)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(TIMEOUT_S)
        done = runs_by_well(ledger)
        assert len(done) < len(names), "the kill came too late to test anything"
        # the batch's workers do not outlive it (no orphan goes on writing outputs)
        workers |= {int(str(r["worker"]).rsplit(":", 1)[1]) for r in done.values() if r["worker"]}
        wait_for(lambda w=workers: all(gone(pid) for pid in w))
        finished_before.update({w: int(str(r["id"])) for w, r in done.items()})
        finished_before.update(published_unrecorded(out))  # killed between publish and record

    final = spawn(*args, stderr=tmp_path / "final.log")
    assert final.wait(TIMEOUT_S) == 0, (tmp_path / "final.log").read_text()

    rows = runs(ledger)
    for well in names:
        mine = [r for r in rows if r["well"] == well]
        assert [r["status"] for r in mine].count("done") == 1, mine
        done = next(r for r in mine if r["status"] == "done")
        if well in finished_before:  # finished before a kill: never run again
            assert done["id"] == finished_before[well]
            assert mine[-1] is done
        assert {r["status"] for r in mine} <= {"done", "interrupted"}
        published = assert_complete(out / well)
        assert json.loads((out / well / "batch.json").read_text())["run_id"] == done["id"]
        assert published["outputs"] == json.loads(str(done["outputs"]))
    assert no_staging_left(out)
    assert [b["status"] for b in batches(ledger)] == ["interrupted", "interrupted", "finished"]
    last = summary(out)
    assert {w for w, r in last.items() if r["status"] == "skipped"} == set(finished_before)
    assert all(
        r["detail"].startswith("done before the interruption (batch ")
        for w, r in last.items()
        if w in finished_before
    )


def big_listing(path: Path, rows: int) -> None:
    """The bundled listing's header over ``rows`` stations every 0.5 m (a slower well)."""
    lines = STATIONS.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    body = (f"{0.5 * i:.2f},{min(0.01 * i, 60.0):.2f},37.00" for i in range(rows))
    path.write_text("\n".join([*lines[: header + 1], *body]) + "\n")


@pytest.mark.process("a worker of a running batch is SIGKILLed")
def test_a_worker_killed_by_the_os_costs_only_a_retry(tmp_path: Path, survey: Path):
    (tmp_path / "in").mkdir()
    for i in range(3):
        big_listing(tmp_path / "in" / f"B{i}.csv", 30_000)
    out = tmp_path / "out"
    proc = spawn(
        "batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out, "--workers", "2",
        "--quiet", stderr=tmp_path / "log",
    )  # fmt: skip

    def running_worker() -> int | None:
        for staging in (out / WORK_DIR).glob("*.staging"):
            owner = staging_owner(staging)  # a running well's staging: <well>.<run>.<pid>.staging
            if owner is not None and owner[1] is not None:
                return owner[1]
        return None

    wait_for(lambda: running_worker() is not None, proc)
    victim = running_worker()
    assert victim is not None and victim != proc.pid
    os.kill(victim, signal.SIGKILL)
    assert proc.wait(TIMEOUT_S) == 0, (tmp_path / "log").read_text()
    rows = runs(out / "ledger.sqlite")
    assert sorted(r["well"] for r in rows) == ["B0", "B1", "B2"]  # one run each
    assert {r["status"] for r in rows} == {"done"}
    assert str(victim) not in {str(r["worker"]).rsplit(":", 1)[1] for r in rows}
    for well in ("B0", "B1", "B2"):
        assert_complete(out / well)


DYING_BATCH = """
import os, signal, sys
from pathlib import Path
from pipeline.batch.fingerprint import PENDING, PlanIdentity
from pipeline.batch.jobs import jobs_from_glob
from pipeline.batch.ledger import Ledger
from pipeline.batch.policy import Mode, decide
from pipeline.batch.worker import WellTask, run_well
from pipeline.executing import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec
from pipeline.well import WellMetadata

survey, pattern, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
registry = load_registry()
plan = build_plan(load_spec(survey), registry)
(job,) = jobs_from_glob(pattern, ["stations"], WellMetadata())
fingerprint = PlanIdentity.of(plan, registry).fingerprint(job, {"stations": PENDING})
ledger = Ledger(out / "ledger.sqlite")
batch = ledger.start_batch("key", survey, plan.digest, out, {})
claim = ledger.claim(
    "W", batch, fingerprint, {}, out / "W",
    lambda state: decide(Mode(), state, fingerprint, batch_id=batch.id,
                         batch_started=batch.started, resume_since=None),
)
ref = PipelineRef(survey, plan.spec)
task = WellTask("W", claim.run_id, batch.id, ref.digest,
                {"stations": str(job.inputs["stations"])}, {}, str(out), fingerprint.to_json())
assert run_well(task, ref).status == "done"
print(claim.run_id, flush=True)
os.kill(os.getpid(), signal.SIGKILL)  # dies after publishing, before recording the outcome
"""


@pytest.mark.process("the batch SIGKILLs itself after a publish")
def test_a_run_published_before_its_batch_died_is_recovered_not_recomputed(
    tmp_path: Path, survey: Path
):
    make_wells(tmp_path / "in", ["W"])
    out = tmp_path / "out"
    pattern = str(tmp_path / "in" / "*.csv")
    dying = subprocess.run(
        [sys.executable, "-c", DYING_BATCH, str(survey), pattern, str(out)],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert dying.returncode == -signal.SIGKILL, dying.stderr
    run_id = int(dying.stdout)
    assert runs(out / "ledger.sqlite")[0]["status"] == "running"

    ledger = Ledger(out / "ledger.sqlite")
    (swept,) = ledger.sweep()
    recovered = ledger.run(run_id)
    ledger.close()
    assert swept.status == "running" and recovered is not None
    assert recovered.status == "done"
    assert recovered.note == "recovered: its outputs were published before its batch process ended"
    assert recovered.outputs == assert_complete(out / "W")["outputs"]
    # started again, the batch does not recompute the well
    again = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--only-changed")
    assert again.returncode == 0, again.output
    assert summary(out)["W"] == {**summary(out)["W"], "status": "skipped", "detail": "unchanged"}
    assert [r["id"] for r in runs(out / "ledger.sqlite")] == [run_id]


def _wait_until_open(procs: list[subprocess.Popen[str]], path: Path) -> None:
    """Until every process in ``procs`` holds ``path`` open (Linux ``/proc/PID/fd``)."""
    deadline = time.monotonic() + TIMEOUT_S
    waiting = list(procs)
    while waiting and time.monotonic() < deadline:
        for proc in list(waiting):
            fds = Path(f"/proc/{proc.pid}/fd")
            if proc.poll() is not None or any(_links_to(fd, path) for fd in fds.iterdir()):
                waiting.remove(proc)
        time.sleep(0.02)
    assert not waiting, "a batch process never opened the ledger"


def _links_to(fd: Path, path: Path) -> bool:
    try:
        return os.readlink(fd) == str(path)
    except OSError:  # closed meanwhile
        return False


@pytest.mark.process("two batch processes share one ledger at once")
def test_two_batches_on_one_ledger_run_each_well_once(tmp_path: Path, survey: Path):
    names = [f"W{i:02d}" for i in range(12)]
    make_wells(tmp_path / "in", names)
    out = tmp_path / "out"
    out.mkdir()
    ledger_path = out / "ledger.sqlite"
    Ledger(ledger_path).close()
    hold = sqlite3.connect(ledger_path, isolation_level=None)
    hold.execute("BEGIN IMMEDIATE")  # each batch waits on it at its first write: they start
    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    procs = [
        spawn(*args, "--workers", "1", "--only-changed", "--quiet", stderr=tmp_path / f"b{i}.log")
        for i in range(2)
    ]
    _wait_until_open(procs, ledger_path)  # together however slowly a loaded machine starts them
    hold.execute("COMMIT")
    hold.close()
    codes = [p.wait(TIMEOUT_S) for p in procs]
    assert codes == [0, 0], [(tmp_path / f"b{i}.log").read_text() for i in range(2)]

    rows = runs(out / "ledger.sqlite")
    assert sorted(r["well"] for r in rows) == names  # exactly one run per well, none failed
    assert {r["status"] for r in rows} == {"done"}
    assert len({r["batch"] for r in rows}) == 2  # both batches did work
    per_batch: dict[int, set[str]] = {}
    for log in (tmp_path / "b0.log", tmp_path / "b1.log"):
        events = log_events(log.read_text())
        batch = next(e["batch"] for e in events if e["event"] == "start")
        wells = [e for e in events if e["event"] == "well"]
        assert sorted(e["well"] for e in wells) == names  # each batch accounts for every well
        per_batch[batch] = {e["well"] for e in wells if e["status"] == "done"}
        skipped = {e["detail"] for e in wells if e["status"] == "skipped"}
        assert skipped <= {"unchanged", *(f"done by batch {b} meanwhile" for b in (1, 2))}
    assert set.union(*per_batch.values()) == set(names)
    assert set.intersection(*per_batch.values()) == set()
    for well in names:
        assert_complete(out / well)


def test_a_pool_broken_between_waits_still_takes_new_wells(tmp_path: Path, survey: Path):
    """A worker dies while the batch is busy elsewhere: the next submit meets a broken pool
    (the CI failure of 2026-11-21) and must go to a fresh pool, not end the batch."""
    make_wells(tmp_path / "in", ["W"])
    registry = load_registry()
    plan = build_plan(load_spec(survey), registry)
    ref = PipelineRef(str(survey), plan.spec)
    executor = LocalExecutor(2, ref)
    try:
        pool = executor._pool  # forked: both workers start; from the forkserver: one, on demand
        wait_for(lambda: len(pool._processes or {}) >= 1)
        os.kill(next(iter(pool._processes or {})), signal.SIGKILL)
        wait_for(lambda: bool(pool._broken))
        inputs = {"stations": str(tmp_path / "in" / "W.csv")}
        task = WellTask("W", 1, 1, ref.digest, inputs, {}, str(tmp_path / "out"), "{}")
        executor.submit(task)
        outcomes: list[WellOutcome] = []
        wait_for(lambda: bool(outcomes.extend(executor.wait(0.05)) or outcomes))
    finally:
        executor.close(cancel=True)
    assert [(o.well_id, o.status) for o in outcomes] == [("W", "done")], outcomes
    assert_complete(tmp_path / "out" / "W")


def staging_pids(out: Path) -> set[int]:
    """The worker processes named by the staging directories left in OUT (the next batch
    removes those of processes that no longer exist: a zombie still does, until this
    machine's init reaps it)."""
    work = out / ".gyropipe-batch"
    names = [p.name.split(".") for p in work.iterdir()] if work.is_dir() else []
    return {int(parts[-2]) for parts in names if len(parts) > 2 and parts[-2].isdigit()}


@pytest.mark.process("the batch SIGKILLs itself at each step of its loop")
@pytest.mark.parametrize(
    "kills",
    [("commit:2",), ("committed:2",), ("submitted:2",), ("received:1", "received:1")],
    ids=["in-transaction", "committed", "submitted", "received-then-checking"],
)
def test_a_batch_killed_at_any_step_resumes_with_every_well_done_once(
    tmp_path: Path, survey: Path, kills: tuple[str, ...]
):
    names = [f"K{i}" for i in range(6)]
    make_wells(tmp_path / "in", names)
    out = tmp_path / "out"
    ledger = out / "ledger.sqlite"
    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out, "--workers", "2")
    finished_before: dict[str, int] = {}
    for attempt, step in enumerate(kills):
        log = tmp_path / f"kill{attempt}.log"
        proc = spawn(*args, "--quiet", stderr=log, env={"GYROPIPE_TEST_CRASH_AT": step})
        assert proc.wait(TIMEOUT_S) == -signal.SIGKILL, log.read_text()
        done = runs_by_well(ledger)
        workers = {int(str(r["worker"]).rsplit(":", 1)[1]) for r in done.values() if r["worker"]}
        wait_for(lambda w=workers: all(gone(pid) for pid in w))
        wait_for(lambda: not any(Path(f"/proc/{pid}").exists() for pid in staging_pids(out)))
        finished_before.update({w: int(str(r["id"])) for w, r in done.items()})
        finished_before.update(published_unrecorded(out))  # killed between publish and record

    final = spawn(*args, stderr=tmp_path / "final.log")
    assert final.wait(TIMEOUT_S) == 0, (tmp_path / "final.log").read_text()
    rows = runs(ledger)
    assert "running" not in {r["status"] for r in rows}  # no claim (nor check) left behind
    for well in names:
        mine = [r for r in rows if r["well"] == well]
        assert [r["status"] for r in mine].count("done") == 1, mine  # done exactly once
        done_row = next(r for r in mine if r["status"] == "done")
        if well in finished_before:  # finished before a kill: never run again
            assert done_row["id"] == finished_before[well]
        assert {r["status"] for r in mine} <= {"done", "interrupted"}
        assert_complete(out / well)
        assert json.loads((out / well / "batch.json").read_text())["run_id"] == done_row["id"]
        history = json.loads(gyropipe_cli("history", well, "--dir", out, "--json").stdout)
        assert [(r["id"], r["status"]) for r in history["runs"]] == [
            (r["id"], r["status"]) for r in mine
        ]
    assert no_staging_left(out)
    last = summary(out)
    assert {w for w, r in last.items() if r["status"] == "skipped"} == set(finished_before)
    assert {r["status"] for w, r in last.items() if w not in finished_before} == {"done"}


# --------------------------------------------------------- a ledger half made when killed

MAKING_LEDGER = """
import os, signal, sys
from pathlib import Path
from pipeline.batch import ledger_file

put_in_place = ledger_file._put_in_place
def at_the_link(aside, path):
    if sys.argv[2] == "die":
        os.kill(os.getpid(), signal.SIGKILL)  # made beside its place, never linked
    print(aside, flush=True)
    sys.stdin.readline()  # held half made while the test opens the ledger
    put_in_place(aside, path)
ledger_file._put_in_place = at_the_link
ledger_file.make_ledger(Path(sys.argv[1]))
"""


def making_ledger(path: Path, how: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", MAKING_LEDGER, str(path), how],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )


def beside(path: Path) -> list[str]:
    return sorted(p.name for p in path.parent.iterdir() if p.name.startswith(f".{path.name}."))


@pytest.mark.process("the batch is SIGKILLed while it makes the ledger")
def test_a_ledger_half_made_by_a_killed_batch_is_removed_by_the_next(tmp_path: Path, survey: Path):
    out = tmp_path / "out"
    out.mkdir()
    dying = making_ledger(out / "ledger.sqlite", "die")
    assert dying.wait(TIMEOUT_S) == -signal.SIGKILL
    (left, *_) = beside(out / "ledger.sqlite")
    assert left.startswith(f".ledger.sqlite.{dying.pid}.") and left.endswith(".new")
    assert not (out / "ledger.sqlite").exists()
    make_wells(tmp_path / "in", ["W"])
    pattern = str(tmp_path / "in" / "*.csv")
    result = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out)
    assert result.returncode == 0, result.output
    assert beside(out / "ledger.sqlite") == []
    assert runs(out / "ledger.sqlite")[0]["status"] == "done"


@pytest.mark.process("another process is making the ledger meanwhile")
def test_a_ledger_being_made_by_a_live_process_is_left_to_it(tmp_path: Path):
    path = tmp_path / "ledger.sqlite"
    maker = making_ledger(path, "hold")
    assert maker.stdout is not None and maker.stdin is not None
    aside = Path(maker.stdout.readline().strip())
    Ledger(path).close()  # the ledger made here; the other one's file is its own
    assert aside.exists()
    maker.stdin.write("\n")
    maker.stdin.close()
    assert maker.wait(TIMEOUT_S) == 0
    assert beside(path) == [] and runs(path) == []


def test_a_ledger_half_made_elsewhere_is_removed_once_old(tmp_path: Path):
    """Made on another host (its process cannot be asked) or by an earlier version (no pid
    in the name): removed only once older than a ledger takes to make, by far."""
    path = tmp_path / "ledger.sqlite"
    names = [
        f".ledger.sqlite.{os.getpid() + 1}.other-host.example.{'a' * 32}.new",
        f".ledger.sqlite.{os.getpid() + 1}.other-host.example.{'a' * 32}.new-wal",
        f".ledger.sqlite.{'b' * 32}.new",
    ]
    for name in names:
        (tmp_path / name).write_bytes(b"SQLite format 3\0")
    (tmp_path / ".ledger.sqlite.notes.newer").write_text("not the ledger's")
    Ledger(path).close()
    assert beside(path) == sorted([*names, ".ledger.sqlite.notes.newer"])
    old = time.time() - 2 * 3600
    for name in names:
        os.utime(tmp_path / name, (old, old))
    Ledger(path).close()
    assert beside(path) == [".ledger.sqlite.notes.newer"]
