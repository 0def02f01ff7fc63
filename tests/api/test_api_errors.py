"""Every error the Python API raises on bad input is a :class:`gp.GyropipeError` (issue 32
item 14): a Parquet file whose pandas metadata pyarrow cannot use (``KeyError``,
``JSONDecodeError``, ``RecursionError`` before), a well that is no mapping of valid fields,
an argument that is no table or path, text in a number column, an extension no writer has,
a simulation plan that does not validate, a parameter that is not finite."""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from tests_support import ROOT

STATIONS = ROOT / "examples" / "stations-j-well.csv"
BAD_PANDAS = {
    "not JSON": b"{not json",
    "no columns": b"{}",
    "a list": b"[1, 2]",
    "nested past the recursion limit": b"[" * 100_000 + b"]" * 100_000,
    "an unknown index column": json.dumps({"columns": [], "index_columns": ["x"]}).encode(),
    "not UTF-8": b"\xff\xfe",
}


def _frame() -> pd.DataFrame:
    frame = pd.DataFrame(
        {"md": [0.0, 100.0, 200.0], "inc": [0.0, 5.0, 10.0], "azi": [0.0, 40.0, 45.0]}
    )
    frame.attrs["north_reference"] = "true"
    return frame


@pytest.mark.parametrize("kind", ["stations", "log"])
@pytest.mark.parametrize("name", list(BAD_PANDAS))
def test_unusable_pandas_metadata_is_an_input_file_error(
    tmp_path: Path, name: str, kind: str
) -> None:
    path = tmp_path / "bad.parquet"
    written = gp.write(gp.read(STATIONS), path)  # units and well in the schema metadata
    table = pq.read_table(written)
    meta = {**(table.schema.metadata or {}), b"pandas": BAD_PANDAS[name]}
    pq.write_table(table.replace_schema_metadata(meta), path)
    with pytest.raises(
        gp.GyropipeError, match=r"pandas metadata \(schema metadata 'pandas'\)"
    ) as caught:
        gp.read(path, kind=kind)
    assert str(caught.value).startswith(f"{path}: ")
    # the table itself reads: only the DataFrame needs the metadata
    assert gp.read_table(path, kind=kind).num_rows == table.num_rows


def _with_attrs(frame: pd.DataFrame, **attrs: Any) -> pd.DataFrame:
    """``frame`` with ``attrs`` set (a ValueError, or pydantic's, escaped before)."""
    frame.attrs.update(attrs)
    return frame


def _arrow_with_well(raw: bytes) -> pa.Table:
    """An Arrow table of stations whose schema metadata holds ``raw`` as the well metadata
    (a JSONDecodeError, or pydantic's ValidationError, escaped before)."""
    table = gp.to_table(_frame())
    return table.replace_schema_metadata({b"gyropipe.well": raw})


BAD_CALLS: dict[str, Callable[[], Any]] = {
    "a well that is no mapping": lambda: gp.read(STATIONS, well=5),
    "a well field of the wrong type": lambda: gp.read(STATIONS, well={"latitude": "x"}),
    "a path that is no path": lambda: gp.read(5),  # type: ignore[arg-type]
    "to_table of text": lambda: gp.to_table("x"),  # type: ignore[arg-type]
    "to_frame of text": lambda: gp.to_frame("x"),  # type: ignore[arg-type]
    "a stage given text": lambda: gp.minimum_curvature("x"),  # type: ignore[arg-type]
    "text in a number column": lambda: gp.minimum_curvature(
        pd.DataFrame({"md": ["a", "b"], "inc": [0.0, 1.0], "azi": [0.0, 1.0]}),
        well={"north_reference": "true"},
    ),
    "an infinite parameter": lambda: gp.minimum_curvature(_frame(), vs_azimuth=float("inf")),
    "a NaN parameter": lambda: gp.minimum_curvature(_frame(), vs_azimuth=float("nan")),
    "attrs['units'] that is no mapping": lambda: gp.minimum_curvature(
        _frame().pipe(_with_attrs, units="deg")
    ),
    "attrs['north_references'] that is no mapping": lambda: gp.minimum_curvature(
        _frame().pipe(_with_attrs, north_references="true")
    ),
    "an unknown attrs['north_reference']": lambda: gp.minimum_curvature(
        _frame().pipe(_with_attrs, north_reference="sideways")
    ),
    "an Arrow table whose well metadata is not JSON": lambda: gp.minimum_curvature(
        _arrow_with_well(b"{not json"), well={"north_reference": "true"}
    ),
    "an Arrow table whose well metadata is invalid": lambda: gp.minimum_curvature(
        _arrow_with_well(b'{"latitude": 100}'), well={"north_reference": "true"}
    ),
    "to_frame of a table whose well metadata is invalid": lambda: gp.to_frame(
        _arrow_with_well(b'{"latitude": 100}')
    ),
    "an extension no writer has": lambda: gp.write(_frame(), "x.bogus"),
    "a plan that does not validate": lambda: gp.simulate({"bogus": 1}),
    "runs that are no mapping": lambda: gp.definitive_survey("nope"),  # type: ignore[arg-type]
    "a run input that is no table": lambda: gp.run(
        ROOT / "pipelines/survey.yaml", inputs={"stations": 5}
    ),
}


@pytest.mark.parametrize("name", list(BAD_CALLS))
def test_bad_arguments_raise_a_gyropipe_error(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(gp.GyropipeError) as caught:
        BAD_CALLS[name]()
    assert "\n" not in str(caught.value).strip()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_reading_a_fifo_says_what_it_is_without_blocking(tmp_path: Path) -> None:
    """Fuzz finding: a FIFO was 'no such file'."""
    fifo = tmp_path / "survey.csv"
    os.mkfifo(fifo)
    with pytest.raises(gp.GyropipeError, match=r"survey.csv: not a regular file \(a FIFO\)"):
        gp.read(fifo)
