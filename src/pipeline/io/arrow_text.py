"""How the text readers (CSV, LAS) run ``pyarrow.csv``, on the threads
:func:`~pipeline.io.threads.reader_threads` gives them, and how they let go of the part of a
mapped file they have read.

``pyarrow.csv`` parses blocks on a thread pool, and the CSV reader parses its blocks of
rows on threads of its own. On one thread (a batch worker: the workers are the
parallelism) blocks are small, so they stay in the processor's cache; on more, they are
parsed in parallel.
"""

from __future__ import annotations

import mmap
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from itertools import islice
from typing import TypeVar

import pyarrow.csv as pacsv

from pipeline.io import threads as io_threads

SERIAL_BLOCK = 1 << 20
"""Bytes parsed per block by one thread (fits the cache; larger blocks are slower)."""
PARALLEL_BLOCK = 512 << 10
"""Bytes per block when blocks are parsed in parallel."""

T = TypeVar("T")
R = TypeVar("R")


def read_options(names: list[str], *, threads: bool | None = None) -> pacsv.ReadOptions:
    """Read options for rows without a header line (columns ``names``), on pyarrow's threads
    when the readers have more than one (:func:`~pipeline.io.threads.reader_threads`)
    unless ``threads`` says otherwise."""
    parallel = io_threads.reader_threads() > 1 if threads is None else threads
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
