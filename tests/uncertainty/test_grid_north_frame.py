"""The position uncertainty of a trajectory listed in grid or magnetic north is referred to
that north. The error model works in true north (a gyro's earth-rate terms, an MWD model's
magnetic azimuth), so the listing's azimuths go to it true and its covariance comes back
turned. Before, a gyro model took grid azimuths as true ones (its physics off by γ), and an
MWD model's true-north covariance was labelled grid north (its ellipses γ off), silently.

The forward model: one well listed twice, in true north and in grid (or magnetic) north,
azimuths less δ (γ = 2.5°, D = 17°), the well's header stating δ. The second listing's
covariance must be the first's turned by δ (R C Rᵀ, written out here), its ellipse azimuth
the first's less δ (mod 180°), its semi-axes the same."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml

from tests_support import ROOT, gyropipe_cli, stage, survey_stages, without_report, write_pipeline

MD = np.arange(0.0, 1501.0, 30.0)
INC = np.clip((MD - 150.0) / 15.0, 0.0, 50.0)
AZI_TRUE = np.where(MD > 150.0, 40.0 + (MD - 150.0) / 25.0, 40.0)
"""A build-and-turn well (MD m, inclination and true azimuth deg): 0 to 50°, 40° to 94°."""
CONVERGENCE = 2.5  # deg, grid north east of true north
DECLINATION = 17.0  # deg, magnetic north east of true north
SHIFT = {"true": 0.0, "grid": CONVERGENCE, "magnetic": DECLINATION}
"""δ of each listing's north: A = A_true − δ."""
MAGNETIC = {"total_field": 59731.0, "dip": 78.29, "declination": DECLINATION}
"""The site's geomagnetic reference (nT, deg) the MWD runs are given."""
COV = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
TOLERANCE = {"rtol": 1e-9, "atol": 1e-12}  # m²: the two listings differ by rounding only


def listing(directory: Path, north: str, *, corrections: bool = True, first: int = 0) -> Path:
    """The well's stations file in ``north`` north (azimuths less δ), from station
    ``first``; its header states the latitude and (``corrections``) the site for the
    geomagnetic model, the declination and γ."""
    site = ["Longitude: 73.4", "Survey Date: 2026-11-21"]
    stated = [f"Magnetic Declination: {DECLINATION}", f"Grid Convergence: {CONVERGENCE}"]
    head = [
        "Well: G-1",
        "Latitude: 61.25",
        *([*site, *stated] if corrections else []),
        "",
        f"MD (m),Inc (deg),Azimuth {north.capitalize()} (deg)",
    ]
    azi = (AZI_TRUE - SHIFT[north]) % 360.0
    rows = [f"{m:.2f},{i:.10f},{a:.10f}" for m, i, a in zip(MD, INC, azi, strict=True)]
    path = directory / f"{north}-{first}.csv"
    path.write_text("\n".join([*head, *rows[first:]]) + "\n")
    return path


def run(tmp_path: Path, stations: Path, model: str, *options: str) -> dict[str, np.ndarray]:
    """The persisted uncertainty table of ``stations`` under ``model``, by column, and
    the north its azimuths and ellipse azimuths state (``azi_north``)."""
    params = {"model": model, **({"magnetic": MAGNETIC} if "MWD" in model else {})}
    pipeline = write_pipeline(
        tmp_path / "pipeline",
        [
            *survey_stages(),
            stage("uncertainty", "position_uncertainty", {"trajectory": "trajectory.trajectory"},
                  ["trajectory"], **params),
        ],
    )  # fmt: skip
    out = tmp_path / f"{stations.stem}-{model}"
    gyropipe_cli("run", pipeline, "--input", stations, "--out", out, *options, check=True)
    table = pq.read_table(out / "uncertainty.trajectory.parquet")
    north = table.schema.field("azi").metadata[b"north_reference"].decode()
    assert table.schema.field("ellipse_azimuth").metadata[b"north_reference"].decode() == north
    return {
        "azi_north": np.array(north),
        **{n: table.column(n).to_numpy() for n in table.column_names},
    }


def matrices(table: dict[str, np.ndarray]) -> np.ndarray:
    """The NEV covariances (n, 3, 3) of a table's six columns."""
    nn, ne, nv, ee, ev, vv = (table[c] for c in COV)
    return np.stack([np.stack([nn, ne, nv], -1), np.stack([ne, ee, ev], -1), np.stack([nv, ev, vv], -1)], -2)  # fmt: skip


def turned(cov: np.ndarray, delta_deg: float) -> np.ndarray:
    """True-north NEV covariances referred to the north δ east of true: a vector's
    N' = N cos δ + E sin δ, E' = E cos δ − N sin δ, V' = V; C' = R C Rᵀ."""
    c, s = np.cos(np.radians(delta_deg)), np.sin(np.radians(delta_deg))
    rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return rot @ cov @ rot.T


@pytest.mark.parametrize("model", ["GYRO-NS", "ISCWSA-MWD-REV5"])
@pytest.mark.parametrize("north", ["grid", "magnetic"])
def test_a_listing_in_another_north_has_the_true_covariance_turned(
    tmp_path: Path, model: str, north: str
) -> None:
    true = run(tmp_path, listing(tmp_path, "true"), model)
    other = run(tmp_path, listing(tmp_path, north), model)
    assert true["azi_north"] == "true" and other["azi_north"] == north
    delta = SHIFT[north]
    np.testing.assert_allclose(other["azi"], (true["azi"] - delta) % 360.0, atol=1e-9)
    np.testing.assert_allclose(matrices(other), turned(matrices(true), delta), **TOLERANCE)
    for name in ("ellipse_major", "ellipse_minor", "sigma_v", "ellipse_major_conf"):
        np.testing.assert_allclose(other[name], true[name], rtol=1e-9, atol=1e-9)
    # the ellipse's major axis, where it has one (a round ellipse's azimuth is arbitrary)
    shaped = true["ellipse_major"] - true["ellipse_minor"] > 1e-3 * true["ellipse_major"]
    assert shaped.sum() > 40
    difference = (other["ellipse_azimuth"] - true["ellipse_azimuth"] + delta + 90.0) % 180.0 - 90.0
    np.testing.assert_allclose(difference[shaped], 0.0, atol=1e-6)
    # the turn moves the covariance by far more than the tolerance: the test can tell
    assert np.abs(other["cov_ne"] - true["cov_ne"]).max() > 1e-3 * true["cov_nn"].max()


def test_a_given_tie_on_covariance_is_in_the_listings_north(tmp_path: Path) -> None:
    """A survey tied on at 510 m: the ``tie_covariance`` given (stated in the listing's
    north, as its covariance columns are) is added to every station as it is."""
    given = {"nn": 4.0, "ne": 1.0, "nv": 0.2, "ee": 9.0, "ev": -0.3, "vv": 0.25}
    stations = listing(tmp_path, "grid", first=17)
    bare = run(tmp_path / "bare", stations, "GYRO-NS")
    tied = run(
        tmp_path / "tied",
        stations,
        "GYRO-NS",
        "--set",
        "uncertainty.tie_covariance={" + ", ".join(f"{k}: {v}" for k, v in given.items()) + "}",
    )
    added = np.column_stack([tied[c] - bare[c] for c in COV])
    np.testing.assert_allclose(added, np.tile(list(given.values()), (added.shape[0], 1)), atol=1e-9)


@pytest.mark.parametrize(
    ("north", "needed", "field", "value"),
    [
        ("grid", "grid convergence", "grid_convergence", CONVERGENCE),
        ("magnetic", "magnetic declination", "declination", DECLINATION),
    ],
)
def test_a_listing_without_its_correction_to_true_north_is_refused(
    tmp_path: Path, north: str, needed: str, field: str, value: float
) -> None:
    """Grid azimuths without a grid convergence, magnetic ones without a declination (nor
    the site for the geomagnetic model): refused, naming the stage and how to give it (they
    were taken as true north); given on the command line, the run goes."""
    stations = listing(tmp_path, north, corrections=False)
    pipeline = write_pipeline(
        tmp_path / "pipeline",
        [
            *survey_stages(),
            stage("uncertainty", "position_uncertainty", {"trajectory": "trajectory.trajectory"},
                  ["trajectory"]),
        ],
    )  # fmt: skip
    done = gyropipe_cli("run", pipeline, "--input", stations, "--out", tmp_path / "out")
    assert done.returncode == 1, done.output
    assert "stage 'uncertainty' (position_uncertainty" in done.stderr
    assert f"needs the {needed} of the {north}-north azimuths" in done.stderr
    assert f"--well {field}=" in done.stderr and "Traceback" not in done.stderr
    given = gyropipe_cli(
        "run", pipeline, "--input", stations, "--out", tmp_path / "given",
        "--well", f"{field}={value}",
    )  # fmt: skip
    assert given.returncode == 0, given.stderr


def test_a_definitive_survey_in_grid_north_has_the_true_covariance_turned(tmp_path: Path) -> None:
    """The shipped definitive example (gyro top hole, MWD below) and the same two runs
    listed in grid north: the survey's covariance (each run's model in true north) is the
    true-north survey's turned by γ, its ellipse azimuth the true one's less γ."""
    pipeline = without_report("definitive", tmp_path)
    surveys = {}
    for north in ("true", "grid"):
        inputs = []
        for run_name in ("gyro", "mwd"):
            text = (ROOT / "examples" / "definitive" / f"{run_name}-run.csv").read_text()
            head, rows = text.split("\n\nMD (m),Inc (deg),Azimuth True (deg)\n")
            if north == "grid":
                head += f"\nGrid Convergence: {CONVERGENCE}"
            stations = [row.split(",") for row in rows.splitlines()]
            shifted = [
                f"{md},{inc},{(float(azi) - SHIFT[north]) % 360.0:.10f}"
                for md, inc, azi in stations
            ]
            path = tmp_path / f"{north}-{run_name}.csv"
            column = f"Azimuth {north.capitalize()} (deg)"
            path.write_text("\n".join([head, "", f"MD (m),Inc (deg),{column}", *shifted]) + "\n")
            inputs += ["--input", f"{run_name}={path}"]
        out = tmp_path / north
        gyropipe_cli("run", pipeline, *inputs, "--out", out, check=True)
        table = pq.read_table(out / "definitive.survey.parquet")
        assert table.schema.field("ellipse_azimuth").metadata[b"north_reference"] == north.encode()
        surveys[north] = {n: table.column(n).to_numpy() for n in table.column_names}
    true, grid = surveys["true"], surveys["grid"]
    np.testing.assert_allclose(matrices(grid), turned(matrices(true), CONVERGENCE), **TOLERANCE)
    np.testing.assert_allclose(grid["ellipse_major"], true["ellipse_major"], rtol=1e-9)
    shaped = true["ellipse_major"] - true["ellipse_minor"] > 1e-3 * true["ellipse_major"]
    difference = (grid["ellipse_azimuth"] - true["ellipse_azimuth"] + CONVERGENCE + 90.0) % 180.0
    np.testing.assert_allclose(difference[shaped] - 90.0, 0.0, atol=1e-6)


RUN_DECLINATION = {"gyro": 12.0, "mwd": 14.5}
"""Each run's own declination (deg): the two runs surveyed a year apart."""


def definitive_runs(tmp_path: Path, north: str) -> list[str]:
    """The shipped definitive example's two runs listed in ``north`` north, each run's
    azimuths less its own declination and its header stating it (magnetic), as --input."""
    inputs = []
    for run_name, declination in RUN_DECLINATION.items():
        text = (ROOT / "examples" / "definitive" / f"{run_name}-run.csv").read_text()
        head, rows = text.split("\n\nMD (m),Inc (deg),Azimuth True (deg)\n")
        shift = declination if north == "magnetic" else 0.0
        head += f"\nMagnetic Declination: {declination}"
        shifted = [
            f"{md},{inc},{(float(azi) - shift) % 360.0:.13f}"
            for md, inc, azi in (row.split(",") for row in rows.splitlines())
        ]
        path = tmp_path / f"{north}-{run_name}.csv"
        column = f"Azimuth {north.capitalize()} (deg)"
        path.write_text("\n".join([head, "", f"MD (m),Inc (deg),{column}", *shifted]) + "\n")
        inputs += ["--input", f"{run_name}={path}"]
    return inputs


def test_a_definitive_survey_of_runs_in_two_magnetic_norths_is_refused(tmp_path: Path) -> None:
    """The definitive example's runs listed in magnetic north, the gyro's declination 12°,
    the MWD's 14.5°: one survey in "magnetic north" would be integrated from azimuths in two
    norths (before: its MWD stations' positions were in neither run's frame, 126.0 N / 57.9 E
    at 745 m where true north gives 110.6 / 83.7), so it is refused, naming both; given
    north_reference: true, each run is referred to true north by its own declination and the
    survey is the true-north listing's (azimuths, positions, covariances)."""
    pipeline = without_report("definitive", tmp_path)
    refused = gyropipe_cli(
        "run", pipeline, *definitive_runs(tmp_path, "magnetic"), "--out", tmp_path / "refused"
    )
    assert refused.returncode != 0 and "Traceback" not in refused.stderr
    assert (
        "the runs' magnetic norths are not one (magnetic north east of true north by "
        "GYRO-1: 12°, MWD-1: 14.5°)" in refused.stderr
    ), refused.stderr
    assert "give the stage north_reference: true" in refused.stderr
    spec = yaml.safe_load(pipeline.read_text(encoding="utf-8"))
    (stage,) = [st for st in spec["stages"] if st["uses"] == "definitive_survey"]
    stage["with"]["north_reference"] = "true"
    pipeline.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    surveys = {}
    for north in ("true", "magnetic"):
        out = tmp_path / north
        gyropipe_cli("run", pipeline, *definitive_runs(tmp_path, north), "--out", out, check=True)
        table = pq.read_table(out / "definitive.survey.parquet")
        assert table.schema.field("azi").metadata[b"north_reference"] == b"true"
        surveys[north] = table
    true, magnetic = surveys["true"], surveys["magnetic"]
    for name in ("azi", "north", "east", "tvd"):
        np.testing.assert_allclose(
            magnetic.column(name).to_numpy(), true.column(name).to_numpy(), atol=1e-8
        )
    np.testing.assert_allclose(
        matrices({n: magnetic.column(n).to_numpy() for n in COV}),
        matrices({n: true.column(n).to_numpy() for n in COV}),
        rtol=1e-7,
        atol=1e-12,
    )


def test_a_definitive_run_in_grid_north_without_the_convergence_says_how_to_give_it(
    tmp_path: Path,
) -> None:
    """Before: 'run1: grid north needs the grid convergence γ (deg)', not where to give it."""
    pipeline = without_report("definitive", tmp_path)
    inputs = definitive_runs(tmp_path, "grid")
    refused = gyropipe_cli("run", pipeline, *inputs, "--out", tmp_path / "out")
    assert refused.returncode != 0
    assert (
        "the definitive_survey stage needs the grid convergence of run1's grid-north azimuths"
        in refused.stderr
    )
    assert (
        "give the well's `grid_convergence` (deg, grid north east of true north positive) in "
        "the pipeline's `well:` block, on the command line (--well grid_convergence=…) or in "
        "the input file's header" in refused.stderr
    )
    given = ("--well", "grid_convergence=0.5", "--out", tmp_path / "given")
    gyropipe_cli("run", pipeline, *inputs, *given, check=True)
