"""A LAS trajectory's tie-on record (where each survey's uncertainty starts) written as
~Parameter items and read back whole: several surveys, one tied on another, one with a given
tie-on covariance; a survey id a LAS value cannot hold is refused, not written wrong.
Expected values: the record written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

import pipeline as gp
from pipeline.contracts import UNIT_KEY
from pipeline.errors import InputFileError, ParameterError
from pipeline.uncertainty.stated import with_statements
from pipeline.uncertainty.tieon import TieOn, TieOnRecord, tie_on_of

COV = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
NORTH = {b"north_reference": b"true"}
RECORD = TieOnRecord(
    surveys=(
        TieOn(survey="1", md=500.0, basis="given", semi_major=0.15),
        TieOn(survey="2", md=700.0, basis="survey", parent="1"),
    )
)


def trajectory(record: TieOnRecord) -> pa.Table:
    """Four stations of two surveys (numeric ids: a LAS survey curve) with covariances,
    stating ``record``."""
    units = {"md": b"m", "inc": b"deg", "azi": b"deg", **dict.fromkeys(COV, b"m2")}
    values = {"md": [500.0, 600, 700, 800], "inc": [10.0, 12, 14, 16], "azi": [30.0, 32, 34, 36]}
    values |= {name: list(np.arange(1.0, 5.0) * 0.01 * (k + 1)) for k, name in enumerate(COV)}
    fields = [pa.field("survey", pa.int64())] + [
        pa.field(n, pa.float64(), metadata={UNIT_KEY: u} | (NORTH if n == "azi" else {}))
        for n, u in units.items()
    ]
    arrays = [pa.array([1, 1, 2, 2])] + [pa.array(values[n]) for n in units]
    table = pa.Table.from_arrays(arrays, schema=pa.schema(fields))
    return with_statements(table, None, "TEST-GYRO rev 2", record)


def test_several_surveys_tie_ons_round_trip(tmp_path: Path) -> None:
    path = gp.write(trajectory(RECORD), tmp_path / "two.las")
    back = gp.read_table(path)
    assert back.column("survey").to_pylist() == ["1", "1", "2", "2"]
    assert tie_on_of(back) == RECORD
    np.testing.assert_allclose(back.column("cov_ev").to_numpy(), [0.05, 0.1, 0.15, 0.2])


def test_a_survey_id_no_las_value_holds_is_refused(tmp_path: Path) -> None:
    record = TieOnRecord(
        surveys=(RECORD.surveys[0], RECORD.surveys[1].model_copy(update={"parent": "a:b"}))
    )
    with pytest.raises(ParameterError, match=r"survey id 'a:b' cannot be a LAS value"):
        gp.write(trajectory(record), tmp_path / "bad.las")
    assert not (tmp_path / "bad.las").exists()


def test_a_tie_on_item_given_twice_differently_is_refused(tmp_path: Path) -> None:
    path = gp.write(trajectory(RECORD), tmp_path / "twice.las")
    text = path.read_text()
    path.write_text(text.replace("~Curve", " TIEMD1  .m   550.0 : again\n~Curve", 1))
    line = text[: text.index("~Curve")].count("\n") + 1
    with pytest.raises(InputFileError, match=rf"twice.las:{line}: TIEMD1 is given twice"):
        gp.read(path, kind="stations")
