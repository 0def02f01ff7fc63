"""Streamed ports end to end: a long point survey flows from a reader through position
averaging and validity checks to Parquet files without its samples ever being held whole
(a reader counts its record batches alive), with the whole-table results; contracts are
checked batch by batch and errors name the row counted from the start of the stream."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from pydantic import BaseModel

from pipeline import ports
from pipeline.errors import ContractViolation, InputFileError, StageError
from pipeline.gyrocompass.readings import position_readings
from pipeline.registry import ReaderDef, StageContext, StageDef
from pipeline.streams import TableStream
from pipeline.tables import AnyTable, RawSamples
from pipeline.well import WellMetadata
from stream_support import PIPELINE, ROWS, Alive, counting_reader, registry_with, run, survey


def test_a_long_survey_streams_through_with_few_batches_alive(tmp_path: Path) -> None:
    samples = survey()
    source = tmp_path / "samples.parquet"
    pq.write_table(samples, source)
    alive = Alive()
    result = run(tmp_path, registry_with(counting_reader(alive)), PIPELINE, source)
    passes = alive.made / -(-samples.num_rows // ROWS)
    assert alive.made > 100 and passes == int(passes)  # whole passes over ≈ 50 batches
    assert alive.peak <= 3, f"{alive.peak} of {alive.made} batches alive at once"
    out = tmp_path / "out"
    readings = pq.read_table(out / "readings.readings.parquet")
    assert readings.num_rows > 100
    whole = position_readings(samples)
    assert readings.select(whole.column_names).equals(whole)
    for name in ("read.samples.parquet", "copy.parquet"):
        written = pq.ParquetFile(out / name)
        assert written.metadata.num_row_groups > 40  # written batch by batch
        assert written.read().select(samples.column_names).equals(samples)
    stages = {s["id"]: s for s in result.manifest["stages"]}
    assert stages["read"]["rows_out"] == {"samples": samples.num_rows}
    assert stages["readings"]["rows_in"] == {"samples": samples.num_rows}
    assert alive.now == 0


def test_a_reader_that_cannot_stream_is_cut_into_slices(tmp_path: Path) -> None:
    samples = survey()
    source = tmp_path / "samples.parquet"
    pq.write_table(samples, source)
    registry = registry_with(counting_reader(Alive(), streams=False))
    run(tmp_path, registry, PIPELINE, source)
    readings = pq.read_table(tmp_path / "out" / "readings.readings.parquet")
    whole = position_readings(samples)
    assert readings.select(whole.column_names).equals(whole)


def test_a_bad_row_in_a_late_batch_names_its_row_from_the_start(tmp_path: Path) -> None:
    samples = survey()
    time = samples.column("time").to_numpy().copy()
    time[3 * ROWS] = time[3 * ROWS - 1]  # the first row of the fourth batch
    bad = samples.set_column(0, samples.schema.field("time"), pa.array(time))
    source = tmp_path / "bad.parquet"
    pq.write_table(bad, source)
    with pytest.raises(StageError) as info:
        run(tmp_path, registry_with(counting_reader(Alive())), PIPELINE, source)
    cause = info.value.__cause__
    assert isinstance(cause, InputFileError)
    assert f"row {3 * ROWS}: {float(time[3 * ROWS])!r}" in str(cause) and "'time'" in str(cause)
    assert "stage 'read'" in str(info.value)
    assert not (tmp_path / "out").exists()


def doubling(
    inputs: Mapping[str, TableStream], params: Any, ctx: StageContext
) -> dict[str, TableStream]:
    """A streamed stage: each batch's gyro_x doubled, NaN from sample 2500 on."""
    samples = inputs["samples"]

    def batches() -> Iterator[pa.RecordBatch]:
        done = 0
        for batch in samples:
            gyro = batch.column("gyro_x").to_numpy() * 2
            gyro[max(2500 - done, 0) :] = np.nan
            i = batch.schema.get_field_index("gyro_x")
            yield batch.set_column(i, batch.schema.field(i), pa.array(gyro))
            done += batch.num_rows

    return {"samples": TableStream(samples.schema, batches)}


DOUBLING: Callable[..., Any] = doubling


def test_a_streamed_output_is_checked_batch_by_batch_at_its_stage(tmp_path: Path) -> None:
    stage = StageDef(
        name="counting.doubling",
        func=DOUBLING,
        description="doubles gyro_x",
        inputs={"samples": RawSamples},
        outputs={"samples": RawSamples},
        streamed_inputs=frozenset({"samples"}),
        streamed_outputs=frozenset({"samples"}),
    )
    source = tmp_path / "samples.parquet"
    pq.write_table(survey(), source)
    text = PIPELINE.split("  - id: readings")[0] + (
        "  - id: double\n    uses: counting.doubling\n    inputs: {samples: read.samples}\n"
        "  - id: readings\n    uses: position_readings\n    inputs: {samples: double.samples}\n"
    )
    with pytest.raises(ContractViolation) as info:
        run(tmp_path, registry_with(counting_reader(Alive()), stage), text, source)
    message = str(info.value)
    assert "stage 'double' output port 'samples'" in message
    assert "'gyro_x': finite" in message and "row 2500: nan" in message


def test_a_stream_holding_a_contract_is_not_checked_again() -> None:
    """A stream already checked against a contract (``holds`` it) passes through that
    contract's check as it is; one that does not hold it is checked, then holds it."""
    samples = survey()
    time = samples.column("time").to_numpy().copy()
    time[7] = time[6]  # not strictly increasing
    bad = TableStream.from_table(
        samples.set_column(0, samples.schema.field("time"), pa.array(time))
    )
    checked = RawSamples.validate_stream(bad)
    assert RawSamples in checked.holds
    with pytest.raises(ContractViolation, match="'time'"):
        list(checked)
    assert RawSamples.validate_stream(checked) is checked


def test_the_samples_a_stage_streams_hold_their_contract(tmp_path: Path) -> None:
    """The read stage's samples reach a streamed stage holding RawSamples (checked once,
    as they were read), so neither the runner nor the stage checks them again."""
    seen: list[frozenset[Any]] = []

    def recording(
        inputs: Mapping[str, TableStream], params: Any, ctx: StageContext
    ) -> dict[str, TableStream]:
        seen.append(inputs["samples"].holds)
        return {"samples": inputs["samples"]}

    stage = StageDef(
        name="counting.recording",
        func=recording,
        description="records what its input holds",
        inputs={"samples": RawSamples},
        outputs={"samples": RawSamples},
        streamed_inputs=frozenset({"samples"}),
        streamed_outputs=frozenset({"samples"}),
    )
    source = tmp_path / "samples.parquet"
    pq.write_table(survey(), source)
    text = PIPELINE.split("  - id: readings")[0] + (
        "  - id: record\n    uses: counting.recording\n    inputs: {samples: read.samples}\n"
        "    persist: [samples]\n"
    )
    run(tmp_path, registry_with(counting_reader(Alive()), stage), text, source)
    assert seen and RawSamples in seen[0]


def test_a_kept_stream_reads_its_source_once_for_its_passes() -> None:
    """``TableStream.kept(3)``: the two passes after one run to its end yield that pass's
    batches without reading the source, the last letting each go as it passes; the passes
    after them read the source. A pass left unfinished keeps nothing."""
    samples = survey()
    reads = [0]

    def source() -> Iterator[pa.RecordBatch]:
        reads[0] += 1
        yield from TableStream.from_table(samples, ROWS)

    stream = TableStream(samples.schema, source).kept(3)
    next(iter(stream))  # unfinished: nothing kept
    first = list(stream)
    assert reads == [2] and len(first) > 40
    for _ in range(2):
        again = list(stream)
        assert reads == [2] and all(a is b for a, b in zip(first, again, strict=True))
    for n in (3, 4):
        assert pa.Table.from_batches(list(stream)).equals(samples) and reads == [n]

    alive = Alive()
    tracked = TableStream(samples.schema, lambda: map(alive.track, source())).kept(2)
    list(tracked)  # kept: every batch of the pass alive
    assert alive.now == alive.made == len(first)
    for n, batch in enumerate(tracked):  # the last kept pass lets them go in turn
        assert (alive.now, alive.made) == (len(first) - n, len(first))
        del batch
    assert alive.now == 0 and reads == [5]


def sized(reader: ReaderDef, nbytes: int) -> ReaderDef:
    """``reader`` whose streams say a pass decodes to ``nbytes``."""
    opener = reader.stream
    assert opener is not None

    def stream(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
        found, well = opener(path, kind, options)
        return dataclasses.replace(found, nbytes=nbytes), well

    return dataclasses.replace(reader, stream=stream)


SHARED = PIPELINE.split("  - id: validity")[0] + "  - id: copy" + PIPELINE.split("  - id: copy")[1]
"""read (samples persisted) → readings, copy: three readers of the samples"""
ALONE = PIPELINE.split("  - id: validity")[0].replace("    persist: [samples]\n", "")
"""read → readings: one reader"""
OPTIONAL = PIPELINE.split("  - id: copy")[0].replace("    persist: [samples]\n", "")
"""read → readings, validity (whose samples it may leave unread: not counted): one reader"""


@pytest.mark.parametrize(
    ("text", "larger", "reads"),
    [(SHARED, False, 1), (SHARED, True, 3), (ALONE, False, 1), (OPTIONAL, False, 2)],
    ids=["three-readers", "three-readers-too-large", "one-reader", "an-unread-input"],
)
def test_the_plan_keeps_a_pass_for_the_stages_that_read_it_again(
    tmp_path: Path, text: str, larger: bool, reads: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A streamed output read by several (readings, a copy, persisted) is read from its
    source once where it says it decodes to at most KEEP_BYTES (the pass held from the first
    reader to the last, which lets it go), else once per reader; one with a single reader
    is not kept (its batches go as they pass; validity, which may leave its samples unread,
    is no reader the plan counts: reading them, it reads them again)."""
    samples = survey()
    source = tmp_path / "samples.parquet"
    pq.write_table(samples, source)
    alive = Alive()
    if larger:
        monkeypatch.setattr(ports, "KEEP_BYTES", samples.nbytes - 1)
    reader = sized(counting_reader(alive), samples.nbytes)
    result = run(tmp_path, registry_with(reader), text, source)
    batches = -(-samples.num_rows // ROWS)
    assert alive.made == reads * batches
    held = text == SHARED and not larger
    assert alive.peak == batches if held else alive.peak <= 3
    assert alive.now == 0 and result.manifest["stages"][0]["rows_out"] == {
        "samples": samples.num_rows
    }
    whole = position_readings(samples)
    readings = pq.read_table(tmp_path / "out" / "readings.readings.parquet")
    assert readings.select(whole.column_names).equals(whole)
    for name in ("read.samples.parquet", "copy.parquet"):
        if text == SHARED:
            assert (
                pq.read_table(tmp_path / "out" / name).select(samples.column_names).equals(samples)
            )


def test_a_kept_pass_goes_after_its_last_reader_though_it_made_no_pass(tmp_path: Path) -> None:
    """The samples wired to readings and to a stage that takes them as an optional input
    (counted as a pass) but reads none of them: the pass kept after readings is let go once
    that stage has run, not held to the end of the run (a stage after it sees no batch
    alive); an optional input the stage reads is read from the kept pass (the MCAP export's
    and the report's series)."""
    samples = survey()
    source = tmp_path / "samples.parquet"
    pq.write_table(samples, source)
    alive = Alive()
    seen: list[int] = []

    def ignoring(inputs: Mapping[str, Any], params: Any, ctx: StageContext) -> dict[str, Any]:
        if params.reads:
            list(inputs["samples"])
        return {}

    def probe(inputs: Mapping[str, pa.Table], params: Any, ctx: StageContext) -> dict[str, Any]:
        seen.append(alive.now)
        return {}

    class Reads(BaseModel):
        reads: bool

    stages = [
        StageDef(
            name="counting.ignoring",
            func=ignoring,
            description="may read its optional samples",
            inputs={"samples": RawSamples},
            optional_inputs=frozenset({"samples"}),
            streamed_inputs=frozenset({"samples"}),
            params=Reads,
        ),
        StageDef(
            name="counting.probe",
            func=probe,
            description="records the batches alive",
            inputs={"readings": AnyTable},
        ),
    ]
    batches = -(-samples.num_rows // ROWS)
    for reads in (False, True):
        alive, seen[:] = Alive(), []
        text = ALONE + (
            "  - id: ignoring\n    uses: counting.ignoring\n    inputs: {samples: read.samples}\n"
            f"    with: {{reads: {str(reads).lower()}}}\n"
            "  - id: probe\n    uses: counting.probe\n    inputs: {readings: readings.readings}\n"
        )
        reader = sized(counting_reader(alive), samples.nbytes)
        out = tmp_path / str(reads)
        out.mkdir()
        run(out, registry_with(reader, *stages), text, source)
        assert alive.made == batches and alive.peak == batches  # one pass, kept
        assert seen == [0] and alive.now == 0
        whole = position_readings(samples)
        readings = pq.read_table(out / "out" / "readings.readings.parquet")
        assert readings.select(whole.column_names).equals(whole)


def test_the_passes_a_run_keeps_are_bounded_together(monkeypatch: pytest.MonkeyPatch) -> None:
    """``ports.kept`` keeps a pass only while it and the passes the run keeps already fit in
    KEEP_BYTES together: a second stream that would take the run past it is read again by
    each of its consumers."""
    samples = survey()
    reads = [0]

    def source() -> Iterator[pa.RecordBatch]:
        reads[0] += 1
        yield from TableStream.from_table(samples, ROWS)

    monkeypatch.setattr(ports, "KEEP_BYTES", 1000)
    stream = TableStream(samples.schema, source)
    for held, once in ((0, True), (400, True), (401, False)):
        reads[0] = 0
        given = ports.kept(stream, 2, 600, held)
        list(given), list(given)
        assert (given is not stream) == once and reads == [1 if once else 2]
    assert ports.kept(stream, 1, 10, 0) is stream  # one consumer: nothing to keep
    assert ports.kept(stream, 2, None, 0) is stream  # a size not known
