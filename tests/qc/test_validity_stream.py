"""Validity checks of position readings with the raw samples streamed equal those with the
samples whole: the magnetometer means of each reading are taken in one pass over record
batches cut anywhere (inside a reading's span), bit for bit; and the same errors."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pytest
from test_checks import WHITE, point_run, random_well

from pipeline.qc.engine import station_checks
from pipeline.qc.options import QcInputError
from pipeline.qc.sensors import readings_sensors
from pipeline.streams import TableStream


@pytest.fixture(scope="module")
def survey(tmp_path_factory: pytest.TempPathFactory):
    well = random_well(tmp_path_factory.mktemp("stream") / "w.csv", 6, seed=4)
    return point_run(well, WHITE)


@pytest.mark.parametrize("rows", [1, 37, 500, 1 << 20])
def test_streamed_samples_give_the_whole_table_checks(survey, rows: int) -> None:
    sim, readings, site = survey
    whole = station_checks(readings, site, samples=sim.samples)
    streamed = station_checks(readings, site, samples=TableStream.from_table(sim.samples, rows))
    assert "magnetic_field" in whole[0].column("check").to_pylist()
    for a, b in zip(whole, streamed, strict=True):
        assert b.equals(a)
    sensors = readings_sensors(readings, TableStream.from_table(sim.samples, rows))
    expected = readings_sensors(readings, sim.samples)
    assert sensors.mag is not None and expected.mag is not None
    assert (sensors.mag == expected.mag).all() and (sensors.mag_sigma == expected.mag_sigma).all()


def test_streamed_samples_without_magnetometers_check_no_field(survey) -> None:
    sim, readings, site = survey
    bare = sim.samples.drop_columns(["mag_x", "mag_y", "mag_z"])
    nulls = sim.samples.set_column(
        sim.samples.schema.get_field_index("mag_y"),
        sim.samples.schema.field("mag_y"),
        pa.nulls(sim.samples.num_rows, pa.float64()),
    )
    for samples in (bare, nulls):
        qc, _ = station_checks(readings, site, samples=TableStream.from_table(samples, 500))
        assert "magnetic_field" not in qc.column("check").to_pylist()
        assert qc.equals(station_checks(readings, site, samples=samples)[0])


def test_streamed_samples_raise_the_whole_table_errors(survey, tmp_path: Path) -> None:
    sim, readings, site = survey
    cases = [
        (readings.drop_columns(["n", "duration"]), sim.samples, "n/duration"),
        (readings, sim.samples.slice(0, 3000), "the samples hold"),
    ]
    for table, samples, message in cases:
        with pytest.raises(QcInputError, match=message) as whole:
            station_checks(table, site, samples=samples)
        with pytest.raises(QcInputError, match=message) as streamed:
            station_checks(table, site, samples=TableStream.from_table(samples, 250))
        assert str(streamed.value) == str(whole.value)
