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
import sys
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
from pipeline.continuous.store import (
    CHUNK_ROWS,
    CarriedUnwrap,
    ColumnStore,
    Interpolation,
    RunningIntegrals,
    median_step,
)
from pipeline.graph import build_plan
from pipeline.runner import run_plan
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.spec import load_spec
from stream_support import ROWS, Alive, counting_reader, registry_with
from tests_support import faults_of

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


def chunked(size: int, rows: int) -> list[tuple[int, int]]:
    return [(a, min(a + rows, size)) for a in range(0, size, rows)]


@pytest.mark.parametrize("rows", [1, 7, 1000])
def test_interpolation_in_chunks_is_np_interp_to_the_bit(rows: int) -> None:
    rng = np.random.default_rng(rows)
    xp = 3.0 + np.cumsum(rng.uniform(0.01, 0.02, size=500))
    f = rng.normal(size=(2, xp.size))
    # points before, between, on and after the samples, in no order
    x = rng.permutation(np.concatenate([rng.uniform(2.0, 14.0, 80), xp[::37], [xp[-1]]]))
    interpolation = Interpolation(x, 2)
    for a, b in chunked(xp.size, rows):
        interpolation.feed(xp[a:b], f[0, a:b], f[1, a:b])
    want = np.stack([np.interp(x, xp, row) for row in f])
    assert np.array_equal(interpolation.result(), want)


@pytest.mark.parametrize("rows", [2, 7, 1000])
def test_running_integrals_in_chunks_are_the_whole_series_trapezoids(rows: int) -> None:
    rng = np.random.default_rng(rows)
    xp = 3.0 + np.cumsum(rng.uniform(0.01, 0.02, size=500))
    line = 0.5 - 2.0 * xp  # trapezoids integrate a line exactly
    wiggle = np.sin(7.0 * xp) + rng.normal(scale=0.1, size=xp.size)
    x = rng.permutation(np.concatenate([rng.uniform(2.0, 14.0, 80), xp[::37], [xp[-1]]]))
    integrals = RunningIntegrals(x, 2)
    for a, b in chunked(xp.size - 1, rows - 1):  # each chunk from the last one's last sample
        integrals.add(xp[a : b + 1], line[a : b + 1], wiggle[a : b + 1])
    got = integrals.result()
    on = np.isin(x, xp)
    exact = 0.5 * (x[on] - xp[0]) - (x[on] ** 2 - xp[0] ** 2)
    np.testing.assert_allclose(got[0, on], exact, rtol=1e-12, atol=1e-12)
    assert np.all(got[:, x < xp[0]] == 0.0)
    for row, values in zip(got, (line, wiggle), strict=True):
        running = np.concatenate([[0.0], np.cumsum(np.diff(xp) * (values[1:] + values[:-1]) / 2)])
        np.testing.assert_allclose(row, np.interp(x, xp, running), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("rows", [1, 13, 5000])
def test_median_step_in_chunks_is_the_median_of_the_whole_diff(rows: int) -> None:
    rng = np.random.default_rng(rows)
    clock = 100.0 + np.cumsum(rng.choice([0.01, 0.01 + 1e-9, 0.02], size=3000, p=[0.6, 0.3, 0.1]))
    cases = {
        "clock": clock,  # a few distinct steps: the middle ones share a bin
        "walk": np.cumsum(rng.normal(size=2999)),  # negative steps too, an even count
        "steady": np.arange(500) * 0.25,  # one step throughout
        "one step": np.array([3.0, 4.5]),
    }
    store = ColumnStore()
    for name, x in cases.items():
        store.write(name, 0, x)
        for lo in (0, 7):
            want = np.median(np.diff(x[lo:])) if x.size - lo > 1 else np.nan
            got = median_step(store, name, lo, x.size, rows)
            assert got == want or (np.isnan(got) and np.isnan(want)), (name, lo)


@pytest.mark.parametrize("extra", [-1, 0, 1])
def test_median_step_read_whole_or_by_passes_at_its_bound(extra: int) -> None:
    """Steps of up to two chunks are read whole, one more goes through the histogram passes:
    either way np.median's number, for a clock of a few distinct steps around 0.01 s."""
    rows = 50
    steps = 100 + extra  # two chunks of steps, one fewer, one more
    clock = 300.0 + np.arange(steps + 1) * 0.01  # the steps rounded a few ways
    store = ColumnStore()
    store.write("time", 0, clock)
    assert np.unique(np.diff(clock)).size > 1
    assert median_step(store, "time", 0, clock.size, rows) == np.median(np.diff(clock))


@pytest.mark.parametrize("rows", [1, 13, 5000])
def test_carried_unwrap_in_chunks_is_np_unwrap_of_the_whole_series(rows: int) -> None:
    rng = np.random.default_rng(rows)
    turning = np.cumsum(rng.normal(scale=0.05, size=3000)) + 0.02 * np.arange(3000)
    wrapped = (turning + np.pi) % (2 * np.pi) - np.pi  # jumps of about 2π, 9 turns
    halfway = np.tile([0.0, np.pi, 0.0, -np.pi], 50)  # steps of exactly π
    smooth = np.cumsum(rng.normal(scale=0.01, size=3000))  # no jump: carried zeros
    for angle in (wrapped, halfway, smooth):
        unwrap = CarriedUnwrap()
        got = np.concatenate([unwrap(angle[a:b]) for a, b in chunked(angle.size, rows)])
        assert np.array_equal(got, np.unwrap(angle))


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


HEAP_FAULTS = """
import json, resource, sys
from pathlib import Path
import pyarrow.parquet as pq
from pipeline.streams import use_returning_memory_pool

use_returning_memory_pool()
from pipeline.continuous import ContinuousOptions, integrate_continuous
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec

data = Path(sys.argv[1])
ref = json.loads((data / "previous_outputs.json").read_text())
spec = SimulationSpec.model_validate(ref["cases"]["single_axis_forward"]["spec"])
samples = simulate(spec).samples
stops = pq.read_table(data / "stops-single-axis-forward.parquet")
options = ContinuousOptions(**ref["options"])


def well():
    result = integrate_continuous(samples, stops, float(sys.argv[2]), options)
    for _ in result.series:
        pass


well()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
well()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@pytest.mark.process("glibc's trim threshold fixed as in a batch worker, from a fresh heap")
@pytest.mark.skipif(sys.platform != "linux", reason="glibc's mallopt")
def test_a_second_integration_reuses_the_heap_of_the_first() -> None:
    """A chunk's temporaries (≈ 15 MiB here) freed at the top of the heap were handed back
    at a 4 MiB trim threshold and faulted in again, chunk after chunk and well after well
    (1,724 page faults for this run's second integration); kept, the heap is reused."""
    faults = faults_of(HEAP_FAULTS, DATA, LAT)
    assert faults < 256, faults
