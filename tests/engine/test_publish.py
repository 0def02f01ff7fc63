"""A run publishes its output directory in one step: a process SIGKILLed at each step of the
publish leaves either the complete previous run or the complete new one, never a mixture
(real processes, killed by the signal at a chosen step; the runs around them in process), and the next run cleans up."""

from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from pipeline import atomic
from pipeline.errors import FileSystemError
from tests_support import ROOT, gyropipe_cli, stage, survey_stages, write_pipeline

SAMPLE = ROOT / "examples" / "stations-j-well.csv"
STAGES = [
    *survey_stages(),
    stage(
        "csv", "write", {"table": "trajectory.trajectory"}, writer="csv", filename="trajectory.csv"
    ),
]
KILLER = textwrap.dedent(
    """
    import os, signal, sys
    import pipeline.atomic as atomic
    import pipeline.runner as runner

    def die(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGKILL)

    step = os.environ["KILL_AT"]
    if step == "manifest":      # every output staged, run.json not yet written
        runner.atomic_write_bytes = die
    elif step == "publish":     # run.json staged, the directories not yet swapped
        runner.replace_dir = die
    elif step == "swapped":     # just after the swap, the old run not yet moved to trash
        exchange = atomic._exchange
        atomic._exchange = lambda a, b: (exchange(a, b), die())
    elif step == "trash":       # the old run moved to trash, not yet deleted
        atomic.shutil.rmtree = die
    from pipeline.cli import main
    sys.argv = ["gyropipe", *sys.argv[1:]]
    main()
    """
)


def run(tmp: Path, out: Path, vs_azimuth: float, kill_at: str | None = None) -> int:
    """``gyropipe run`` of :data:`STAGES` into ``out``: in this process, or in a process
    SIGKILLed at step ``kill_at``; its exit status."""
    pipeline = write_pipeline(tmp, STAGES, name="publish")
    args = ["run", str(pipeline), "--input", str(SAMPLE), "--out", str(out)]
    args += ["--set", f"trajectory.vs_azimuth={vs_azimuth}"]
    if kill_at is None:
        return gyropipe_cli(*args).returncode
    env = {**os.environ, "KILL_AT": kill_at}
    done = subprocess.run(
        [sys.executable, "-c", KILLER, *args], capture_output=True, text=True, env=env, timeout=120
    )
    return done.returncode


def complete_run(out: Path) -> float:
    """The vs_azimuth (0 or 45°) of the one complete run ``out`` holds: exactly the files its
    run.json lists, each with its recorded hash."""
    manifest = json.loads((out / "run.json").read_text())
    listed = {entry["file"]: entry["sha256"] for entry in manifest["outputs"]}
    assert {p.name for p in out.iterdir()} == {*listed, "run.json"}
    for name, digest in listed.items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest, name
    table = pq.read_table(out / "trajectory.trajectory.parquet")
    north, east = table["north"].to_numpy(), table["east"].to_numpy()
    vs = table["vertical_section"].to_numpy()
    for azimuth in (0.0, 45.0):
        a = math.radians(azimuth)
        if abs(vs - (north * math.cos(a) + east * math.sin(a))).max() < 1e-9:
            return azimuth
    raise AssertionError("the trajectory is neither run's")


@pytest.mark.process("the run is SIGKILLed at a step of its publish")
@pytest.mark.parametrize(
    ("step", "published"),
    [("manifest", 0.0), ("publish", 0.0), ("swapped", 45.0), ("trash", 45.0)],
)
def test_a_run_killed_while_publishing_leaves_one_complete_run(
    tmp_path: Path, step: str, published: float
) -> None:
    out = tmp_path / "out"
    assert run(tmp_path, out, 0.0) == 0
    assert complete_run(out) == 0.0
    assert run(tmp_path, out, 45.0, kill_at=step) == -9
    assert complete_run(out) == published
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".out.")]
    assert leftovers  # the dead run's staging (or trash) stays until the next run
    assert run(tmp_path, out, 45.0) == 0
    assert complete_run(out) == 45.0
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".out.")]


def test_a_directory_holding_other_files_is_not_replaced(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    pipeline = write_pipeline(tmp_path, STAGES, name="publish")
    args = ["run", str(pipeline), "--input", str(SAMPLE), "--out", str(out)]
    done = gyropipe_cli(*args)
    assert done.returncode == 2
    assert "holds files that are not a previous run's (notes.txt)" in done.stderr
    assert (out / "notes.txt").read_text() == "mine"


def test_every_file_is_fsynced_once_the_writeback_of_all_was_started(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """fsync_files fsyncs each file (the writeback started for them all first is a hint
    only), and names a failing one as the caller publishes it."""
    paths = [tmp_path / f"{name}.bin" for name in "abc"]
    for path in paths:
        path.write_bytes(b"x" * 5000)
    events: list[tuple[str, str]] = []
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}")))
        real_fsync(fd)

    def start(fd: int, offset: int, length: int, flags: int) -> int:
        events.append(("start", os.readlink(f"/proc/self/fd/{fd}")))
        return 0

    monkeypatch.setattr(atomic, "_sync_file_range", lambda: start)
    monkeypatch.setattr(os, "fsync", fsync)
    atomic.fsync_files(paths, lambda path: path)
    names = [str(path) for path in paths]
    assert events == [("start", name) for name in names] + [("fsync", name) for name in names]

    def no_space(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(FileSystemError, match=r"cannot write .*published\.bin"):
        atomic.fsync_files(paths, lambda path: tmp_path / "out" / "published.bin")
