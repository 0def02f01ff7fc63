"""Units of a CSV title block, as operators' and vendors' listings write them: map coordinates
in the unit the file states (``Easting (usft):``, ``Northing: … ft``), never a foot taken for
a metre or one foot for the other; a unit in brackets after the key (``Elevation (ft):``); a
datum's elevation (``KB Elevation``, ``RKB``, ``Ground Level``), the depth reference choosing
among several."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning

FEET = "MD (ft),Inc (deg),Azimuth True (deg)"
METRES = "MD (m),Inc (deg),Azimuth True (deg)"
USFT = 1200 / 3937


def listing(path: Path, title: str, header: str = FEET) -> Path:
    """Three stations under ``header``, below a title block of ``title`` lines."""
    body = "0,0,0\n1000,5,45\n2000,10,46\n"
    path.write_text(f"Well: A-7\nCRS: EPSG:2277\n{title}\n\n{header}\n{body}")
    return path


def well(path: Path) -> dict[str, object]:
    return dict(gp.read(path, kind="stations").attrs["well"])


@pytest.mark.parametrize(
    ("title", "east", "north"),
    [
        ("Easting (usft): 2300000.5\nNorthing (usft): 13900000.25", 2300000.5, 13900000.25),
        ("Easting: 2300000.5 usft\nNorthing: 13900000.25 ftUS", 2300000.5, 13900000.25),
        ("Easting [US ft]: 2300000.5\nNorthing: 13900000.25 us-ft", 2300000.5, 13900000.25),
    ],
)
def test_map_coordinates_in_us_survey_feet_are_metres_in_the_well(
    tmp_path: Path, title: str, east: float, north: float
):
    """A Texas state-plane listing gives the wellhead in US survey feet: read as metres
    (the brackets were no key, the unit after the value refused), the report said 2.3e6 m."""
    found = well(listing(tmp_path / "usft.csv", title))
    assert found["easting"] == pytest.approx(east * USFT, rel=1e-15)
    assert found["northing"] == pytest.approx(north * USFT, rel=1e-15)


def test_map_coordinates_in_international_feet(tmp_path: Path):
    found = well(listing(tmp_path / "ft.csv", "Easting (ft): 2300000\nNorthing: 13900000 ft"))
    assert (found["easting"], found["northing"]) == (2300000 * 0.3048, 13900000 * 0.3048)


def test_a_unitless_map_coordinate_beside_feet_is_refused(tmp_path: Path):
    """Lengths in feet do not tell a map coordinate's unit: US survey or international feet
    differ by 2 ppm, 4.6 ft at this easting (it was taken as metres)."""
    source = listing(tmp_path / "bare.csv", "Easting: 2300000\nNorthing: 13900000")
    with pytest.raises(InputFileError, match=r"invalid easting '2300000': no unit.*usft") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 3


def test_a_unitless_map_coordinate_beside_metres_is_metres(tmp_path: Path):
    source = listing(tmp_path / "utm.csv", "Easting: 431250.5\nNorthing: 6478512.25", METRES)
    assert (well(source)["easting"], well(source)["northing"]) == (431250.5, 6478512.25)
    ours = listing(tmp_path / "ours.csv", "# well.easting=431250.5")  # gyropipe's field, m
    assert well(ours)["easting"] == 431250.5


def test_a_key_and_its_value_stating_two_units_are_refused(tmp_path: Path):
    source = listing(tmp_path / "two.csv", "Easting (usft): 2300000 m")
    with pytest.raises(InputFileError, match="the key says 'usft', the value 'm'") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 3


def test_brackets_holding_no_unit_leave_the_line_unread(tmp_path: Path):
    """``Easting (US Survey Feet)`` names no unit this reader knows: not read, said so (never
    a bare easting, in metres beside MD in m)."""
    source = listing(tmp_path / "words.csv", "Easting (US Survey Feet): 2300000", METRES)
    with pytest.warns(InputFileWarning, match="'Easting \\(US Survey Feet\\)' not read"):
        found = well(source)
    assert "easting" not in found
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert well(listing(tmp_path / "deg.csv", "Latitude (deg): 30.25"))["latitude"] == 30.25


def test_a_unit_in_brackets_after_the_key_is_read(tmp_path: Path):
    """``Elevation (ft): 82`` was no key (skipped, the elevation lost)."""
    assert well(listing(tmp_path / "ft.csv", "Elevation (ft): 82"))["elevation"] == 82 * 0.3048


@pytest.mark.parametrize(
    ("title", "elevation", "reference"),
    [
        ("Elevation (ft): 82", 82 * 0.3048, None),
        ("KB Elevation: 82", 82 * 0.3048, "KB"),
        ("KB Elevation (m): 25", 25.0, "KB"),
        ("RKB: 82 ft", 82 * 0.3048, "KB"),
        ("Elev. DF: 80", 80 * 0.3048, "DF"),
        ("Ground Level: 60", 60 * 0.3048, "GL"),
        ("Depth Reference: RKB\nKB Elevation: 82\nGround Level: 60", 82 * 0.3048, "RKB"),
        ("Ground Level: 60\nDepth Reference: GL\nRKB: 82", 60 * 0.3048, "GL"),
        ("Elevation: 90\nKB Elevation: 82\nGround Level: 60", 90 * 0.3048, None),
    ],
)
def test_a_datums_elevation_is_read(
    tmp_path: Path, title: str, elevation: float, reference: str | None
):
    """Vendors name the elevation by its datum or state its unit beside the key: those lines
    were skipped, the elevation lost; among several, the depth reference's is the one."""
    found = well(listing(tmp_path / "datum.csv", title))
    assert found["elevation"] == pytest.approx(elevation, rel=1e-15)
    assert found.get("depth_reference") == reference


@pytest.mark.parametrize(
    ("title", "said"),
    [
        ("KB Elevation: 82\nGround Level: 60", "KB (line 3), GL (line 4) are not of the depth"),
        ("Depth Reference: MSL\nGround Level: 60", "GL (line 4) are not of the depth reference"),
    ],
)
def test_an_elevation_of_no_known_depth_reference_is_left_out(
    tmp_path: Path, title: str, said: str
):
    """A ground level is not the elevation depths measured from the kelly bushing are below."""
    source = listing(tmp_path / "which.csv", title)
    with pytest.warns(
        InputFileWarning, match=re.escape(f"elevation left out: the elevations of {said}")
    ):
        found = well(source)
    assert "elevation" not in found
