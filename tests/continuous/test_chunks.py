"""The continuous stage a chunk at a time equals the whole series at once (issue #20).

The runs of ``tests/data/continuous/previous_outputs.json`` (single-axis forward, two-axis
forward, single-axis back in time across a held near-vertical section) are integrated in one
chunk and in chunks of awkward sizes: 97 samples is shorter than the İ filter (101 samples)
and the odometer fit (201), so every filter window and every station's noise neighbourhood
spans several chunks, and chunk edges fall inside the stops and the held section. The
series, the stations with their σ and the misclosure must agree within 1e-9°. End to end,
a continuous pipeline reads its samples from a reader that counts its record batches alive:
the integration holds at most two batches at once, and the series is written a chunk per
Parquet row group.
"""

from __future__ import annotations

import json
import textwrap
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from continuous_support import LAT

from pipeline.continuous import ContinuousOptions, integrate_continuous
from pipeline.continuous.store import CHUNK_ROWS
from pipeline.graph import build_plan
from pipeline.runner import run_plan
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.spec import load_spec
from stream_support import ROWS, Alive, counting_reader, registry_with

DATA = Path(__file__).parents[1] / "data" / "continuous"
TOLERANCE = 1e-9  # deg


@cache
def case(name: str) -> tuple[pa.Table, pa.Table, ContinuousOptions]:
    """Samples, compassed stops and options of a stored case."""
    ref: dict[str, Any] = json.loads((DATA / "previous_outputs.json").read_text())
    sim = simulate(SimulationSpec.model_validate(ref["cases"][name]["spec"]))
    stops = pq.read_table(DATA / f"stops-{name.replace('_', '-')}.parquet")
    return sim.samples, stops, ContinuousOptions(**ref["options"])


def assert_close(got: pa.Table, want: pa.Table, label: str) -> None:
    assert got.column_names == want.column_names
    for column in want.column_names:
        x, y = got.column(column).to_numpy(), want.column(column).to_numpy()
        finite = np.isfinite(y)
        assert np.array_equal(np.isfinite(x), finite), f"{label}.{column}"
        diff = np.abs(x[finite] - y[finite])
        if column == "azi":
            diff = np.abs((x[finite] - y[finite] + 180.0) % 360.0 - 180.0)
        assert diff.max(initial=0.0) <= TOLERANCE, f"{label}.{column}: {diff.max()}"


@pytest.mark.parametrize(
    ("name", "rows"),
    [("single_axis_forward", 97), ("two_axis_forward", 1009), ("single_axis_backward", 2003)],
)
def test_chunks_give_the_whole_series_results(name: str, rows: int) -> None:
    samples, stops, options = case(name)
    whole = integrate_continuous(samples, stops, LAT, options, rows=samples.num_rows)
    chunked = integrate_continuous(samples, stops, LAT, options, rows=rows)
    series = chunked.series.read_all()
    assert series.num_rows > 10 * rows
    assert_close(series, whole.series.read_all(), "series")
    assert_close(chunked.stations, whole.stations, "stations")
    if np.isnan(whole.misclosure):
        assert np.isnan(chunked.misclosure)
    else:
        assert abs(chunked.misclosure - whole.misclosure) <= TOLERANCE
    if name == "single_axis_backward":  # the chunks cross a held section
        assert np.any(chunked.stations.column("flags").to_numpy() & 1)


PIPELINE = """
name: streamed-continuous
version: "1"
well: {latitude: %(lat)r}
inputs: {samples: {description: raw samples}}
stages:
  - id: read
    uses: read_samples
    with: {reader: counting}
  - id: readings
    uses: position_readings
    inputs: {samples: read.samples}
    with: {trim_start: 0.5, min_dwell: 1.0}
  - id: stops
    uses: compass
    inputs: {readings: readings.readings}
    with: {noise_floor: 0.01}
    persist: [stations]
  - id: continuous
    uses: integrate_continuous
    inputs: {samples: read.samples, stops: stops.stations}
    with: %(options)s
    persist: [stations, series]
"""


def test_a_continuous_run_streams_its_samples_and_writes_its_series_by_row_groups(
    tmp_path: Path,
) -> None:
    samples, _, options = case("single_axis_forward")
    source = tmp_path / "samples.parquet"
    pq.write_table(samples, source)
    alive = Alive()
    registry = registry_with(counting_reader(alive))
    spec = tmp_path / "pipeline.yaml"
    given = json.dumps(options.model_dump(exclude_defaults=True))
    spec.write_text(textwrap.dedent(PIPELINE % {"lat": LAT, "options": given}))
    out = tmp_path / "out"
    plan = build_plan(load_spec(spec), registry)
    run_plan(plan, registry, inputs={"samples": source}, out_dir=out)
    per_pass = -(-samples.num_rows // ROWS)
    assert alive.made == 2 * per_pass  # one pass to average the stops, one to integrate
    integrating = alive.history[per_pass:]  # (a stop's samples stay while it is averaged)
    assert max(integrating) <= 2, f"{max(integrating)} batches alive at once"
    written = pq.ParquetFile(out / "continuous.series.parquet")
    assert written.metadata.num_row_groups == -(-written.metadata.num_rows // CHUNK_ROWS)
    stops = pq.read_table(out / "stops.stations.parquet")
    whole = integrate_continuous(samples, stops, LAT, options, rows=samples.num_rows)
    assert_close(written.read(), whole.series.read_all(), "series")
    assert_close(pq.read_table(out / "continuous.stations.parquet"), whole.stations, "stations")
