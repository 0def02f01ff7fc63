"""Helpers of the batch tests: wells made of copies of the bundled station listing (and
corrupt copies) in a temporary directory, the CLI run as a real subprocess (in process:
``tests_support.gyropipe_cli``), and independent readers of the ledger (plain sqlite3) and
of the published outputs, and an executor that runs each task in this process."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sqlite3
import subprocess
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from pipeline.batch.worker import WellOutcome, WellTask, run_well
from pipeline.executing import ExecutorSetup
from tests_support import ROOT, gyropipe, stage, survey_stages, write_pipeline

STATIONS = ROOT / "examples" / "stations-j-well.csv"


def survey_pipeline(directory: Path) -> Path:
    """Write the survey test pipeline into ``directory``: the survey job of
    pipelines/survey.yaml without its report (fast, and fixed while the shipped pipeline
    evolves)."""
    trajectory = {"table": "trajectory.trajectory"}
    stages = [
        *survey_stages(),
        stage(
            "dls_check", "check", trajectory, ["results"], check="dls_limit", params={"limit": 10.0}
        ),
        stage("export_csv", "write", trajectory, writer="csv", filename="trajectory.csv"),
    ]
    return write_pipeline(directory, stages, name="survey")


def spawn(
    *args: str | Path, stderr: Path, env: Mapping[str, str] | None = None
) -> subprocess.Popen[str]:
    """``gyropipe ARGS`` as a real subprocess, its stderr to a file (``env`` added to the
    environment)."""
    with open(stderr, "w") as err:
        return subprocess.Popen(
            [*gyropipe(), *map(str, args)],
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            cwd=ROOT,
            env={**os.environ, "COLUMNS": "200", **(env or {})},
        )


def make_wells(directory: Path, names: list[str]) -> list[Path]:
    """A copy of the bundled station listing per name (``<name>.csv``)."""
    directory.mkdir(parents=True, exist_ok=True)
    text = STATIONS.read_text()
    paths = []
    for name in names:
        path = directory / f"{name}.csv"
        path.write_text(text)
        paths.append(path)
    return paths


def corrupt(path: Path) -> str:
    """Make ``path`` a station listing whose 15th data row lost a cell; returns the
    1-based line number of that row."""
    lines = STATIONS.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    bad = header + 15
    lines[bad] = ",".join(lines[bad].split(",")[:2])
    path.write_text("\n".join(lines) + "\n")
    return str(bad + 1)


def change_one_azimuth(path: Path) -> None:
    """Change the azimuth of the last station (a real content change)."""
    lines = path.read_text().rstrip("\n").splitlines()
    md, inc, _ = lines[-1].split(",")
    lines[-1] = f"{md},{inc},45.00"
    path.write_text("\n".join(lines) + "\n")


def runs(ledger: Path) -> list[dict[str, Any]]:
    """Every run row of a ledger, oldest first (read with plain sqlite3)."""
    with sqlite3.connect(ledger) as db:
        db.row_factory = sqlite3.Row
        return [dict(r) for r in db.execute("SELECT * FROM runs ORDER BY id")]


def batches(ledger: Path) -> list[dict[str, Any]]:
    with sqlite3.connect(ledger) as db:
        db.row_factory = sqlite3.Row
        return [dict(r) for r in db.execute("SELECT * FROM batches ORDER BY id")]


def summary(out: Path) -> dict[str, dict[str, Any]]:
    """summary.json rows by well."""
    return {row["well"]: row for row in json.loads((out / "summary.json").read_text())["wells"]}


def log_events(stderr: str) -> list[dict[str, Any]]:
    """The JSON log lines of a batch."""
    return [json.loads(line) for line in stderr.splitlines() if line.startswith("{")]


def assert_complete(well_dir: Path) -> dict[str, Any]:
    """``well_dir`` holds one complete run: every output of its run.json on disk with the
    recorded hash, batch.json naming a run, nothing else. Returns run.json."""
    manifest = json.loads((well_dir / "run.json").read_text())
    listed = {o["file"] for o in manifest["outputs"]}
    assert sorted(p.name for p in well_dir.iterdir()) == sorted(listed | {"run.json", "batch.json"})
    for entry in manifest["outputs"]:
        path = well_dir / entry["file"]
        assert entry["path"] == str(path)
        assert hashlib.sha256(path.read_bytes()).hexdigest() == entry["sha256"]
    assert json.loads((well_dir / "batch.json").read_text())["well_id"] == well_dir.name
    return manifest


def output_hashes(out: Path, wells: list[str]) -> dict[str, dict[str, str]]:
    return {
        w: {
            o["file"]: o["sha256"]
            for o in json.loads((out / w / "run.json").read_text())["outputs"]
        }
        for w in wells
    }


def no_staging_left(out: Path) -> bool:
    work = out / ".gyropipe-batch"
    return not work.exists() or not any(work.iterdir())


def gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (a zombie still answers kill(0); it is not running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] == "Z"
    except OSError:  # reaped meanwhile
        return True


def children(pid: int) -> set[int]:
    """The processes ``pid`` started (e.g. a batch's pool workers), as Linux lists them."""
    found: set[int] = set()
    try:
        for task in Path(f"/proc/{pid}/task").iterdir():
            found |= {int(p) for p in (task / "children").read_text().split()}
    except OSError:  # it has ended
        pass
    return found


class Opens:
    """The files this process opens through Python (an audit hook, installed once for the
    test process), while active (``with``): by the batch process's own code, or inside
    :meth:`worker` blocks (an executor running a task in this process)."""

    def __init__(self) -> None:
        self.driver: list[str] = []
        self.worker: list[str] = []
        self._in_worker = False

    def __enter__(self) -> Opens:
        if not _ACTIVE and not _HOOKED:
            sys.addaudithook(_audit)
            _HOOKED.append(True)
        _ACTIVE.append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        _ACTIVE.remove(self)

    @contextlib.contextmanager
    def worker_code(self) -> Iterator[None]:
        self._in_worker = True
        try:
            yield
        finally:
            self._in_worker = False

    def record(self, path: str) -> None:
        (self.worker if self._in_worker else self.driver).append(path)


_ACTIVE: list[Opens] = []
_HOOKED: list[bool] = []  # the hook cannot be removed: installed once


def _audit(event: str, args: tuple[Any, ...]) -> None:
    # open() and io.open() give their mode; os.open() gives None: a descriptor opened to
    # fstat a file (the batch's stat key) is not a read, and is left out — unless it is then
    # opened for reading (open(fd), as the hashing does): named by what the descriptor is
    if event != "open" or not _ACTIVE:
        return
    path, mode = args[0], args[1]
    if mode is None:
        return
    if isinstance(path, int):
        try:
            path = os.readlink(f"/proc/self/fd/{path}")
        except OSError:
            return
    if isinstance(path, str | bytes | os.PathLike):
        _ACTIVE[-1].record(os.fsdecode(path))


class InProcess:
    """An executor running each task at once in this process (as the ``serial`` test plugin
    does); ``wait`` hands back what has run since. Tests act around :meth:`run`."""

    def __init__(self, setup: ExecutorSetup) -> None:
        self.ref = setup.ref
        self._finished: list[WellOutcome] = []

    def run(self, task: WellTask) -> WellOutcome:
        return run_well(task, self.ref)

    def submit(self, task: WellTask) -> None:
        self._finished.append(self.run(task))

    def wait(self, timeout: float) -> list[WellOutcome]:
        finished, self._finished = self._finished, []
        return finished

    def close(self, cancel: bool) -> None:
        self._finished = []
