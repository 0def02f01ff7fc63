"""What the streamed-port tests share (imported by test modules; tests/ is on sys.path): a
long simulated point survey, a reader that counts the record batches it made that are still
alive (proves that a streamed port never holds a survey whole), a registry with test readers
and stages added, and a pipeline run over a samples file (read → readings → validity →
Parquet, the samples persisted and copied)."""

from __future__ import annotations

import textwrap
import weakref
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pipeline.graph import build_plan
from pipeline.io import parquet
from pipeline.plugins import load_registry
from pipeline.registry import PluginInfo, ReaderDef, Registry, StageDef
from pipeline.runner import run_plan
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.spec import load_spec
from pipeline.streams import TableStream
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata

SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "elevation": 120.0,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
ROWS = 1000
"""Rows per batch of the counting reader: a long survey is many batches."""


@cache
def survey() -> pa.Table:
    """A point survey of 47 stations × 4 positions at 50 Hz with magnetometers (≈ 50 k
    samples)."""
    spec = SimulationSpec.model_validate(
        {
            "name": "long",
            "seed": 3,
            "site": SITE,
            "well": {
                "sections": [
                    {"kind": "vertical", "length": 20},
                    {"kind": "curve", "dls": 3.0, "inc": 50, "azi": 120},
                    {"kind": "hold", "length": 170},
                ]
            },
            "tool": {"preset": "ideal", "overrides": {"sample_rate": 50}},
            "survey": {
                "mode": "point",
                "every": 15.0,
                "positions": [0, 90, 180, 270],
                "dwell": 6.0,
                "move_time": 1.0,
                "settle_time": 0.5,
                "speed": 5.0,
            },
        }
    )
    return simulate(spec).samples


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


PIPELINE = """
name: streamed
version: "1"
well: {latitude: 61.25, longitude: 73.4, elevation: 120.0, survey_date: "2026-11-21"}
inputs: {samples: {description: raw samples}}
stages:
  - id: read
    uses: read_samples
    with: {reader: counting}
    persist: [samples]
  - id: readings
    uses: position_readings
    inputs: {samples: read.samples}
    persist: [readings]
  - id: validity
    uses: validity_checks
    inputs: {readings: readings.readings, samples: read.samples}
  - id: copy
    uses: write
    inputs: {table: read.samples}
    with: {writer: parquet, filename: copy.parquet}
"""


def run(tmp_path: Path, registry: Registry, text: str, samples: Path) -> Any:
    path = tmp_path / "pipeline.yaml"
    path.write_text(textwrap.dedent(text))
    plan = build_plan(load_spec(path), registry)
    return run_plan(plan, registry, inputs={"samples": samples}, out_dir=tmp_path / "out")
