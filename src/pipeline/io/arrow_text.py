"""How the text readers (CSV, LAS) run ``pyarrow.csv`` (threads only when a core is free),
and how they let go of the part of a mapped file they have read.

``pyarrow.csv`` parses blocks on a thread pool. On a machine whose cores are busy (other
processes, or the workers of a batch each reading its own well) the threads only add
overhead, so one thread parses small blocks that stay in the processor's cache; when the
1-minute load average leaves a core idle, the pool parses in parallel.
"""

from __future__ import annotations

import mmap
import os

import pyarrow.csv as pacsv

SERIAL_BLOCK = 1 << 20
"""Bytes parsed per block by one thread (fits the cache; larger blocks are slower)."""
PARALLEL_BLOCK = 512 << 10
"""Bytes per block when blocks are parsed in parallel."""


def use_threads() -> bool:
    """Whether a core is idle (1-minute load average at least one below the core count)."""
    cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except OSError:  # no load average on this system: trust the pool
        return cores > 1
    return cores > 1 and load <= cores - 1


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
