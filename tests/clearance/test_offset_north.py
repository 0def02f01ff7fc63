"""Each offset well's azimuths are referred to true north by its own corrections (its file's,
else the manifest's ``declination`` / ``convergence``), never by another offset file's or
the reference well's: the same well written in true, magnetic and grid north, as CSV, LAS
and WITSML files state it, gives the same separation factors; a magnetic-north well with no
declination of its own is refused; a grid-north well with no convergence of its own takes
the reference's only where the reference is on grid north too (with a warning)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning, ParameterError, StageError
from tests_support import ROOT, gyropipe_cli, without_report

EXAMPLE = ROOT / "examples" / "clearance"
RULE = {
    "reference_model": "ISCWSA-MWD-REV4",
    "reference_hole_diameter": 36 * 0.0254,
    "magnetic": {"total_field": 50000.0, "dip": 70.0, "declination": 0.0},
}
SLOTS = {"offset-03": "0,10", "offset-04": "0,20"}
"""Two wells of the ISCWSA set close to the reference (north, east m): SF of a few."""
HEADER = "well_id,file,model,hole_diameter (in),north (m),east (m)"


def survey(name: str) -> np.ndarray:
    """MD, inclination and azimuth (deg) of a well of the example: grid azimuths with a
    grid convergence of 0 there, so its true azimuths too."""
    return np.loadtxt(EXAMPLE / "offsets" / f"{name}.csv", delimiter=",", skiprows=9).T


def csv_file(folder: Path, name: str, north: str, shift: float, **header: float) -> str:
    """The well as a CSV listing with azimuths ``shift`` deg west of true (the ``north``
    word of the header), ``header`` lines above (``Declination: 3.0``)."""
    md, inc, azi = survey(name).tolist()
    lines = [f"Well: {name}", *(f"{k.replace('_', ' ')}: {v}" for k, v in header.items()), ""]
    lines.append(f"MD (m),Inc (deg),Azimuth {north} (deg)")
    lines += [f"{m!r},{i!r},{(a - shift) % 360.0!r}" for m, i, a in zip(md, inc, azi, strict=True)]
    (folder / f"{name}-{north}.csv").write_text("\n".join(lines) + "\n")
    return f"{name}-{north}.csv"


def las_file(folder: Path, name: str, declination: float) -> str:
    """The well as a LAS 2.0 file with magnetic azimuths and its ~Well DECL."""
    md, inc, azi = survey(name).tolist()
    rows = [
        f"{m!r} {i!r} {(a - declination) % 360.0!r}" for m, i, a in zip(md, inc, azi, strict=True)
    ]
    text = f"""~Version
 VERS.   2.0 : CWLS LOG ASCII STANDARD - VERSION 2.0
 WRAP.   NO  : one line per depth step
~Well
 STRT.M  {md[0]!r} : first MD
 STOP.M  {md[-1]!r} : last MD
 STEP.M  0 : irregular
 NULL.   -999.25 : null value
 WELL.   {name} : well
 NREF.   magnetic : north reference
 DECL.DEG  {declination!r} : magnetic declination
~Curve
 DEPT.M   : measured depth
 INC.DEG  : inclination
 AZI.DEG  : azimuth
~A
""" + "\n".join(rows)
    (folder / f"{name}.las").write_text(text + "\n")
    return f"{name}.las"


def witsml_file(folder: Path, name: str, declination: float) -> str:
    """The well as a vendor's WITSML 1.4.1.1 trajectory with magnetic azimuths (rad): WITSML
    has no element for the site's declination, only the one applied (here none)."""
    md, inc, azi = survey(name).tolist()
    stations = "\n".join(
        f'<trajectoryStation uid="s{k}"><md uom="m">{m!r}</md>'
        f'<incl uom="rad">{math.radians(i)!r}</incl>'
        f'<azi uom="rad">{math.radians((a - declination) % 360.0)!r}</azi></trajectoryStation>'
        for k, (m, i, a) in enumerate(zip(md, inc, azi, strict=True))
    )
    text = f"""<?xml version="1.0" encoding="UTF-8"?>
<trajectorys xmlns="http://www.witsml.org/schemas/1series" version="1.4.1.1">
<trajectory uidWell="W-{name}" uidWellbore="W-{name}-1" uid="MWD">
<nameWell>{name}</nameWell><nameWellbore>{name}</nameWellbore><name>MWD survey</name>
<dTimTrajStart>2020-12-30T08:00:00.000Z</dTimTrajStart>
<magDeclUsed uom="rad">0</magDeclUsed><aziRef>magnetic north</aziRef>
{stations}
</trajectory>
</trajectorys>
"""
    (folder / f"{name}.xml").write_text(text)
    return f"{name}.xml"


def manifest(folder: Path, *rows: tuple[str, ...], columns: str = "") -> Path:
    """A manifest of the wells (id, file, the cells of ``columns``) at their slots."""
    lines = [HEADER + columns]
    lines += [",".join((w, f, "ISCWSA-MWD-REV4", "24", SLOTS[w], *more)) for w, f, *more in rows]
    path = folder / "manifest.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def sf(reference: Path, offsets: Path) -> dict[str, np.ndarray]:
    frame = gp.clearance(str(reference), offsets, **RULE)
    return {w: frame[frame.offset == w].sf.to_numpy() for w in SLOTS}


@pytest.fixture
def in_true_north(tmp_path: Path) -> dict[str, np.ndarray]:
    """Both wells in true north, every correction 0: the separation factors to match."""
    folder = tmp_path / "true"
    folder.mkdir()
    rows = [(w, csv_file(folder, w, "True", 0.0)) for w in SLOTS]
    return sf(EXAMPLE / "reference.csv", manifest(folder, *rows))


def same(found: dict[str, np.ndarray], expected: dict[str, np.ndarray]) -> None:
    for well in SLOTS:
        assert found[well] == pytest.approx(expected[well], rel=1e-9, abs=1e-12), well


@pytest.mark.parametrize("kind", ["csv", "las", "witsml"])
def test_a_magnetic_first_offset_is_corrected_by_its_own_declination(
    tmp_path: Path, in_true_north: dict[str, np.ndarray], kind: str
):
    """Offset 03 first, in magnetic north with its own declination 3° (the reference's 0°):
    once corrected by the reference's (3° off) and offset 04 (true north, its file stating a
    declination of 5°) turned to magnetic by 5° and back by 0°."""
    if kind == "csv":
        first = csv_file(tmp_path, "offset-03", "Magnetic", 3.0, Declination=3.0)
    elif kind == "las":
        first = las_file(tmp_path, "offset-03", 3.0)
    else:
        first = witsml_file(tmp_path, "offset-03", 3.0)
    second = csv_file(tmp_path, "offset-04", "True", 0.0, Declination=5.0)
    if kind == "witsml":  # the file cannot state it: the manifest does
        rows = [("offset-03", first, "3.0"), ("offset-04", second, "")]
        path = manifest(tmp_path, *rows, columns=",declination (deg)")
    else:
        path = manifest(tmp_path, ("offset-03", first), ("offset-04", second))
    same(sf(EXAMPLE / "reference.csv", path), in_true_north)


def test_a_grid_offset_is_corrected_by_its_own_convergence(
    tmp_path: Path, in_true_north: dict[str, np.ndarray]
):
    """Offset 03 on a grid 1.5° east of true north (its file says so), the reference's grid
    convergence 0: its azimuths were once taken as the reference's grid, 1.5° off."""
    rows = [
        ("offset-03", csv_file(tmp_path, "offset-03", "Grid", 1.5, Grid_Convergence=1.5)),
        ("offset-04", csv_file(tmp_path, "offset-04", "Magnetic", -2.0, Declination=-2.0)),
    ]
    same(sf(EXAMPLE / "reference.csv", manifest(tmp_path, *rows)), in_true_north)


def test_a_magnetic_offset_without_its_declination_is_refused(
    tmp_path: Path, in_true_north: dict[str, np.ndarray]
):
    """A magnetic-north well whose file states no declination once took the reference's (of
    another site and date); refused naming the manifest line and file, and given by the
    manifest's ``declination`` column it is corrected by it."""
    magnetic = csv_file(tmp_path, "offset-03", "Magnetic", 3.0)
    true = csv_file(tmp_path, "offset-04", "True", 0.0)
    path = manifest(tmp_path, ("offset-03", magnetic), ("offset-04", true))
    with pytest.raises(InputFileError) as caught:
        gp.clearance(str(EXAMPLE / "reference.csv"), path, **RULE)
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'manifest.csv'}:2 (column 'declination'): ")
    assert "offset well 'offset-03'" in message
    assert "offset-03-Magnetic.csv" in message
    assert "magnetic-north azimuths and no declination" in message
    # given for the magnetic well; a null marker (the true-north well's) is no value
    rows = [("offset-03", magnetic, "3.0"), ("offset-04", true, "-999.25")]
    path = manifest(tmp_path, *rows, columns=",declination (deg)")
    same(sf(EXAMPLE / "reference.csv", path), in_true_north)


def test_a_manifest_declination_contradicting_the_file_is_refused(tmp_path: Path):
    magnetic = csv_file(tmp_path, "offset-03", "Magnetic", 3.0, Declination=3.0)
    path = manifest(tmp_path, ("offset-03", magnetic, "2.5"), columns=",declination (deg)")
    with pytest.raises(InputFileError, match=r"declination 2.5 contradicts the file's 3.0"):
        gp.clearance(str(EXAMPLE / "reference.csv"), path, **RULE)


def test_a_manifest_declination_in_radians_agrees_with_the_file_s_degrees(
    tmp_path: Path, in_true_north: dict[str, np.ndarray]
):
    """The file's 3° given again by the manifest in rad (3.0000000000000004° converted):
    one value within well.AGREEING's 1e-6°, as headers agree, not a contradiction."""
    magnetic = csv_file(tmp_path, "offset-03", "Magnetic", 3.0, Declination=3.0)
    true = csv_file(tmp_path, "offset-04", "True", 0.0)
    rows = [("offset-03", magnetic, repr(math.radians(3.0))), ("offset-04", true, "")]
    path = manifest(tmp_path, *rows, columns=",declination (rad)")
    same(sf(EXAMPLE / "reference.csv", path), in_true_north)


def true_reference(folder: Path, *, convergence: bool = False) -> Path:
    """The example's reference well stated in true north (its grid convergence is 0: kept
    in its header with ``convergence``)."""
    text = (EXAMPLE / "reference.csv").read_text().replace("Azimuth Grid", "Azimuth True")
    path = folder / "reference-true.csv"
    path.write_text(text if convergence else text.replace("Grid Convergence: 0.0\n", ""))
    return path


def test_a_grid_offset_without_its_convergence_takes_a_grid_reference_s(
    tmp_path: Path, in_true_north: dict[str, np.ndarray]
):
    """On the reference's grid (the same pad): the reference's convergence, with a warning
    naming the well; against a true-north reference: refused, until the manifest gives it."""
    rows = [
        ("offset-03", csv_file(tmp_path, "offset-03", "Grid", 0.0)),
        ("offset-04", csv_file(tmp_path, "offset-04", "True", 0.0)),
    ]
    path = manifest(tmp_path, *rows)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = sf(EXAMPLE / "reference.csv", path)
    same(found, in_true_north)
    (warning,) = [w for w in caught if issubclass(w.category, InputFileWarning)]
    assert str(warning.message).startswith(f"{path}:2: offset well 'offset-03'")
    assert "the reference well's grid convergence (0.0°) taken: the same grid" in str(
        warning.message
    )
    with pytest.raises(InputFileError) as refused:
        gp.clearance(str(true_reference(tmp_path)), path, **RULE)
    assert "(column 'convergence'): offset well 'offset-03'" in str(refused.value)
    assert "grid-north azimuths and no grid convergence" in str(refused.value)
    taken = "azimuths took the reference well's grid convergence"
    with pytest.warns(InputFileWarning), pytest.raises(StageError, match=taken):
        gp.clearance(str(true_reference(tmp_path, convergence=True)), path, **RULE)
    given = manifest(tmp_path, *((*row, "0") for row in rows), columns=",convergence (deg)")
    same(sf(true_reference(tmp_path), given), in_true_north)


def test_gyropipe_run_refuses_and_warns_naming_the_offset(tmp_path: Path):
    """Through `gyropipe run pipelines/clearance.yaml`: the refusal and the warning."""
    out = tmp_path / "out"

    def run(reference: Path, offsets: Path):  # type: ignore[no-untyped-def]
        return gyropipe_cli(
            "run",
            "pipelines/clearance.yaml",
            "--input",
            f"reference={reference}",
            "--input",
            f"offsets={offsets}",
            "--set",
            "clearance.reference_model=ISCWSA-MWD-REV4",
            "--set",
            "clearance.reference_hole_diameter=0.9144",
            "--out",
            str(out),
        )

    magnetic = manifest(tmp_path, ("offset-03", csv_file(tmp_path, "offset-03", "Magnetic", 3.0)))
    result = run(EXAMPLE / "reference.csv", magnetic)
    assert result.returncode != 0
    assert f"{magnetic}:2 (column 'declination'): offset well 'offset-03'" in result.stderr
    assert "Traceback" not in result.stderr
    grid = manifest(tmp_path, ("offset-03", csv_file(tmp_path, "offset-03", "Grid", 0.0)))
    result = run(EXAMPLE / "reference.csv", grid)
    assert result.returncode == 0, result.stderr
    assert f"warning: {grid}:2: offset well 'offset-03'" in result.stderr
    table = pd.read_parquet(out / "clearance.clearance.parquet")
    assert np.isfinite(table.sf).all()
    assert (
        "offset-03: grid azimuths stating no grid convergence of their own; the reference "
        "well&#x27;s (0.0°) applied, the same grid assumed."
    ) in (out / "report.html").read_text()
    result = run(true_reference(tmp_path, convergence=True), grid)
    assert result.returncode != 0
    assert (
        "offset well 'offset-03': its grid-north azimuths took the reference well's grid "
        "convergence (0.0°), but the reference's azimuths are true north: give its own grid "
        "convergence"
    ) in result.stderr


def test_a_grid_reference_without_its_convergence_is_refused_saying_how(tmp_path: Path):
    """The reference's grid azimuths without a grid convergence: the scan (its frame the
    reference's north, every model's covariance turned into it from true north) refuses,
    naming the stage and how to give it; given on the command line, it runs."""
    grid = (EXAMPLE / "reference.csv").read_text().replace("Grid Convergence: 0.0\n", "")
    reference = tmp_path / "reference-grid.csv"
    reference.write_text(grid)
    offsets = manifest(tmp_path, ("offset-03", csv_file(tmp_path, "offset-03", "True", 0.0)))
    args = [
        "run", without_report("clearance", tmp_path), "--input", f"reference={reference}",
        "--input", f"offsets={offsets}", "--set", "clearance.reference_model=ISCWSA-MWD-REV4",
        "--set", "clearance.reference_hole_diameter=0.9144",
    ]  # fmt: skip
    result = gyropipe_cli(*args, "--out", str(tmp_path / "refused"))
    assert result.returncode == 1, result.output
    assert "stage 'clearance' (clearance" in result.stderr
    assert "needs the grid convergence of the grid-north azimuths" in result.stderr
    assert "--well grid_convergence=" in result.stderr and "Traceback" not in result.stderr
    given = ["--well", "grid_convergence=0.0", "--out", str(tmp_path / "given")]
    assert gyropipe_cli(*args, *given).returncode == 0


def test_offsets_given_by_id_take_their_own_corrections(
    tmp_path: Path, in_true_north: dict[str, np.ndarray]
):
    """``gp.clearance`` with offset files or tables by well id: each well's own declination
    and convergence (once the reference's: 3° off), the norths may differ; a magnetic one
    without its own is refused naming it."""
    magnetic = tmp_path / csv_file(tmp_path, "offset-03", "Magnetic", 3.0, Declination=3.0)
    grid = tmp_path / csv_file(tmp_path, "offset-04", "Grid", -1.5, Grid_Convergence=-1.5)
    options = {
        "offset_model": "ISCWSA-MWD-REV4",
        "offset_hole_diameter": 24 * 0.0254,
        "offset_position": {w: tuple(map(float, at.split(","))) for w, at in SLOTS.items()},
        **RULE,
    }
    for offsets in (
        {"offset-03": magnetic, "offset-04": grid},
        {"offset-03": gp.read(magnetic), "offset-04": gp.read_table(grid)},
    ):
        frame = gp.clearance(str(EXAMPLE / "reference.csv"), offsets, **options)
        same({w: frame[frame.offset == w].sf.to_numpy() for w in SLOTS}, in_true_north)
    silent = tmp_path / csv_file(tmp_path, "offset-04", "Magnetic", 3.0)
    with pytest.raises(ParameterError, match="offset well 'offset-04': magnetic-north azimuths"):
        gp.clearance(str(EXAMPLE / "reference.csv"), {"offset-04": silent}, **options)
