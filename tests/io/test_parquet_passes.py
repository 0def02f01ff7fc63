"""The continuous pipeline decodes its samples once (issue #30): the plan keeps the readings
stage's pass over a Parquet input for the continuous stage's, each column of each row decoded
by the Parquet library once, with the outputs of two decodes; a bad value anywhere is still
the file's error at its column and row."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml

from pipeline import ports
from pipeline.io.mcap.tables import read_tables
from tests_support import ROOT, gyropipe_cli, without_report

GROUP_ROWS = 4096
"""Rows per row group of the test's samples file (several batches per pass)."""
PARQUET_FILE = pq.ParquetFile
"""pyarrow's class, which opens the files the test does not count"""


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short continuous survey (the example's, 600–640 m: ≈ 47,600 samples with both
    stops) written in row groups of :data:`GROUP_ROWS` rows."""
    where = tmp_path_factory.mktemp("continuous")
    plan = yaml.safe_load((ROOT / "examples" / "plans" / "j-well-continuous.yaml").read_text())
    plan["survey"].update(start_md=600, end_md=640)
    (where / "plan.yaml").write_text(yaml.safe_dump(plan))
    gyropipe_cli("simulate", where / "plan.yaml", "--out", where / "sim", check=True)
    path = where / "samples.parquet"
    pq.write_table(
        pq.read_table(where / "sim" / "samples.parquet"), path, row_group_size=GROUP_ROWS
    )
    return path


class Counting(pq.ParquetFile):
    """A Parquet file adding the rows of each column it hands out to ``rows``."""

    rows: Counter[str]

    def iter_batches(self, *args: Any, **kwargs: Any) -> Iterator[pa.RecordBatch]:
        for batch in super().iter_batches(*args, **kwargs):
            self.rows.update(dict.fromkeys(batch.schema.names, batch.num_rows))
            yield batch


def decoded(monkeypatch: pytest.MonkeyPatch, path: Path) -> Counter[str]:
    """Rows of each column the Parquet library hands out of ``path`` from now on (every
    ``ParquetFile.iter_batches`` of it)."""
    rows: Counter[str] = Counter()

    def opened(source: Any, *args: Any, **kwargs: Any) -> pq.ParquetFile:
        if not (isinstance(source, str | Path) and Path(source).resolve() == path.resolve()):
            return PARQUET_FILE(source, *args, **kwargs)
        file = Counting(source, *args, **kwargs)
        file.rows = rows
        return file

    monkeypatch.setattr(pq, "ParquetFile", opened)
    return rows


def run(tmp_path: Path, samples: Path, out: str) -> Path:
    pipeline = without_report("continuous-gyro", tmp_path)
    gyropipe_cli("run", pipeline, "--input", samples, "--out", tmp_path / out, check=True)
    return tmp_path / out


def test_the_continuous_pipeline_decodes_each_column_of_its_samples_once(
    tmp_path: Path, samples: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    file = pq.ParquetFile(samples)
    rows, names = file.metadata.num_rows, file.schema_arrow.names
    assert file.metadata.num_row_groups > 10
    once = decoded(monkeypatch, samples)
    kept = run(tmp_path, samples, "kept")
    assert once == dict.fromkeys(names, rows)  # readings and continuous: one decode
    monkeypatch.setattr(ports, "KEEP_BYTES", 0)  # every pass reads the file
    twice = decoded(monkeypatch, samples)
    again = run(tmp_path, samples, "again")
    assert twice == dict.fromkeys(names, 2 * rows)
    tables = sorted(p.name for p in kept.glob("*.parquet"))
    assert "readings.readings.parquet" in tables
    assert tables == sorted(p.name for p in again.glob("*.parquet"))
    series = [read_tables(out / "processed.mcap")[0]["series"] for out in (kept, again)]
    assert series[0].num_rows > 1000 and series[0].equals(series[1])  # the moving run
    for name in tables:  # to the bit
        assert (kept / name).read_bytes() == (again / name).read_bytes(), name


def test_a_bad_value_in_the_moving_run_is_the_files_error_at_its_row(
    tmp_path: Path, samples: Path
) -> None:
    """Between the stops (samples the readings do not average, that the continuous stage
    takes from the kept pass), a NaN is still found by the checks of the first pass."""
    table = pq.read_table(samples)
    row = int(np.flatnonzero(table.column("station").is_null().to_numpy(zero_copy_only=False))[7])
    gyro = table.column("gyro_x").to_numpy().copy()
    gyro[row] = np.nan
    index = table.schema.get_field_index("gyro_x")
    bad = tmp_path / "bad.parquet"
    pq.write_table(
        table.set_column(index, table.schema.field(index), pa.array(gyro)),
        bad,
        row_group_size=GROUP_ROWS,
    )
    pipeline = without_report("continuous-gyro", tmp_path)
    result = gyropipe_cli("run", pipeline, "--input", bad, "--out", tmp_path / "out")
    assert result.returncode != 0
    assert "'gyro_x'" in result.stderr and f"row {row}: nan" in result.stderr, result.stderr
    assert str(bad) in result.stderr
    assert not (tmp_path / "out").exists()
