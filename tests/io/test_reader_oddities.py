"""What vendors' LAS and CSV survey listings do that the standards do not forbid, read through
the command line as a user runs it: each a number or label read as the file means it, or a
typed error naming the file and line."""

from __future__ import annotations

from pathlib import Path

import pytest

import pipeline as gp
from tests_support import gyropipe_cli

MAGNETIC_LAS = """~Version Information
 VERS.            2.0 : CWLS LOG ASCII STANDARD - VERSION 2.0
 WRAP.             NO : ONE LINE PER DEPTH STEP
~Well Information
 STRT.M       0.0000 : START DEPTH
 STOP.M     300.0000 : STOP DEPTH
 STEP.M       0.0000 : STEP
 NULL.     -999.2500 : NULL VALUE
 WELL.          B-14 : WELL
 DATE.    2026-11-21 : SURVEY DATE
 DECL.DEG       0.00 : MAGNETIC DECLINATION
~Parameter Information
 NREF.      MAGNETIC : AZIMUTH REFERENCE
 DECL.DEG      14.82 : MAGNETIC DECLINATION
~Curve Information
 DEPT.M              : MEASURED DEPTH
 INCL.DEG            : INCLINATION
 AZIM.DEG            : AZIMUTH
~A  DEPT      INCL      AZIM
   0.000     0.000     0.000
 150.000     4.500   212.000
 300.000     9.000   214.500
"""


def test_las_item_in_well_and_parameter_sections_with_different_values(tmp_path: Path) -> None:
    """A ~Well DECL 0.00 (a template's) and a ~Parameter DECL 14.82: the ~Well's was read
    silently, a declination of 0° on magnetic azimuths, which turned to true north would be
    14.82° off. Refused at the second, naming both."""
    path = tmp_path / "B-14.las"
    path.write_text(MAGNETIC_LAS)
    result = gyropipe_cli("convert", path, tmp_path / "B-14.csv", "--kind", "stations")
    assert result.returncode != 0
    assert f"{path}:14: DECL is given twice with different values ('0.00' on line 11" in (
        result.stderr
    )
    # the same number written twice, as templates do, is one value
    path.write_text(MAGNETIC_LAS.replace(" DECL.DEG       0.00", " DECL.deg      14.820"))
    result = gyropipe_cli("convert", path, tmp_path / "B-14.csv", "--kind", "stations")
    assert result.returncode == 0, result.stderr
    assert "# well.declination=14.82\n" in (tmp_path / "B-14.csv").read_text()


LISTING_BODY = """MD (m),Inc (deg),Azi (deg)
0.00,0.00,0.00
150.00,4.50,212.00
300.00,9.00,214.50
"""


def test_csv_title_magnetic_declination_and_convergence_are_read(tmp_path: Path) -> None:
    """'Magnetic Declination:', 'Mag Dec:' and 'Convergence:' (as survey listings title
    them) were no keys: the lines were skipped without a word and magnetic azimuths left
    without the declination their vendor stated."""
    path = tmp_path / "B-14.csv"
    path.write_text(
        "Well: B-14\nNorth Reference: Magnetic\nMagnetic Declination: 14.82°\n"
        "Convergence: -0.95°\n" + LISTING_BODY
    )
    well = gp.read(path).attrs["well"]
    assert (well["declination"], well["grid_convergence"]) == (14.82, -0.95)
    path.write_text("Well: B-14\nNorth Reference: Magnetic\nMag Dec: 14.82\n" + LISTING_BODY)
    assert gp.read(path).attrs["well"]["declination"] == 14.82


def test_csv_title_angles_with_a_hemisphere_letter(tmp_path: Path) -> None:
    """'Magnetic Declination: 2.5° W' (−2.5°, east of true north positive), 'Grid
    Convergence: 0.95 W', 'Latitude: 33.5 S' as listings write them were refused as an
    unknown unit 'W'/'S'; a sign beside the letter stays refused, at its line."""
    path = tmp_path / "C-3.csv"
    path.write_text(
        "Well: C-3\nNorth Reference: Magnetic\nMagnetic Declination: 2.5° W\n"
        "Grid Convergence: 0.95 W\nLatitude: 33.5 S\nLongitude: 151.2 E\n" + LISTING_BODY
    )
    well = gp.read(path).attrs["well"]
    assert (well["declination"], well["grid_convergence"]) == (-2.5, -0.95)
    assert (well["latitude"], well["longitude"]) == (-33.5, 151.2)
    path.write_text("Well: C-3\nNorth Reference: Magnetic\nDeclination: -2.5 W\n" + LISTING_BODY)
    with pytest.raises(gp.GyropipeError, match=r"C-3.csv:3: invalid declination '-2.5 W'"):
        gp.read(path)
