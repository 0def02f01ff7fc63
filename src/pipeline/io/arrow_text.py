"""How the text readers (CSV, LAS) run ``pyarrow.csv`` (threads only when a core is free),
and how they let go of the part of a mapped file they have read.

``pyarrow.csv`` parses blocks on a thread pool, and the CSV reader parses its blocks of
rows on threads of its own. On a machine whose cores are busy (other processes, or the
workers of a batch each reading its own well) threads only add overhead, so one thread
parses small blocks that stay in the processor's cache; when a core is left idle by the
other processes, blocks are parsed in parallel. The other processes' load is the
machine's busy CPU time less this process's own over the time since the previous look
(``/proc/stat``), so a reader that has itself kept a core busy (a batch of files, a
benchmark) does not take its own load for another's; without that, the 1-minute load
average (which counts this process too).
"""

from __future__ import annotations

import mmap
import os
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from itertools import islice
from typing import TypeVar

import pyarrow.csv as pacsv

SERIAL_BLOCK = 1 << 20
"""Bytes parsed per block by one thread (fits the cache; larger blocks are slower)."""
PARALLEL_BLOCK = 512 << 10
"""Bytes per block when blocks are parsed in parallel."""
MAX_WORKERS = 4
"""Threads a reader parses its blocks on at most (each holds a block in memory)."""
SPARE = 0.5
"""Cores' worth of other processes' load still counted as leaving a core idle (system
daemons, a shell)."""
WINDOW = (0.2, 60.0)
"""Seconds since the previous look for which the machine's busy time is compared with
this process's: shorter, the last decision stands; longer, the load average decides."""

T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True)
class CpuTimes:
    """A look at the CPU time spent (s): by the whole machine (all cores, busy only) and by
    this process (all its threads), at a moment of ``time.monotonic``."""

    at: float
    machine: float
    own: float


def cpu_times() -> CpuTimes | None:
    """The machine's and this process's CPU time now; None where ``/proc/stat`` is not."""
    try:
        with open("/proc/stat", "rb") as fh:
            ticks = [int(t) for t in fh.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    if len(ticks) < 5:
        return None
    idle = ticks[3] + ticks[4]  # idle and waiting for I/O; the rest is busy (steal too)
    busy = (sum(ticks) - idle) / os.sysconf("SC_CLK_TCK")
    return CpuTimes(time.monotonic(), busy, time.process_time())


def others_load(before: CpuTimes, after: CpuTimes) -> float:
    """Cores kept busy by other processes between two looks (mean over the interval)."""
    span = after.at - before.at
    return max(0.0, (after.machine - before.machine) - (after.own - before.own)) / span


_last: list[tuple[CpuTimes, bool]] = []
"""The previous look and the decision it gave (a forked process starts afresh: its own CPU
time restarts from zero)."""
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_last.clear)


def use_threads() -> bool:
    """Whether a core is idle beyond this process's: the other processes' load since the
    previous look (within :data:`WINDOW`) at most the cores less one (and
    :data:`SPARE`); else the 1-minute load average at most the cores less one."""
    cores = os.cpu_count() or 1
    if cores < 2:
        return False
    now = cpu_times()
    if now is not None and _last:
        before, decided = _last[0]
        if now.at - before.at < WINDOW[0]:
            return decided
        if now.at - before.at <= WINDOW[1]:
            decided = others_load(before, now) <= cores - 2 + SPARE
            _last[:] = [(now, decided)]
            return decided
    try:
        decided = os.getloadavg()[0] <= cores - 1
    except OSError:  # no load average on this system: trust the pool
        decided = True
    if now is not None:
        _last[:] = [(now, decided)]
    return decided


def workers() -> int:
    """Threads to parse blocks on: every core (at most :data:`MAX_WORKERS`) when
    :func:`use_threads`, else one."""
    return min(os.cpu_count() or 1, MAX_WORKERS) if use_threads() else 1


def read_options(names: list[str], *, threads: bool | None = None) -> pacsv.ReadOptions:
    """Read options for rows without a header line (columns ``names``), threaded per
    :func:`use_threads` unless ``threads`` says otherwise."""
    parallel = use_threads() if threads is None else threads
    return pacsv.ReadOptions(
        column_names=names,
        use_threads=parallel,
        block_size=PARALLEL_BLOCK if parallel else SERIAL_BLOCK,
    )


def release(data: bytes | mmap.mmap, start: int, end: int) -> None:
    """Let the pages of a mapped file that lie wholly within ``data[start:end]`` (read, no
    longer needed) leave this process's memory: a streamed read then holds a few blocks of
    the file, not every page it went through (they stay in the page cache; reading them
    again maps them again). Nothing for bytes, or where the system cannot."""
    if not isinstance(data, mmap.mmap) or not hasattr(mmap, "MADV_DONTNEED"):
        return
    first = -(-start // mmap.PAGESIZE) * mmap.PAGESIZE
    last = end // mmap.PAGESIZE * mmap.PAGESIZE
    if last > first:
        try:
            data.madvise(mmap.MADV_DONTNEED, first, last - first)
        except (OSError, ValueError):  # the system declines: the pages stay
            return


def in_order(items: Iterable[T], work: Callable[[T], R], threads: int) -> Iterator[tuple[T, R]]:
    """Each item with ``work(item)``, in the items' order; with ``threads`` above one, the
    work runs on that many threads, at most ``threads`` items ahead of the one handed
    on (so a stream holds a few blocks, not the file). Work not started when the
    consumer stops is dropped; an exception in the work is raised at its item."""
    if threads <= 1:
        for item in items:
            yield item, work(item)
        return
    source = iter(items)
    with ThreadPoolExecutor(threads) as pool:
        pending = deque((item, pool.submit(work, item)) for item in islice(source, threads))
        try:
            while pending:
                item, future = pending.popleft()
                result = future.result()
                for later in islice(source, 1):
                    pending.append((later, pool.submit(work, later)))
                yield item, result
        finally:
            for _, future in pending:
                future.cancel()
