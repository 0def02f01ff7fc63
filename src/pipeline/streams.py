"""Streamed tables: a schema known up front and record batches produced on demand.

A :class:`TableStream` is what a *streamed* port of a stage carries instead of a whole
``pyarrow.Table`` (``StageDef.streamed_inputs`` / ``streamed_outputs``): its ``schema``
(fields, units, schema metadata) is fixed before any row is read, and every pass over it
(``for batch in stream``) produces its record batches afresh, one at a time, from its source —
a file read again, or an upstream stream recomputed. So a stream can feed several consumers
without ever being held whole; memory is bounded by a few batches, not by the survey.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, TypeAlias

import pyarrow as pa

BATCH_ROWS = 65_536
"""Rows per batch when a whole table is cut into a stream (the generic fallback)."""
KEEP_BYTES = 32 << 20
"""The most bytes a stream's pass may decode to for the plan to keep it for the stream's
other consumers (:meth:`TableStream.kept`, :func:`~pipeline.ports.kept`): the samples
of a continuous survey of 163,601 samples × 9 columns, read by the readings stage and then
the continuous stage, decode to 11.8 MB (≈ 7 ms a pass); a longer survey is read again."""


@dataclass(frozen=True)
class TableStream:
    """Record batches of ``schema``; each iteration is a new pass over the source.

    ``passes()`` returns a fresh iterator of record batches every time it is called; every
    batch has the stream's column names and types (its schema metadata is the stream's).
    """

    schema: pa.Schema
    passes: Callable[[], Iterator[pa.RecordBatch]]
    holds: frozenset[Any] = frozenset()
    """table contracts (classes) every batch of every pass is known to satisfy: a wrapper
    that checks one of them again can pass the stream through unchecked"""
    nbytes: int | None = None
    """bytes a pass decodes to, where the source tells before it is read (a Parquet file's
    footer); None where it does not"""

    def __iter__(self) -> Iterator[pa.RecordBatch]:
        return self.passes()

    @property
    def column_names(self) -> list[str]:
        return list(self.schema.names)

    @classmethod
    def from_table(cls, table: pa.Table, rows: int = BATCH_ROWS) -> TableStream:
        """A stream of slices of ``table`` (zero-copy), ``rows`` at a time."""

        def slices() -> Iterator[pa.RecordBatch]:
            for start in range(0, table.num_rows, rows):
                yield from table.slice(start, rows).combine_chunks().to_batches()

        return cls(table.schema, slices)

    @classmethod
    def of_batches(
        cls, schema: pa.Schema, passes: Callable[[], Iterator[pa.RecordBatch]]
    ) -> TableStream:
        """A stream whose batches are relabelled with ``schema`` (its metadata, its field
        metadata such as units) as they pass; names and types must already match."""

        def relabelled() -> Iterator[pa.RecordBatch]:
            for batch in passes():
                yield pa.RecordBatch.from_arrays(batch.columns, schema=schema)

        return cls(schema, relabelled)

    def replace_schema_metadata(self, metadata: dict[bytes, bytes] | None) -> TableStream:
        """The same stream with other schema metadata (on every batch too); the columns and
        their metadata are unchanged, so it holds the same contracts."""
        relabelled = TableStream.of_batches(self.schema.with_metadata(metadata or {}), self.passes)
        return TableStream(relabelled.schema, relabelled.passes, self.holds, self.nbytes)

    def kept(self, passes: int) -> TableStream:
        """The same stream, its source read once for ``passes`` passes: the first pass run
        to its end keeps its batches, and the ``passes − 1`` passes after it yield them
        instead of reading the source again, the last of them letting each go as it passes
        on. Passes after those read the source again, as every pass does while none has run
        to its end. What is held is one pass, from its first consumer to its last, or until
        :func:`release` lets it go (a reader that made no pass). Its passes are read one
        after another (a run's stages, on one thread), not at once."""
        return TableStream(self.schema, KeptPasses(self.passes, passes), self.holds, self.nbytes)

    def read_all(self) -> pa.Table:
        """One pass concatenated into a table (for a consumer that needs it whole)."""
        return pa.Table.from_batches(list(self), schema=self.schema)


class KeptPasses:
    """The passes of a kept stream (:meth:`TableStream.kept`): ``source`` read once for
    ``passes`` passes."""

    def __init__(self, source: Callable[[], Iterator[pa.RecordBatch]], passes: int) -> None:
        self.source = source
        self.held: list[pa.RecordBatch] | None = None
        self.left = passes - 1
        """passes still to be given the kept batches"""

    def __call__(self) -> Iterator[pa.RecordBatch]:
        if self.held is not None:
            self.left -= 1
            if self.left:
                yield from self.held
                return
            batches, self.held = self.held[::-1], None
            while batches:
                yield batches.pop()
            return
        batches = []
        for batch in self.source():
            if self.left:
                batches.append(batch)
            yield batch
        if self.left:
            self.held = batches

    def release(self) -> None:
        """Let the kept batches go: every later pass reads the source again."""
        self.held, self.left = None, 0


def release(value: Port) -> None:
    """Let a kept stream's held batches go (:meth:`TableStream.kept`; others: nothing)."""
    if isinstance(value, TableStream) and isinstance(value.passes, KeptPasses):
        value.passes.release()


Port: TypeAlias = "pa.Table | TableStream"
"""What a port carries: a whole table, or a stream of record batches (a streamed port)."""


def as_stream(value: Port) -> TableStream:
    """``value`` as a stream: a table is cut into slices of :data:`BATCH_ROWS` rows."""
    return value if isinstance(value, TableStream) else TableStream.from_table(value)


def as_table(value: Port) -> pa.Table:
    """``value`` as a whole table: a stream is read in one pass and concatenated."""
    return value.read_all() if isinstance(value, TableStream) else value


def use_returning_memory_pool() -> None:
    """Allocate so that freed memory goes back to the operating system: Arrow from jemalloc
    (unless ``ARROW_DEFAULT_MEMORY_POOL`` chooses; the system allocator where pyarrow has no
    jemalloc), and glibc's ``malloc`` with a fixed mmap threshold of :data:`MMAP_THRESHOLD`
    (glibc's default moves up to the largest block freed, 32 MiB at most, after which arrays
    of a survey's length stay in the heap and a process's peak grew with the survey it
    streamed) and trim threshold of :data:`TRIM_THRESHOLD`. jemalloc purges freed pages
    after its decay time and reuses them meanwhile: it peaks lower than the system
    allocator, which maps and faults in every block of a batch afresh (Parquet decoding took
    2.5× as long), and than mimalloc, pyarrow's default on Linux (benchmarks/bench_memory.py)."""
    if not os.environ.get("ARROW_DEFAULT_MEMORY_POOL"):
        try:
            pool = pa.jemalloc_memory_pool()
        except NotImplementedError:  # a pyarrow built without jemalloc
            pool = pa.system_memory_pool()
        pa.set_memory_pool(pool)
    if sys.platform == "linux" and not os.environ.get("MALLOC_MMAP_THRESHOLD_"):
        try:
            libc = ctypes.CDLL("libc.so.6")
        except OSError:  # not glibc
            return
        libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)
        if not os.environ.get("MALLOC_TRIM_THRESHOLD_"):
            libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)


MMAP_THRESHOLD = 1 << 20
"""bytes: NumPy arrays up to this size come from glibc's heap and are reused, larger ones are
mapped and unmapped whole. Above a column of a batch or of a continuous-integration chunk
(65,536 rows × 8 B = 512 KiB, plus a filter's overlap), which at 128 KiB were mapped and
faulted in afresh for every temporary: a continuous well took 2.73 s CPU then, 2.00 s now,
for peaks 20–30 MiB higher (benchmarks/bench_memory.py; still within the targets)."""
TRIM_THRESHOLD = 64 << 20
"""bytes: free memory at the top of glibc's heap kept for reuse, not handed back (so a
process's resident memory stays at most this much above what it uses). A fixed mmap
threshold also fixes this one at glibc's 128 KiB, below which every batch's temporaries
(a few 512 KiB columns) were given back when freed and faulted in afresh for the next
batch: a point-gyro well's position readings took 1.7× their CPU time then. At 4 MiB a
continuous well's heap (≈ 47 MiB at its top, ≈ 30 MiB of it a chunk's temporaries, freed
and taken again chunk after chunk and by the series' passes) was still handed back and
faulted in again: 25,900 page faults a well (bench_well_floor's continuous well), ≈ 50 ms
of its CPU; kept, ≈ 600. A chunk's temporaries do not grow with the survey (CHUNK_ROWS),
so neither does what is kept."""
_M_MMAP_THRESHOLD = -3
_M_TRIM_THRESHOLD = -1
"""glibc's ``mallopt`` parameter numbers (malloc.h)."""
