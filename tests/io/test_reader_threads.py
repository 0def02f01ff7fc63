"""The readers' thread count, decided in one place (:mod:`pipeline.io.threads`): alone, every
core the process may run on; in a batch worker, one; told otherwise by the environment."""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

import pyarrow as pa
import pytest

from pipeline.io import threads as io_threads
from pipeline.io.threads import ENV, ThreadSettingError, reader_threads, set_reader_threads
from tests_support import ROOT, gyropipe_cli, plugin_site, stage, survey_stages, write_pipeline

SAMPLE = ROOT / "examples" / "stations-j-well.csv"
NOTER = """
import json
import os

import pyarrow as pa

from pipeline.hookspecs import hookimpl
from pipeline.io.threads import reader_threads
from pipeline.registry import WriterDef


def write(table, path, well):
    with open(path, "w") as fh:
        json.dump(
            {
                "reader_threads": reader_threads(),
                "pyarrow_cpu_count": pa.cpu_count(),
                "cores": len(os.sched_getaffinity(0)),
                "pid": os.getpid(),
            },
            fh,
        )


@hookimpl
def gyropipe_register_writers(register):
    register(WriterDef("threadnote", "notes the readers' threads where it runs", "csv", write))
"""
"""A writer plugin that writes, instead of the table, the thread setting of the process it
runs in (a batch worker, or the process of ``gyropipe run``)."""


@pytest.fixture(autouse=True)
def unset(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Each test starts and ends with no count set and no :data:`ENV`."""
    monkeypatch.delenv(ENV, raising=False)
    set_reader_threads(None)
    yield
    set_reader_threads(None)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return plugin_site(tmp_path_factory.mktemp("site"), {"threadnote": ("1.0", NOTER)})


def noting(directory: Path) -> Path:
    """A survey pipeline whose trajectory is written by the noting writer (``note.csv``)."""
    table = {"table": "trajectory.trajectory"}
    note = stage("note", "write", table, writer="threadnote", filename="note.csv")
    return write_pipeline(directory, [*survey_stages(), note], name="noting")


needs_affinity = pytest.mark.skipif(
    not hasattr(os, "sched_getaffinity") or not hasattr(os, "fork"),
    reason="no CPU affinity or fork on this system",
)


@needs_affinity
def test_alone_a_reader_uses_every_core_the_process_may_run_on() -> None:
    assert reader_threads() == len(os.sched_getaffinity(0))
    pid = os.fork()
    if pid == 0:  # the child, bound to one core (as by taskset): exit 0 if it sees one
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
        os._exit(0 if reader_threads() == 1 else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


def test_a_count_set_sizes_pyarrow_pool_and_unsetting_restores_it() -> None:
    before = pa.cpu_count()
    set_reader_threads(1)
    assert (reader_threads(), pa.cpu_count()) == (1, 1)
    set_reader_threads(3)
    assert (reader_threads(), pa.cpu_count()) == (3, 3)
    set_reader_threads(None)
    assert pa.cpu_count() == before
    assert reader_threads() == io_threads.available_cores()
    with pytest.raises(ValueError, match="expected at least 1"):
        set_reader_threads(0)


def test_the_environment_sets_the_count(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(ENV, "3")
    assert (reader_threads(), pa.cpu_count()) == (3, 3)


@pytest.mark.parametrize("value", ["0", "two", "-1", "1.5"])
def test_a_bad_environment_value_is_named(monkeypatch: pytest.MonkeyPatch, value: str) -> None:
    monkeypatch.setenv(ENV, value)
    with pytest.raises(ThreadSettingError) as caught:
        reader_threads()
    assert str(caught.value) == (
        f"GYROPIPE_READ_THREADS={value!r}: expected a whole number of threads, at least 1"
    )


@needs_affinity
def test_a_batch_worker_reads_on_one_thread_and_a_run_on_every_core(
    site: Path, tmp_path: Path
) -> None:
    """Through the command line: the writer plugin notes the setting where it runs, in each
    worker of a two-worker batch and in the process of ``gyropipe run``."""
    wells = tmp_path / "in"
    wells.mkdir()
    for name in ("a", "b"):
        (wells / f"{name}.csv").write_bytes(SAMPLE.read_bytes())
    out = tmp_path / "batch"
    pipeline = noting(tmp_path)
    args = ("batch", pipeline, "--inputs", wells / "*.csv", "--out", out, "--workers", "2")
    batch = gyropipe_cli(*args, site=site)
    assert batch.returncode == 0, batch.output
    notes = [json.loads((out / name / "note.csv").read_text()) for name in "ab"]
    assert {(n["reader_threads"], n["pyarrow_cpu_count"]) for n in notes} == {(1, 1)}
    assert os.getpid() not in {n["pid"] for n in notes}  # noted in the workers

    alone = tmp_path / "run"
    run = gyropipe_cli("run", pipeline, "--input", SAMPLE, "--out", alone, site=site)
    assert run.returncode == 0, run.output
    note = json.loads((alone / "note.csv").read_text())
    assert note["pid"] == os.getpid()
    assert note["reader_threads"] == note["cores"] == len(os.sched_getaffinity(0))


def test_a_bad_environment_value_fails_a_run_with_its_name(tmp_path: Path) -> None:
    pipeline = write_pipeline(tmp_path, survey_stages(), name="survey")
    out = tmp_path / "out"
    run = gyropipe_cli("run", pipeline, "--input", SAMPLE, "--out", out, env={ENV: "two"})
    assert run.returncode != 0
    assert "GYROPIPE_READ_THREADS='two': expected a whole number of threads, at least 1" in (
        run.stderr
    )
    assert "Traceback" not in run.output
    assert not out.exists()
