"""Every file-system failure is one located line, never a traceback: a read-only or full
output file system for ``run``, ``convert``, ``simulate``, ``budget`` and ``batch``, and an
input deleted between the run's existence check and its provenance hash (issue 32 item 7).

The read-only and full directories are real (a tmpfs of their own where the tests may
mount, chmod where it binds: ``fs_support``; skipped elsewhere). The tests named
``..._injected`` run everywhere: they make ``os.fsync`` — the last call of every atomic write
and of the run's publishing, where a full disk or a network file system reports ENOSPC —
fail with ENOSPC in this process."""

from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path

import pytest

from pipeline import runner
from tests_support import ROOT, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
STATIONS = ROOT / "examples" / "stations-j-well.csv"
PLAN = ROOT / "examples" / "plans" / "short-j-well.yaml"
READ_ONLY = "Read-only file system (errno 30)"
FULL = "No space left on device (errno 28)"


def commands(out: Path) -> dict[str, tuple[object, ...]]:
    """Each command that writes, writing under ``out``."""
    return {
        "run": ("run", SURVEY, "--input", STATIONS, "--out", out / "well"),
        "convert": ("convert", STATIONS, "--out", out / "stations.parquet"),
        "simulate": ("simulate", PLAN, "--out", out / "sim"),
        "budget": ("budget", PLAN, "--out", out / "budget.csv"),
        "batch": ("batch", SURVEY, "--inputs", STATIONS, "--out", out / "batch", "--quiet"),
    }


def one_error_line(result: object) -> str:
    stderr = result.stderr  # type: ignore[attr-defined]
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in stderr, stderr
    return errors[0]


@pytest.mark.parametrize("command", ["run", "convert", "simulate", "budget", "batch"])
def test_a_read_only_output_directory_is_one_located_line(read_only_dir: Path, command: str):
    args = commands(read_only_dir)[command]
    result = gyropipe_cli(*args)
    assert result.returncode == 1
    line = one_error_line(result)
    assert line.startswith("error: cannot ") and str(read_only_dir) in line
    assert line.endswith(READ_ONLY)


@pytest.mark.parametrize("command", ["run", "convert", "simulate", "budget", "batch"])
def test_a_full_output_file_system_is_one_located_line(full_dir: Path, command: str):
    result = gyropipe_cli(*commands(full_dir)[command])
    assert result.returncode == 1
    line = one_error_line(result)
    assert str(full_dir) in line
    assert line.endswith(FULL) or "SQLITE_FULL" in line or "SQLITE_IOERR" in line
    if command != "batch":  # no partial file is left (a new empty directory may be)
        assert [p.name for p in full_dir.rglob("*") if p.is_file()] == ["filler"]


@pytest.mark.parametrize("command", ["run", "convert", "simulate", "budget"])
def test_a_full_disk_at_fsync_is_one_located_line_injected(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, command: str
):
    def no_space(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", no_space)
    result = gyropipe_cli(*commands(tmp_path)[command])
    assert result.returncode == 1
    line = one_error_line(result)
    assert line.startswith("error: ") and f"cannot write {tmp_path}" in line
    assert line.endswith(FULL)
    if command != "simulate":  # (a simulation's earlier tables stay, each one whole)
        assert [p.name for p in tmp_path.iterdir() if not p.name.startswith(".")] in ([], ["well"])


def test_an_input_deleted_before_its_hash_is_a_located_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """The input exists when the run checks it and is gone when it is hashed."""
    given = tmp_path / "stations.csv"
    shutil.copy(STATIONS, given)
    checked = runner._check_inputs

    def then_deleted(*args: object, **kwargs: object) -> object:
        files = checked(*args, **kwargs)  # type: ignore[arg-type]
        given.unlink()
        return files

    monkeypatch.setattr(runner, "_check_inputs", then_deleted)
    result = gyropipe_cli("run", SURVEY, "--input", given, "--out", tmp_path / "out")
    assert result.returncode == 1
    assert one_error_line(result) == (
        f"error: cannot read {given}: No such file or directory (errno 2)"
    )
    assert not (tmp_path / "out").exists()
