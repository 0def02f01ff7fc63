"""How many threads the readers work on, decided here for the whole process.

Alone (``gyropipe run``, the Python API) a reader uses every core this process may run on
(:func:`os.sched_getaffinity`: a ``taskset`` or a container's CPU set counts, not the
machine's cores); in a batch worker, one: the workers are the parallelism, and a worker's
threads would only contend for the cores the other workers use. The batch worker says so
(:func:`set_reader_threads`); a process may be told so from outside by the environment
variable :data:`ENV` (read once, at the first read).

The CSV and LAS readers parse their blocks on that many threads (:mod:`pipeline.io.arrow_text`,
:mod:`pipeline.io.las.fast`); the Parquet and MCAP readers let pyarrow decode on its threads
only when it is above one. A count set here (or by :data:`ENV`) also sizes pyarrow's CPU
pool (``pyarrow.set_cpu_count``), so pyarrow's own threads follow it; left alone, pyarrow's
pool is as pyarrow sizes it.
"""

from __future__ import annotations

import os

import pyarrow as pa

from pipeline.errors import GyropipeError

ENV = "GYROPIPE_READ_THREADS"
"""Environment variable: the readers' thread count (a whole number ≥ 1)."""

_set: list[int] = []
"""The count set for this process (empty: every core it may run on)."""
_pyarrow_default: list[int] = []
"""pyarrow's CPU pool size before a count was first set (restored by ``None``)."""


class ThreadSettingError(GyropipeError):
    """:data:`ENV` holds something other than a whole number of threads ≥ 1."""


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity; the machine's cores where the
    system has no affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # no affinity on this system (macOS, Windows)
        return os.cpu_count() or 1


def reader_threads() -> int:
    """Threads a reader works on: the count set (:func:`set_reader_threads`, else
    :data:`ENV`), else :func:`available_cores`."""
    if _set:
        return _set[0]
    raw = os.environ.get(ENV, "").strip()
    if raw:
        set_reader_threads(_parsed(raw))
        return _set[0]
    return available_cores()


def set_reader_threads(count: int | None) -> None:
    """Make the readers of this process work on ``count`` threads, and pyarrow's CPU pool
    that size; ``None``: back to every core the process may run on, pyarrow's pool to its
    size before."""
    if count is None:
        _set.clear()
        if _pyarrow_default:
            pa.set_cpu_count(_pyarrow_default[0])
        return
    if count < 1:
        raise ValueError(f"reader threads: {count}; expected at least 1")
    if not _pyarrow_default:
        _pyarrow_default.append(pa.cpu_count())
    _set[:] = [count]
    if pa.cpu_count() != count:
        pa.set_cpu_count(count)


def _parsed(raw: str) -> int:
    try:
        count = int(raw)
    except ValueError:
        count = 0
    if count < 1:
        raise ThreadSettingError(f"{ENV}={raw!r}: expected a whole number of threads, at least 1")
    return count
