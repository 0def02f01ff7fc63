"""MCAP samples as a stream: one record batch per message of gyropipe's channel, checked
against the contract as they pass; the stream holds the table the reader reads."""

from __future__ import annotations

from pathlib import Path

from pipeline.gyrocompass.readings import position_readings
from pipeline.gyrocompass.readings_stream import stream_position_readings
from pipeline.io.mcap.arrow import BATCH_ROWS
from pipeline.plugins import load_registry
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.well import WellMetadata

SPEC = {
    "name": "mcap",
    "seed": 3,
    "site": {
        "latitude": 61.25,
        "longitude": 73.4,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
    },
    "well": {"sections": [{"kind": "vertical", "length": 20}, {"kind": "hold", "length": 60}]},
    "tool": {"preset": "ideal", "overrides": {"sample_rate": 50}},
    "survey": {"mode": "point", "every": 10.0, "positions": [0, 90, 180, 270], "dwell": 6.0},
}


def test_mcap_streams_a_batch_per_message(tmp_path: Path) -> None:
    samples = simulate(SimulationSpec.model_validate(SPEC)).samples
    assert samples.num_rows > 2 * BATCH_ROWS
    registry = load_registry()
    path = tmp_path / "run.mcap"
    registry.writers["mcap"][0].write(samples, path, WellMetadata(well="A-1"))
    stream, well = registry.read_stream(path, "samples")
    assert well.well == "A-1"
    batches = list(stream)
    assert len(batches) >= -(-samples.num_rows // BATCH_ROWS)
    assert max(b.num_rows for b in batches) <= BATCH_ROWS
    assert stream.read_all().equals(samples)
    assert stream_position_readings(stream).equals(position_readings(samples))
