"""Values at the ends of the number line (found by the input fuzzer, seeds 1204 and 1212): a
frame angle in rad at the largest double, scaled to degrees (CSV), or an acceleration in g
scaled to m/s² (LAS), is refused at its line without a NumPy overflow warning; an integer
column past 2^53 is not written to LAS, whose readers read every value as a double (it was
written and could not be read back)."""

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


LAS_SAMPLES = """\
~Version Information
 VERS.       2.0 : CWLS log ASCII Standard - version 2.0
 WRAP.       NO  : one line per index step
~Well Information
 STRT.S      0.0 : first index value
 STOP.S     0.03 : last index value
 STEP.S     0.01 : index step
 NULL.   -999.25 : null value
 WELL.     FZ-1  : well
 LATI.DEG  61.25 : latitude
~Curve Information
 TIME .S         : time
 DEPT .M         : measured depth
 FRAME.DEG       : frame angle
 GYROX.DEG/H     : gyro x
 ACCX .G         : accelerometer x
 ACCY .G         : accelerometer y
 ACCZ .G         : accelerometer z
~A
0.00 0.04 0 3.7  -0.0003 0.0003 1.0014
0.01 0.02 0 12.2 -0.0002 0.0002 1.0014
0.02 0.02 0 -1.6 -0.0001 0.0001 -1e308
0.03 0.04 0 6.2  -0.0000 0.0003 1.0014
"""


def test_an_acceleration_scaled_past_the_largest_double_is_refused_at_its_line(
    tmp_path: Path,
) -> None:
    path = tmp_path / "samples.las"
    path.write_text(LAS_SAMPLES)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (NumPy's "overflow encountered in multiply")
        with pytest.raises(InputFileError, match=r"samples.las:22.*acc_z.*finite"):
            gp.read(path, kind="samples")
    fine = tmp_path / "fine.las"
    fine.write_text(LAS_SAMPLES.replace("-1e308", "1.0013"))
    acc_z = gp.read(fine, kind="samples")["acc_z"].tolist()
    assert acc_z == pytest.approx([9.8204, 9.8204, 9.8194, 9.8204], abs=1e-3)  # 9.80665 m/s² a g


def test_integers_a_double_cannot_hold_are_not_written_to_las(tmp_path: Path) -> None:
    md = pa.array([0.0, 30.0, 60.0], pa.float64())
    table = pa.table({"md": md, "inc": [0.0, 1.0, 2.0], "azi": [0.0, 10.0, 20.0]})
    fine = table.append_column("station", pa.array([1, 2, 2**53], pa.int64()))
    assert "9007199254740992" in gp.write(fine, tmp_path / "fine.las").read_text()
    too_big = table.append_column("station", pa.array([1, 2, 2**53 + 1], pa.int64()))
    with pytest.raises(Exception, match=r"'station' holds integers beyond ±2\^53"):
        gp.write(too_big, tmp_path / "big.las")
    assert not (tmp_path / "big.las").exists()
