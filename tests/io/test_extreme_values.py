"""Values at the ends of the number line (found by the input fuzzer, seed 1204): a frame
angle in rad at the largest double, scaled to degrees, is refused at its line without a
NumPy overflow warning; an integer column past 2^53 is not written to LAS, whose readers
read every value as a double (it was written and could not be read back)."""

from __future__ import annotations

import warnings
from pathlib import Path

import pyarrow as pa
import pytest

import pipeline as gp
from pipeline.errors import InputFileError

SAMPLES = """\
# well.latitude=61.25
time[s],md[m],frame_angle[rad],gyro_x[deg/h],acc_x[m/s2],acc_y[m/s2],acc_z[m/s2],station,position
0,0.04,0,3.7,-0.003,0.0029,9.82,0,0
0.01,0.02,0,12.2,-0.0016,0.0023,9.82,0,0
0.02,0.02,1.7976931348623157e308,-1.6,-0.0012,0.0014,9.82,0,0
0.03,0.04,0,6.2,-0.0002,0.0032,9.82,0,0
"""


def test_a_value_scaled_past_the_largest_double_is_refused_at_its_line(tmp_path: Path) -> None:
    path = tmp_path / "samples.csv"
    path.write_text(SAMPLES)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (NumPy's "overflow encountered in multiply")
        with pytest.raises(InputFileError, match=r"samples.csv:5.*frame_angle.*finite"):
            gp.read(path, kind="samples")


def test_integers_a_double_cannot_hold_are_not_written_to_las(tmp_path: Path) -> None:
    md = pa.array([0.0, 30.0, 60.0], pa.float64())
    table = pa.table({"md": md, "inc": [0.0, 1.0, 2.0], "azi": [0.0, 10.0, 20.0]})
    fine = table.append_column("station", pa.array([1, 2, 2**53], pa.int64()))
    assert "9007199254740992" in gp.write(fine, tmp_path / "fine.las").read_text()
    too_big = table.append_column("station", pa.array([1, 2, 2**53 + 1], pa.int64()))
    with pytest.raises(Exception, match=r"'station' holds integers beyond ±2\^53"):
        gp.write(too_big, tmp_path / "big.las")
    assert not (tmp_path / "big.las").exists()
