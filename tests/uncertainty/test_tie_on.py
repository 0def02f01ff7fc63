"""The uncertainty of a survey tied on below the depth reference: a survey whose first
station is a tie-on point from outside the run (its file's listing at MD 500 m) starts its σ
there as if that position were exactly known — it did so without a word. Now the
deliverables say the tie-on's uncertainty is not included (summary.json, the report, a
DataFrame's attrs) and the run warns; given the tie-on's covariance (the survey above's at
that MD), it is added to every station and stated; a survey from MD 0 says nothing."""

from __future__ import annotations

import html
import json
import math
import re
from pathlib import Path

import lasio
import numpy as np
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from tests_support import (
    LISTING_HEADER,
    ROOT,
    CliResult,
    gyropipe_cli,
    stage,
    survey_stages,
    write_pipeline,
)

HEADER = LISTING_HEADER
TIE_ROW = "500.00,4.00,310.00,498.30,12.10,-3.40"
"""The tie-on point the vendor lists first: MD, inclination, azimuth, TVD, north, east."""
ROWS = [f"{500.0 + 30.0 * k:.2f},{4.0 + 1.5 * k:.2f},{310.0 + 2.0 * k:.2f}" for k in range(1, 11)]
"""The survey below it (no listed positions)."""
GIVEN = {"nn": 4.0, "ne": 1.0, "nv": 0.2, "ee": 9.0, "ev": -0.3, "vv": 0.25}
"""The tie-on's covariance as the survey above's listing gives it, m²."""
NOT_INCLUDED = (
    "The position uncertainty is propagated from its tie-on at 500.00 m MD, taken as exactly "
    "known: the uncertainty of the tie-on position (of the hole above it) is not included."
)


def stations_file(directory: Path, rows: list[str]) -> Path:
    path = directory / "stations.csv"
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def tied_on(directory: Path) -> Path:
    """The survey as its vendor lists it: the tie-on row with its position, then stations."""
    return stations_file(directory, [f"{TIE_ROW}", *(f"{r},,," for r in ROWS)])


def pipeline(directory: Path) -> Path:
    return write_pipeline(
        directory,
        [
            *survey_stages(),
            stage("uncertainty", "position_uncertainty", {"trajectory": "trajectory.trajectory"},
                  ["trajectory"], model="GYRO-NS"),
            stage("summary", "export", {"trajectory": "uncertainty.trajectory"},
                  writer="json_summary", filename="summary.json"),
            stage("report", "report", {"trajectory": "uncertainty.trajectory"}, formats=["html"]),
        ],
    )  # fmt: skip


def run(tmp_path: Path, name: str, stations: Path, *options: str) -> tuple[Path, CliResult]:
    out = tmp_path / name
    done = gyropipe_cli(
        "run", pipeline(tmp_path), "--input", stations, "--out", out, *options, check=True
    )
    return out, done


def text_of(report: Path) -> str:
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", report.read_text())).split())


def covariances(out: Path, persisted: str = "uncertainty.trajectory") -> np.ndarray:
    table = pq.read_table(out / f"{persisted}.parquet")
    names = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
    return np.column_stack([table.column(n).to_numpy() for n in names])


def test_a_tie_on_from_the_file_is_stated_not_included_and_warned(tmp_path: Path) -> None:
    out, done = run(tmp_path, "bare", tied_on(tmp_path))
    assert "is not included" in done.stderr and "tie_covariance" in done.stderr
    doc = json.loads((out / "summary.json").read_text())
    assert doc["uncertainty"]["tie_on"] == [
        {"survey": None, "md": 500.0, "basis": "not included", "parent": None, "semi_major": None}
    ]
    assert NOT_INCLUDED in text_of(out / "report.html")
    frame = gp.read(out / "uncertainty.trajectory.parquet")
    assert frame.attrs["uncertainty"]["tie_on"][0]["basis"] == "not included"
    # a LAS file of it says so in its uncertainty curves' descriptions
    las = lasio.read(gp.write(frame, tmp_path / "bare.las"))
    for mnemonic in ("cov_nn", "ellipse_major"):
        assert "from the tie-on at 500.00 m MD, its own uncertainty not included" in (
            las.curves[mnemonic].descr
        )
    # the first station's σ is the tie-on allowance's alone: far below a metre
    assert covariances(out)[0, 0] < 0.1


def test_a_given_tie_on_covariance_is_added_to_every_station(tmp_path: Path) -> None:
    bare, _ = run(tmp_path, "bare", tied_on(tmp_path))
    given = "{" + ", ".join(f"{k}: {v}" for k, v in GIVEN.items()) + "}"
    out, done = run(
        tmp_path, "given", tied_on(tmp_path), "--set", f"uncertainty.tie_covariance={given}"
    )
    assert "not included" not in done.stderr
    added = covariances(out) - covariances(bare)
    np.testing.assert_allclose(added, np.tile(list(GIVEN.values()), (len(ROWS) + 1, 1)), atol=1e-9)
    # the horizontal semi-major axis of [[4, 1], [1, 9]] m²: √((13 + √29)/2) m
    semi_major = math.sqrt((13.0 + math.sqrt(29.0)) / 2.0)
    tie = json.loads((out / "summary.json").read_text())["uncertainty"]["tie_on"][0]
    assert tie["basis"] == "given"
    assert tie["semi_major"] == pytest.approx(semi_major, rel=1e-12)
    assert (
        f"includes the given uncertainty of its tie-on at 500.00 m MD ({semi_major:.3g} m "
        "semi-major axis at 1σ)" in text_of(out / "report.html")
    )


def test_a_survey_from_the_depth_reference_says_nothing_of_a_tie_on(tmp_path: Path) -> None:
    rows = ["0.00,0.00,0.00,0.00,0.00,0.00", *(f"{r},,," for r in ROWS)]
    out, done = run(tmp_path, "surface", stations_file(tmp_path, rows))
    assert "tie-on" not in done.stderr
    doc = json.loads((out / "summary.json").read_text())
    assert [t["basis"] for t in doc["uncertainty"]["tie_on"]] == ["wellhead"]
    assert "tie-on position" not in text_of(out / "report.html")
    # and a covariance given for a survey that has no such tie-on is refused, not ignored
    done = gyropipe_cli(
        "run", pipeline(tmp_path), "--input", stations_file(tmp_path, rows), "--out",
        tmp_path / "refused", "--set", "uncertainty.tie_covariance={nn: 1, ee: 1, vv: 1}",
    )  # fmt: skip
    assert done.returncode != 0
    assert "tie_covariance" in done.stderr and "none does" in done.stderr


def test_a_covariance_that_is_none_is_refused_before_the_run(tmp_path: Path) -> None:
    done = gyropipe_cli(
        "run", pipeline(tmp_path), "--input", tied_on(tmp_path), "--out", tmp_path / "out",
        "--set", "uncertainty.tie_covariance={nn: 1, ne: 2, ee: 1, vv: 1}",
    )  # fmt: skip
    assert done.returncode != 0
    assert "tie_covariance" in done.stderr and "not a covariance" in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_definitive_survey_from_below_md_0_says_so_and_takes_the_given(tmp_path: Path) -> None:
    """The definitive survey of a gyro run listed from 300 m (its top hole surveyed before)
    and the MWD run below: not included, then the given covariance added to every station."""
    lines = (ROOT / "examples" / "definitive" / "gyro-run.csv").read_text().splitlines()
    head = lines.index("MD (m),Inc (deg),Azimuth True (deg)") + 1
    deep = [line for line in lines[head:] if line and float(line.split(",")[0]) >= 299.0]
    gyro = tmp_path / "gyro-from-300.csv"
    gyro.write_text("\n".join([*lines[:head], *deep]) + "\n")
    inputs = [
        "--input",
        f"gyro={gyro}",
        "--input",
        f"mwd={ROOT / 'examples/definitive/mwd-run.csv'}",
    ]
    definitive = ROOT / "pipelines" / "definitive.yaml"
    bare = gyropipe_cli("run", definitive, *inputs, "--out", tmp_path / "bare", check=True)
    assert "tie-on at 299.99 m MD" in bare.stderr and "is not included" in bare.stderr
    assert "tie-on at 299.99 m MD, taken as exactly known" in text_of(
        tmp_path / "bare" / "report.html"
    )
    given = "{" + ", ".join(f"{k}: {v}" for k, v in GIVEN.items()) + "}"
    done = gyropipe_cli(
        "run", definitive, *inputs, "--out", tmp_path / "given",
        "--set", f"definitive.tie_covariance={given}", check=True,
    )  # fmt: skip
    assert "not included" not in done.stderr
    added = covariances(tmp_path / "given", "definitive.survey") - covariances(
        tmp_path / "bare", "definitive.survey"
    )
    np.testing.assert_allclose(added, np.tile(list(GIVEN.values()), (added.shape[0], 1)), atol=1e-9)


def test_a_clearance_offset_surveyed_from_below_md_0_is_flagged(tmp_path: Path) -> None:
    """The ISCWSA clearance set with offset 03's file listed from 1,020 m (its top hole
    surveyed before): its separation factors leave the hole above out — warned and stated in
    the report's clearance section; the set as published states nothing of a tie-on."""
    given = ROOT / "examples" / "clearance"
    (tmp_path / "offsets").mkdir()
    for path in (given / "offsets").glob("*.csv"):
        lines = path.read_text().splitlines()
        if path.stem == "offset-03":
            head = lines.index("MD (m),Inc (deg),Azimuth Grid (deg)") + 1
            lines = lines[:head] + [r for r in lines[head:] if r and float(r.split(",")[0]) >= 1000]
        (tmp_path / "offsets" / path.name).write_text("\n".join(lines) + "\n")
    (tmp_path / "manifest.csv").write_text((given / "manifest.csv").read_text())
    args = [
        "--input", f"reference={given / 'reference.csv'}",
        "--set", "clearance.reference_model=ISCWSA-MWD-REV4",
        "--set", "clearance.reference_hole_diameter=0.9144",
        "--set", "report.formats=[html]",
    ]  # fmt: skip
    clearance = ROOT / "pipelines" / "clearance.yaml"
    cut = gyropipe_cli(
        "run", clearance, "--input", f"offsets={tmp_path / 'manifest.csv'}", *args,
        "--out", tmp_path / "cut", check=True,
    )  # fmt: skip
    assert (
        "Survey offset-03: the position uncertainty is propagated from its tie-on at 1020.00 m"
        in cut.stderr
    )
    assert (
        "Tie-on uncertainty offset-03 from 1020.00 m MD: the survey starts at a tie-on taken as "
        "exactly known" in text_of(tmp_path / "cut" / "report.html")
    )
    whole = gyropipe_cli(
        "run", clearance, "--input", f"offsets={given / 'manifest.csv'}", *args,
        "--out", tmp_path / "whole", check=True,
    )  # fmt: skip
    assert "tie-on" not in whole.stderr
    assert "Tie-on uncertainty" not in text_of(tmp_path / "whole" / "report.html")
