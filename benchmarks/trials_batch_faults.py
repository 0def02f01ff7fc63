"""Fault trials of ``gyropipe batch`` with real processes (issue 32, "done when"):

1. SIGKILL at a random moment (0–0.15 s after a random number of wells, 0–7, is done:
   while it starts, hashes, claims, runs, publishes or records), then the same command
   again to completion;
2. disk full: the output tree, ledger included, on a tmpfs of a random small size (64 KiB
   – 640 KiB), so the batch meets ENOSPC / SQLITE_FULL wherever it happens to be; then the
   file system grown (``mount -o remount,size=64m``: space freed) and the same command
   again to completion. Where no tmpfs can be mounted (not root, no CAP_SYS_ADMIN), the
   batch runs under ``RLIMIT_FSIZE`` instead (``ulimit -f``: a write past the limit fails
   with EFBIG; Python ignores SIGXFSZ), the limit lifted for the second run.

3. SIGKILL of an ``--only-changed`` batch at a random moment (0.4–2 s after its start)
   after a complete batch, half the inputs written again with the same bytes (their hashes
   unknown to the batch process: checked, then skipped) and 1–4 of them changed (checked,
   then run); then the same command to completion. Checks: each well done once more if it
   changed and never else, its published trajectory the one of its input now, no claim
   (nor check) left, the ledger and the tree as below.

After every fault and after every completion the trial checks: the ledger passes SQLite's
``integrity_check`` and every row parses; every ``OUT/<well>`` that exists holds one
complete run (every output of its ``run.json`` with its recorded hash, ``batch.json``,
nothing else); the batch printed no traceback and at most one ``error:`` line; the user's
files — in OUT beside the wells, and the inputs — are byte for byte as before. After the
completion also: every well done exactly once since, its published run the ledger's, no
well that was done before the fault run again, no staging directory left.

    python benchmarks/trials_batch_faults.py [--kills 10] [--fulls 10] [--checks 10] [--seed 1]
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import random
import resource
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "batch")]

from batch_support import (  # noqa: E402
    change_one_azimuth,
    children,
    gone,
    make_wells,
    survey_pipeline,
)

from pipeline.batch.records import batch_row, run_row  # noqa: E402
from tests_support import gyropipe  # noqa: E402

WELLS = [f"T{i:02d}" for i in range(8)]
TIMEOUT_S = 300


def tree_hashes(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def user_files(out: Path) -> None:
    """A user's files in OUT beside the wells (the batch must leave them alone)."""
    (out / "notes").mkdir(parents=True, exist_ok=True)
    (out / "notes" / "field-notes.txt").write_text("rig 7, run 2: keep\n" * 50)
    (out / "README.txt").write_text("client deliverables go here\n")


def batch_args(pipeline: Path, inputs: Path, out: Path) -> list[str]:
    return [
        *gyropipe(), "batch", str(pipeline), "--inputs", str(inputs / "*.csv"), "--out",
        str(out), "--workers", "2", "--quiet",
    ]  # fmt: skip


def wait_gone(pids: set[int]) -> None:
    deadline = time.monotonic() + 60
    while not all(gone(p) for p in pids):
        if time.monotonic() > deadline:
            raise AssertionError(f"workers {sorted(pids)} outlived their batch")
        time.sleep(0.01)


def ledger_rows(out: Path) -> tuple[list[dict[str, object]], list[str]]:
    """The runs (parsed as gyropipe parses them) and the problems found in the ledger."""
    path = out / "ledger.sqlite"
    if not path.exists():
        return [], []
    problems = []
    with sqlite3.connect(path) as db:
        db.row_factory = sqlite3.Row
        if db.execute("PRAGMA integrity_check").fetchone()[0] != "ok":
            problems.append("integrity_check failed")
        tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not tables:  # killed before its schema was committed: an empty database
            return [], problems
        rows = [dict(r) for r in db.execute("SELECT * FROM runs ORDER BY id")]
        for row in db.execute("SELECT * FROM batches"):
            try:
                batch_row(dict(row))
            except Exception as exc:  # any failure is a finding
                problems.append(f"batch row {row['id']}: {exc}")
    for row in rows:
        try:
            run_row(row)
        except Exception as exc:  # (as above)
            problems.append(f"run row {row['id']}: {exc}")
    return rows, problems


def tree_problems(out: Path) -> list[str]:
    """Every published well directory holds one complete run."""
    problems = []
    for well in WELLS:
        well_dir = out / well
        if not well_dir.exists():
            continue
        try:
            manifest = json.loads((well_dir / "run.json").read_text())
            marker = json.loads((well_dir / "batch.json").read_text())
            listed = {o["file"] for o in manifest["outputs"]}
            names = {p.name for p in well_dir.iterdir()}
            if names != listed | {"run.json", "batch.json"} or marker["well_id"] != well:
                problems.append(f"{well}: holds {sorted(names)}")
            for entry in manifest["outputs"]:
                data = (well_dir / entry["file"]).read_bytes()
                if hashlib.sha256(data).hexdigest() != entry["sha256"]:
                    problems.append(f"{well}: {entry['file']} is not the recorded file")
        except (OSError, ValueError, KeyError) as exc:
            problems.append(f"{well}: {type(exc).__name__}: {exc}")
    return problems


def output_problems(stderr: str) -> list[str]:
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    found = ["a traceback"] if "Traceback" in stderr else []
    return found + ([f"{len(errors)} error lines"] if len(errors) > 1 else [])


def complete_problems(out: Path, done_before: dict[str, int]) -> list[str]:
    """After a completed batch: each well done, published as recorded, none run twice."""
    rows, problems = ledger_rows(out)
    for well in WELLS:
        done = [r for r in rows if r["well"] == well and r["status"] == "done"]
        if not done:
            problems.append(f"{well}: not done")
            continue
        if well in done_before and done[-1]["id"] != done_before[well]:
            problems.append(f"{well}: done before the fault, run again")
        marker = out / well / "batch.json"
        if not marker.exists() or json.loads(marker.read_text())["run_id"] != done[-1]["id"]:
            problems.append(f"{well}: the published run is not the ledger's")
    if any(r["status"] == "running" for r in rows):
        problems.append("a run is still claimed")
    work = out / ".gyropipe-batch"
    if work.exists() and any(work.iterdir()):
        problems.append(f"staging left: {sorted(p.name for p in work.iterdir())}")
    return problems


def finished(out: Path) -> bool:
    """Whether the ledger says the batch finished (killed later, while it wrote its summary
    or exited): the same command then runs every well again, by design, and is no resume."""
    uri = f"file:{out / 'ledger.sqlite'}?mode=ro"
    with contextlib.suppress(sqlite3.Error), sqlite3.connect(uri, uri=True) as db:
        row = db.execute("SELECT status FROM batches ORDER BY id DESC LIMIT 1").fetchone()
        return row is not None and row[0] == "finished"
    return False


def done_count(out: Path) -> int:
    """Runs done so far, read while the batch writes (0 while the ledger cannot be read)."""
    try:
        with sqlite3.connect(f"file:{out / 'ledger.sqlite'}?mode=ro", uri=True) as db:
            return int(db.execute("SELECT count(*) FROM runs WHERE status = 'done'").fetchone()[0])
    except sqlite3.Error:
        return 0


def done_runs(out: Path) -> dict[str, int]:
    """Wells whose run is done, or published though still claimed (killed in between)."""
    rows, _ = ledger_rows(out)
    found = {str(r["well"]): int(str(r["id"])) for r in rows if r["status"] == "done"}
    for r in rows:
        marker = out / str(r["well"]) / "batch.json"
        if r["status"] == "running" and marker.exists():
            with contextlib.suppress(ValueError, KeyError):
                if json.loads(marker.read_text())["run_id"] == r["id"]:
                    found[str(r["well"])] = int(str(r["id"]))
    return found


def finish(args: list[str], out: Path, done_before: dict[str, int]) -> list[str]:
    final = subprocess.run(args, capture_output=True, text=True, timeout=TIMEOUT_S)
    problems = output_problems(final.stderr)
    if final.returncode != 0:
        problems.append(f"exit {final.returncode}: {final.stderr.strip()[-300:]}")
    return problems + complete_problems(out, done_before) + tree_problems(out)


def kill_trial(rng: random.Random, pipeline: Path, inputs: Path, out: Path) -> list[str] | None:
    user_files(out)
    user_before = tree_hashes(out)
    args = batch_args(pipeline, inputs, out)
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    target = rng.randrange(len(WELLS))  # wells done (or published) when the kill comes
    delay = rng.uniform(0.0, 0.15)
    workers: set[int] = set()
    deadline = time.monotonic() + TIMEOUT_S
    while done_count(out) < target and proc.poll() is None and time.monotonic() < deadline:
        workers |= children(proc.pid)
        time.sleep(0.02)
    end = time.monotonic() + delay
    while time.monotonic() < end and proc.poll() is None:
        workers |= children(proc.pid)
        time.sleep(0.01)
    workers |= children(proc.pid)
    proc.send_signal(signal.SIGKILL)
    stderr = proc.communicate(timeout=TIMEOUT_S)[1]
    wait_gone(workers)
    killed = proc.returncode == -signal.SIGKILL
    problems = [] if killed else output_problems(stderr)
    problems += ledger_rows(out)[1] + tree_problems(out)
    ended = killed and finished(out)
    done_before = done_runs(out) if killed and not ended else {}
    problems += finish(args, out, done_before)
    after = tree_hashes(out)
    problems += [f"user file changed: {n}" for n, h in user_before.items() if after.get(n) != h]
    when = f"kill {delay:.2f} s after {target} wells done"
    if ended:
        when += " (the ledger had recorded the batch's end: not counted)"
    print(f"  {when}: {len(done_before)} done before; {problems or 'OK'}"
          if killed else f"  {when}: the batch had finished first (not counted)")  # fmt: skip
    return problems if killed and not ended else None


@contextlib.contextmanager
def tmpfs(where: Path, size: int) -> Iterator[bool]:
    where.mkdir(parents=True, exist_ok=True)
    mount = ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)]
    mounted = subprocess.run(mount, capture_output=True).returncode == 0
    try:
        yield mounted
    finally:
        if mounted:
            subprocess.run(["umount", "-l", str(where)], check=True)


def full_trial(
    rng: random.Random, pipeline: Path, inputs: Path, out: Path, use_tmpfs: bool
) -> list[str]:
    size = rng.randint(64, 640) * 1024
    args = batch_args(pipeline, inputs, out)
    with tmpfs(out, size) if use_tmpfs else contextlib.nullcontext(False) as mounted:
        user_files(out)
        user_before = tree_hashes(out)

        def limited() -> None:  # without a tmpfs: no file of the batch grows past size/16
            resource.setrlimit(resource.RLIMIT_FSIZE, (size // 16, size // 16))

        failed = subprocess.run(
            args,
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            preexec_fn=None if mounted else limited,
        )
        problems = output_problems(failed.stderr) + ledger_rows(out)[1] + tree_problems(out)
        errors = [x for x in failed.stderr.splitlines() if x.startswith("error:")]
        failing = [json.loads(x) for x in failed.stderr.splitlines() if x.startswith("{")]
        wells_failed = [e for e in failing if e.get("event") == "well" and e["status"] == "failed"]
        done_before = {} if finished(out) else done_runs(out)
        if mounted:
            subprocess.run(["mount", "-o", "remount,size=64m", str(out)], check=True)
        problems += finish(args, out, done_before)
        after = tree_hashes(out)
        problems += [f"user file changed: {n}" for n, h in user_before.items() if after.get(n) != h]
    what = (
        errors[0][:150] if errors else f"exit {failed.returncode}, {len(wells_failed)} wells failed"
    )
    shown = wells_failed[0]["detail"][:110] if wells_failed and not errors else ""
    print(f"  {size // 1024} KiB: {what} {shown}; {problems or 'OK'}")
    return problems


def last_azimuth(path: Path, column: int) -> float:
    """The azimuth of the last row of a station listing (column 2) or a trajectory CSV."""
    return float(path.read_text().rstrip("\n").splitlines()[-1].split(",")[column])


def check_trial(rng: random.Random, pipeline: Path, root: Path) -> list[str]:
    inputs, out = root / "in", root / "out"
    paths = make_wells(inputs, WELLS)
    args = batch_args(pipeline, inputs, out)
    problems = finish(args, out, {})
    rewritten = rng.sample(paths, len(paths) // 2)
    changed = set(rng.sample(rewritten, rng.randint(1, 4)))
    for path in rewritten:
        path.write_bytes(path.read_bytes())
        if path in changed:
            change_one_azimuth(path)
    proc = subprocess.Popen([*args, "--only-changed"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    delay = rng.uniform(0.4, 2.0)  # the batch process takes about 0.5 s to start
    workers: set[int] = set()
    end = time.monotonic() + delay
    while time.monotonic() < end and proc.poll() is None:
        workers |= children(proc.pid)
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    stderr = proc.communicate(timeout=TIMEOUT_S)[1]
    wait_gone(workers)
    killed = proc.returncode == -signal.SIGKILL
    checking = sum(r["status"] == "running" for r in ledger_rows(out)[0])
    problems += ([] if killed else output_problems(stderr)) + ledger_rows(out)[1]
    problems += finish([*args, "--only-changed"], out, {}) + tree_problems(out)
    rows = ledger_rows(out)[0]
    for well, path in zip(WELLS, paths, strict=True):
        done = sum(r["well"] == well and r["status"] == "done" for r in rows)
        if done != 1 + (path in changed):
            problems.append(f"{well}: done {done} times, changed: {path in changed}")
        if last_azimuth(out / well / "trajectory.csv", 2) != last_azimuth(path, 2):
            problems.append(f"{well}: its published trajectory is not of its input now")
    when = f"kill {delay:.2f} s after the start" if killed else "finished before the kill"
    print(f"  {when}, {len(changed)} changed, {checking} claims left: {problems or 'OK'}")
    return problems


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=10)
    parser.add_argument("--fulls", type=int, default=10)
    parser.add_argument("--checks", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    options = parser.parse_args()
    rng = random.Random(options.seed)
    with tempfile.TemporaryDirectory(prefix="gyropipe-trials-") as tmp:
        root = Path(tmp)
        pipeline = survey_pipeline(root)
        inputs = root / "in"
        make_wells(inputs, WELLS)
        inputs_before = tree_hashes(inputs)
        bad: dict[str, int] = {"kill": 0, "full": 0, "check": 0}
        print(f"SIGKILL trials ({options.kills}), {len(WELLS)} wells, 2 workers:")
        kills = 0
        for i in range(4 * options.kills):  # until that many kills landed mid-batch
            found = kill_trial(rng, pipeline, inputs, root / f"kill{i}")
            kills += found is not None
            bad["kill"] += bool(found)
            if kills == options.kills:
                break
        with tmpfs(root / "probe", 65536) as can_mount:
            pass
        how = "a tmpfs of its own" if can_mount else "RLIMIT_FSIZE (no tmpfs can be mounted)"
        print(f"disk-full trials ({options.fulls}), the output tree on {how}:")
        for i in range(options.fulls):
            out = root / f"full{i}"
            bad["full"] += bool(full_trial(rng, pipeline, inputs, out, can_mount))
        print(f"--only-changed SIGKILL trials ({options.checks}), checks out:")
        for i in range(options.checks):
            bad["check"] += bool(check_trial(rng, pipeline, root / f"check{i}"))
        if tree_hashes(inputs) != inputs_before:
            print("the input files changed!")
            bad["kill"] += 1
        print(
            f"SIGKILL: {kills - bad['kill']}/{kills} consistent; "
            f"disk full: {options.fulls - bad['full']}/{options.fulls} consistent; "
            f"--only-changed: {options.checks - bad['check']}/{options.checks} consistent"
        )
        sys.exit(1 if any(bad.values()) else 0)


if __name__ == "__main__":
    main()
