"""A staging entry's owner is the process that wrote it, not whichever process holds its pid
later (pids are reused once the kernel's counter wraps)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pipeline.processes import owner_alive, process_alive

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="start times from /proc")


def test_a_process_started_after_the_entry_was_written_does_not_own_it(tmp_path: Path):
    entry = tmp_path / "W01.7.123.staging"
    entry.mkdir()
    time.sleep(0.2)  # well beyond the start time's tick and the slack
    later = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        assert process_alive(later.pid)
        assert not owner_alive(later.pid, entry)  # the pid of a process that came later
    finally:
        later.kill()
        later.wait()


def test_a_live_process_owns_what_it_wrote_and_a_gone_one_nothing(tmp_path: Path):
    entry = tmp_path / "mine.staging"
    entry.mkdir()
    assert owner_alive(os.getpid(), entry)  # this process started before writing it
    (entry / "x").write_bytes(b"")  # written again: still its owner
    assert owner_alive(os.getpid(), entry)
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    assert not owner_alive(gone.pid, entry)


def test_a_zombie_is_not_alive(tmp_path: Path):
    """Ended but not yet reaped (its parent has not waited): it writes nothing any more."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    deadline = time.monotonic() + 30
    while Path(f"/proc/{child.pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z":
        assert time.monotonic() < deadline, "the child did not end"
        time.sleep(0.01)
    try:
        os.kill(child.pid, 0)  # the pid still answers …
        assert not process_alive(child.pid)  # … but no process runs
    finally:
        child.wait()
