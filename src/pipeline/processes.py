"""Whether the process that owns a file still runs, on this host.

A process id is reused once the kernel's pid counter wraps (``/proc/sys/kernel/pid_max``,
often 32768): a pid alone can name another process than the one that wrote a staging
directory. :func:`owner_alive` therefore also asks, on Linux, whether the process now holding
the pid started before the entry was last written; elsewhere the pid alone decides. A zombie
(a process that has ended and that its parent has not reaped yet, as a killed batch's workers
can be for a while) still answers to its pid but runs no more: it counts as gone.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

START_SLACK_S = 0.05
"""the clock tick of a process's start time (10 ms) and the file system's timestamp grain"""


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` runs on this host (one of another user counts; a zombie —
    ended, not yet reaped by its parent — does not: it writes nothing any more)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    fields = _stat(pid)
    return fields is None or fields[0] not in ("Z", "X")


def owner_alive(pid: int, entry: Path) -> bool:
    """Whether process ``pid``, which wrote ``entry``, still runs: a process holding the pid
    now that started after ``entry`` was last modified is another one (module docstring)."""
    if not process_alive(pid):
        return False
    started = _started(pid)
    try:
        modified = entry.stat().st_mtime
    except OSError:
        return True
    return started is None or started <= modified + START_SLACK_S


def _stat(pid: int) -> list[str] | None:
    """The fields of ``/proc/<pid>/stat`` after the command name (state first); None where
    there is no such file (not Linux, or the process has gone)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None


def _started(pid: int) -> float | None:
    """When process ``pid`` started (POSIX seconds); None where /proc does not tell."""
    fields = _stat(pid)
    try:
        ticks = int(fields[19]) if fields is not None else None  # field 22: starttime
    except (ValueError, IndexError):
        return None
    if ticks is None:
        return None
    since_boot = ticks / os.sysconf("SC_CLK_TCK")
    booted = time.time() - time.clock_gettime(time.CLOCK_BOOTTIME)
    return booted + since_boot
