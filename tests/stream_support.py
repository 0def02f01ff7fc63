"""A reader that counts the record batches it made that are still alive: proves that a
streamed port never holds a survey whole (imported by test modules; tests/ is on sys.path)."""

from __future__ import annotations

import weakref
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pipeline.io import parquet
from pipeline.plugins import load_registry
from pipeline.registry import PluginInfo, ReaderDef, Registry, StageDef
from pipeline.streams import TableStream
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata

ROWS = 1000
"""Rows per batch of the counting reader: a long survey is many batches."""


class Alive:
    """Counts the record batches a reader made that are still alive: a batch is alive while
    any array it was built on is (Arrow buffers keep their NumPy arrays alive)."""

    def __init__(self) -> None:
        self.now = self.peak = self.made = 0
        self.history: list[int] = []
        """batches alive as each batch was made"""

    def track(self, batch: pa.RecordBatch) -> pa.RecordBatch:
        """A fresh copy of ``batch`` whose columns are tracked NumPy arrays."""
        arrays = [np.array(c.to_numpy(zero_copy_only=False)) for c in batch.columns]
        live = [len(arrays)]

        def gone() -> None:
            live[0] -= 1
            if live[0] == 0:
                self.now -= 1

        for array in arrays:
            weakref.finalize(array, gone)
        self.now += 1
        self.made += 1
        self.peak = max(self.peak, self.now)
        self.history.append(self.now)
        columns = [
            pa.array(a, mask=None if c.null_count == 0 else pc_is_null(c))
            for a, c in zip(arrays, batch.columns, strict=True)
        ]
        return pa.RecordBatch.from_arrays(columns, schema=batch.schema)


def pc_is_null(column: pa.Array) -> np.ndarray:
    return np.asarray(column.is_null().to_numpy(zero_copy_only=False))


def counting_reader(alive: Alive, *, streams: bool = True) -> ReaderDef:
    """The Parquet reader, its stream cut into batches of :data:`ROWS` rows made from
    tracked arrays (or, ``streams=False``, a reader that reads whole tables only)."""

    def stream(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
        schema = pq.read_schema(path)

        def batches() -> Iterator[pa.RecordBatch]:
            with pq.ParquetFile(path) as file:
                for batch in file.iter_batches(batch_size=ROWS):
                    yield alive.track(batch)

        return TableStream(schema, batches), WellMetadata()

    return ReaderDef(
        name="counting",
        description="Parquet, batches counted",
        kinds={"samples": RawSamples},
        read=parquet.read,
        sniff=lambda path: False,
        stream=stream if streams else None,
    )


def registry_with(*items: ReaderDef | StageDef) -> Registry:
    registry = load_registry()
    info = PluginInfo("counting", "1.0", builtin=False)
    registry.plugins[info.name] = info
    for item in items:
        registry.add(item, info, type(item))
    assert not registry.problems
    return registry
