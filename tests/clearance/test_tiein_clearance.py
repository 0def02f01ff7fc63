"""The clearance scan starts the reference and each offset well at their stations files'
own tie-on rows where they list them (both started at their wellheads, TVD = MD, whatever
the files listed): two vertical wells whose files are tied on off their wellheads."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from tests_support import ROOT, gyropipe_cli

CLEARANCE = ROOT / "pipelines" / "clearance.yaml"
HEADER = """\
Well: {well}
Latitude: 61.25
Longitude: 73.4
Survey Date: 2026-11-21

MD (m),Inc (deg),Azimuth True (deg),TVD (m),North (m),East (m)
"""
REFERENCE_TIE = (498.30, 12.10, -3.40)  # TVD, north, east at MD 500 m
OFFSET_TIE = (499.00, 3.00, 2.00)
SLOT = (20.0, 0.0)  # the offset's wellhead from the reference's, north, east (m)


def vertical(path: Path, well: str, tie: tuple[float, float, float]) -> Path:
    """A vertical hole from a tie-on row at MD 500 m down to 1100 m, every 50 m, its listing
    the tie-on's north and east all the way and TVD growing with MD."""
    tvd, north, east = tie
    rows = [
        f"{500 + 50 * k:.2f},0.00,0.00,{tvd + 50 * k:.2f},{north:.2f},{east:.2f}" for k in range(13)
    ]
    path.write_text(HEADER.format(well=well) + "\n".join(rows) + "\n")
    return path


def test_the_reference_and_the_offset_start_at_their_files_tie_on(tmp_path: Path) -> None:
    reference = vertical(tmp_path / "reference.csv", "R-1", REFERENCE_TIE)
    vertical(tmp_path / "offset.csv", "O-1", OFFSET_TIE)
    manifest = tmp_path / "manifest.csv"
    manifest.write_text(
        "well_id,file,model,hole_diameter (in),north (m),east (m)\n"
        f"O-1,offset.csv,GYRO-NS,8.5,{SLOT[0]},{SLOT[1]}\n"
    )
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", CLEARANCE, "--input", f"reference={reference}", "--input", f"offsets={manifest}",
        "--set", "clearance.reference_hole_diameter=0.3112", "--set", "report.formats=[html]",
        "--out", out,
    )  # fmt: skip
    assert result.returncode == 0, result.output
    # parallel verticals: between their tops the centres are apart by the horizontal offset
    # of the offset's slot plus its tie-on from the reference's tie-on (12.16 m; 20 m when
    # both were started at their wellheads)
    apart = math.hypot(
        SLOT[0] + OFFSET_TIE[1] - REFERENCE_TIE[1], SLOT[1] + OFFSET_TIE[2] - REFERENCE_TIE[2]
    )
    table = pq.read_table(out / "clearance.clearance.parquet")
    md = table.column("md").to_numpy()
    distance = table.column("distance").to_numpy()
    below = md >= 550.0  # the offset's first station is 0.7 m deeper than the reference's
    np.testing.assert_allclose(distance[below], apart, atol=1e-6)
    (top,) = distance[md == 500.0]
    assert top == pytest.approx(math.hypot(apart, OFFSET_TIE[0] - REFERENCE_TIE[0]), abs=1e-6)
    # the offset's TVD is its file's: its closest point to the reference at MD 800 m
    # (TVD 798.30 m) is at its own TVD 798.30 m, MD 799.30 m
    offset_md = table.column("offset_md").to_numpy()
    (closest,) = offset_md[md == 800.0]
    assert closest == pytest.approx(800.0 - (OFFSET_TIE[0] - REFERENCE_TIE[0]), abs=1e-6)
    rule = json.loads(table.schema.metadata[b"gyropipe.clearance_rule"])
    assert rule["reference_tie"]["source"] == "stations file"
    assert rule["wells"]["O-1"]["tie_on"] == {"tvd": 499.0, "north": 3.0, "east": 2.0}

    # the Python function scans the same
    frame = gp.clearance(
        reference, manifest, reference_hole_diameter=0.3112, reference_model="GYRO-NS"
    )
    np.testing.assert_allclose(frame["distance"].to_numpy()[below], apart, atol=1e-6)
    given = gp.clearance(
        reference,
        {"O-1": tmp_path / "offset.csv"},
        offset_model="GYRO-NS",
        offset_hole_diameter=0.2159,
        offset_position={"O-1": SLOT},
        reference_hole_diameter=0.3112,
        reference_model="GYRO-NS",
    )
    np.testing.assert_allclose(given["distance"].to_numpy()[below], apart, atol=1e-6)
