"""Position readings from a stream of record batches equal the whole-table readings: the
same rows, bit for bit, whatever the batch boundaries (inside a dwell, inside the trimmed
start, one sample long), for marked and detected dwells; and the same errors."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pyarrow as pa
import pytest
from test_readings import profile, run, synthetic

from pipeline.errors import ContractViolation
from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.gyrocompass.readings_stream import stream_position_readings
from pipeline.gyrocompass.stops import unread_stops
from pipeline.streams import TableStream

BATCHES = [1, 7, 250, 801, 4096, 1 << 20]
"""Rows per batch: a sample at a time, odd sizes that cut dwells and trims anywhere, one
batch for the whole survey."""


def both(samples: pa.Table, options: ReadingOptions, rows: int) -> tuple[pa.Table, pa.Table]:
    whole = position_readings(samples, options)
    streamed = stream_position_readings(TableStream.from_table(samples, rows), options)
    return whole, streamed


@pytest.mark.parametrize("rows", BATCHES[1:])
def test_marked_positions_stream_to_the_whole_table_readings(rows: int) -> None:
    sim = run("noisy", dwell=10.0, move_time=0.1, settle_time=0.0)
    whole, streamed = both(sim.samples, ReadingOptions(), rows)
    assert whole.num_rows == 15
    assert streamed.equals(whole)


@pytest.mark.parametrize("rows", BATCHES[1:])
def test_detected_dwells_stream_to_the_whole_table_readings(rows: int) -> None:
    sim = run("noisy", dwell=10.0, move_time=0.1, settle_time=0.0)
    noise = np.random.default_rng(1).normal(0, 0.05, sim.samples.num_rows)
    md = sim.samples.column("md").to_numpy() + noise
    samples = sim.samples.set_column(1, sim.samples.schema.field("md"), pa.array(md))
    samples = samples.drop_columns(["station", "position"])
    whole, streamed = both(samples, ReadingOptions(), rows)
    assert whole.num_rows == 15
    assert streamed.equals(whole)


@pytest.mark.parametrize("rows", BATCHES)
def test_stations_numbered_by_detection_stream_alike(rows: int) -> None:
    md, angle = profile(
        [
            (0, 100, 10), (10, 100, 10), (11, 100, 100), (21, 100, 100),  # station 0
            (31, 110, 100), (41, 110, 100), (42, 110, 10), (52, 110, 10),  # travel, station 1
            (55, 107, 10), (58, 110, 10), (68, 110, 10),  # pulled up 3 m and back: station 2
            (69, 110.3, 10), (79, 110.3, 10),  # crept 0.3 m (< station_gap): same station
        ]
    )  # fmt: skip
    for smoothing in (0.0, 1.0, 3.0):
        options = ReadingOptions(md_smoothing=smoothing)
        whole, streamed = both(synthetic(md, angle), options, rows)
        assert whole.num_rows == 6
        assert streamed.equals(whole), smoothing


@pytest.mark.parametrize("rows", BATCHES)
def test_stops_without_a_dwell_are_numbered_and_recorded_alike(rows: int) -> None:
    """Two stops with no dwell — the depth held 10 s at 110 m with the frame turning at
    36°/s, 3 s at 115 m with the frame still (a dwell needs 6 s) — are stations 1 and 2 with
    no readings, recorded with how long the depth held: the smoothed MD within 5 cm of its
    level, which the 1 s moving average over the travel either side at 1 m/s reaches
    (0.5 − τ)²/2 m short of it τ s into the stop, so the hold is up to half the window
    shorter. 3 s held 0.3 m from the last station (less than station_gap) is that station's.
    The streamed readings say the same."""
    md, angle = profile(
        [
            (0, 100, 10), (10, 100, 10), (11, 100, 100), (21, 100, 100),  # station 0
            (31, 110, 100), (41, 110, 460),  # held, the frame turning: station 1
            (46, 115, 460), (49, 115, 460),  # held 3 s: station 2
            (54, 120, 460), (64, 120, 460), (65, 120, 550), (75, 120, 550),  # station 3
            (76, 120.3, 550), (79, 120.3, 550), (84, 125, 550),  # crept, held 3 s, left
        ]
    )  # fmt: skip
    whole, streamed = both(synthetic(md, angle), ReadingOptions(), rows)
    assert streamed.equals(whole)
    assert unread_stops(streamed) == unread_stops(whole)
    np.testing.assert_array_equal(whole.column("station").to_numpy(), [0, 0, 3, 3])
    turning, short = unread_stops(whole)
    assert (turning.station, short.station) == (1, 2)
    np.testing.assert_allclose([turning.md, short.md], [110, 115])
    assert 9.5 <= turning.held <= 10 and 2.5 <= short.held <= 3
    assert "frame angle did not stay within 0.5°" in turning.reason()
    assert f"held depth there for only {short.held:.1f} s" in short.reason()


@pytest.mark.parametrize("rows", BATCHES)
def test_a_stop_the_tool_crept_through_is_unread_alike(rows: int) -> None:
    """At 110 m the tool creeps 4 cm in 10 s, the frame still: the smoothed MD stays within
    the 5 cm tolerance for longer than the 6 s a dwell needs, but the (exact) odometer MD
    rests nowhere — the stop is station 1, unread (before: a reading of a moving tool).
    Station 0 leaves at 1 m/s and station 2 arrives so: their readings take in no sample of
    travel (nor of the 1 s trim after the arrival), and lose at most half the 1 s MD
    smoothing window. The streamed readings say the same."""
    md, angle = profile(
        [
            (0, 100, 10), (10, 100, 10), (11, 100, 100), (21, 100, 100),  # station 0
            (31, 110, 100), (41, 110.04, 100),  # crept through: station 1
            (51, 120, 100), (61, 120, 100), (62, 120, 10), (72, 120, 10),  # station 2
        ]
    )  # fmt: skip
    whole, streamed = both(synthetic(md, angle), ReadingOptions(), rows)
    assert streamed.equals(whole)
    assert unread_stops(streamed) == unread_stops(whole)
    np.testing.assert_array_equal(whole.column("station").to_numpy(), [0, 0, 2, 2])
    (crept,) = unread_stops(whole)
    assert crept.station == 1 and crept.md == pytest.approx(110.02, abs=0.01)
    assert crept.held >= 9.5 and "at rest" in crept.reason()
    t, n = whole.column("t").to_numpy(), whole.column("n").to_numpy()
    first, last = t - (n - 1) / 20, t + (n - 1) / 20  # (10 Hz)
    assert 20.5 <= last[1] <= 21.0 and 52.0 <= first[2] <= 52.5  # within half the smoothing


def test_a_batch_boundary_inside_a_stationary_position() -> None:
    sim = run()
    station = sim.samples.column("station").to_numpy(zero_copy_only=False)
    position = sim.samples.column("position").to_numpy(zero_copy_only=False)
    inside = np.flatnonzero((station == 1) & (position == 2))
    cut = int(inside[len(inside) // 2])  # the middle of station 1, position 2
    batches = [sim.samples.slice(0, cut), sim.samples.slice(cut, 1), sim.samples.slice(cut + 1)]
    stream = TableStream(
        sim.samples.schema, lambda: (b for t in batches for b in t.combine_chunks().to_batches())
    )
    assert stream_position_readings(stream).equals(position_readings(sim.samples))


def test_errors_are_the_whole_table_errors() -> None:
    samples = run().samples
    keep = np.ones(samples.num_rows, dtype=bool)
    keep[[1234, 5000]] = False  # dropped samples
    unmarked = samples.drop_columns(["station", "position"])
    station = samples.column("station").to_pylist()
    marked = [i for i, s in enumerate(station) if s is not None]
    for i in [*marked[:5], *marked[400:733], marked[-1]]:  # 3 runs, one over batches of 333
        station[i] = None  # their position markers kept: orphans where there is one
    position = samples.column("position").to_pylist()
    orphaned = sum(s is None and p is not None for s, p in zip(station, position, strict=True))
    assert orphaned > 333  # more than a batch
    orphans = samples.set_column(
        samples.schema.get_field_index("station"),
        samples.schema.field("station"),
        pa.array(station, pa.int64()),
    )
    cases = [
        (orphans, ReadingOptions(), f"^{orphaned} samples have a position marker but no station"),
        (samples.drop_columns(["station"]), ReadingOptions(), "position markers but no station"),
        (samples.drop_columns(["md"]), ReadingOptions(), "no md column"),
        (unmarked.drop_columns(["frame_angle"]), ReadingOptions(), "neither station/position"),
        (unmarked, ReadingOptions(min_dwell=60), "no frame positions found"),
        (samples, ReadingOptions(trim_start=4.0), "too short after trimming"),
        (samples.slice(0, 1), ReadingOptions(), "at least 2 samples"),
        (
            samples.filter(pa.array(keep)),
            ReadingOptions(),
            r"t = 12\.33 s is 0\.02 s \(after row 1233; 2 step",
        ),
    ]
    for table, options, message in cases:
        with pytest.raises(ValueError, match=message) as whole:
            position_readings(table, options)
        with pytest.raises(ValueError, match=message) as streamed:
            stream_position_readings(TableStream.from_table(table, 333), options)
        assert str(streamed.value) == str(whole.value)


def test_each_batch_is_checked_against_the_contract_with_its_row() -> None:
    samples = run().samples
    time = samples.column("time").to_numpy().copy()
    time[1000] = time[999]  # time must increase strictly: row 1000 breaks it
    bad = samples.set_column(0, samples.schema.field("time"), pa.array(time))
    with pytest.raises(ContractViolation, match=r"'time': monotonic.*row 1000"):
        stream_position_readings(TableStream.from_table(bad, 1000))  # at a batch boundary


def test_no_samples_give_no_readings() -> None:
    empty = run().samples.slice(0, 0)
    readings = stream_position_readings(TableStream.from_table(empty))
    assert readings.num_rows == 0


def counting(
    samples: pa.Table, rows: int, first: int | None = None
) -> tuple[TableStream, list[int]]:
    """A stream of ``samples`` in batches of ``rows`` (the first of ``first`` rows, if given)
    and the count of passes made over it."""
    head = [] if first is None else samples.slice(0, first).to_batches()
    rest = TableStream.from_table(samples.slice(first or 0), rows)
    passes = [0]

    def each() -> Iterator[pa.RecordBatch]:
        passes[0] += 1
        yield from head
        yield from rest

    return TableStream(samples.schema, each), passes


def test_marked_positions_are_read_in_one_pass() -> None:
    samples = run("noisy", dwell=10.0, move_time=0.1, settle_time=0.0).samples
    stream, passes = counting(samples, 801)
    assert stream_position_readings(stream).equals(position_readings(samples))
    assert passes == [1]


def _faster_start(samples: pa.Table, rows: int, step: float) -> pa.Table:
    """``samples`` whose first ``rows`` time steps are ``step`` (s), the rest as they were."""
    time = samples.column("time").to_numpy().copy()
    old = time[1] - time[0]
    time[1 : rows + 1] = time[0] + step * np.arange(1, rows + 1)
    time[rows + 1 :] += time[rows] - (time[0] + old * rows)
    return samples.set_column(0, samples.schema.field("time"), pa.array(time))


def test_a_second_pass_where_the_first_batch_does_not_tell_the_trims() -> None:
    samples = run("noisy", dwell=10.0, move_time=0.1, settle_time=0.0).samples
    rate = 1.0 / float(np.diff(samples.column("time").to_numpy()).mean())
    at = samples.schema.get_field_index("gyro_z")
    no_gyro_z = samples.set_column(
        at, samples.schema.field(at), pa.nulls(samples.num_rows, pa.float64())
    )
    # 0.4 % faster over the first batch (uniform within 1 %): 1.003 s is 1 sample more there
    trims = ReadingOptions(trim_start=1.003)
    assert round(1.003 * rate) != round(1.003 * rate * 1.004)
    cases = [
        (samples, ReadingOptions(), 1),  # the first batch one sample: no rate
        (no_gyro_z, ReadingOptions(), None),  # a column without data
        (_faster_start(samples, 900, 1.0 / (rate * 1.004)), trims, None),
    ]
    for table, options, first in cases:
        stream, passes = counting(table, 801, first)
        whole = position_readings(table, options)
        assert whole.num_rows == 15
        assert stream_position_readings(stream, options).equals(whole)
        assert passes == [2], first
