"""``gp.clearance`` through the public API: offsets from a manifest, from files by id, from
tables named by their well metadata; the result's kind and units; bad calls refused."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest

import pipeline as gp
from pipeline.errors import GyropipeError, MissingSiteError, ParameterError
from tests_support import ROOT

EXAMPLE = ROOT / "examples" / "clearance"
REFERENCE = EXAMPLE / "reference.csv"
RULE = {
    "reference_model": "ISCWSA-MWD-REV4",
    "reference_hole_diameter": 36 * 0.0254,
    "magnetic": {"total_field": 50000.0, "dip": 70.0, "declination": 0.0},
}


@pytest.fixture(scope="module")
def from_manifest():  # type: ignore[no-untyped-def]
    return gp.clearance(str(REFERENCE), EXAMPLE / "manifest.csv", **RULE)


def test_manifest_gives_a_frame_per_offset_and_station(from_manifest):  # type: ignore[no-untyped-def]
    frame = from_manifest
    assert len(frame) == 600
    assert list(dict.fromkeys(frame.offset)) == [f"offset-0{k}" for k in range(1, 7)]
    assert frame.attrs["units"]["distance"] == "m"
    assert np.isfinite(frame.sf).all()
    assert frame.groupby("offset").md.apply(lambda md: md.is_monotonic_increasing).all()


def test_files_by_id_and_arrow_reference_give_the_same_table(from_manifest):  # type: ignore[no-untyped-def]
    reference = gp.read_table(REFERENCE)
    offsets = {f"offset-0{k}": EXAMPLE / "offsets" / f"offset-0{k}.csv" for k in (3, 4)}
    positions = {"offset-03": (0.0, 10.0), "offset-04": (0.0, 20.0)}
    table = gp.clearance(
        reference,
        offsets,
        offset_model="iscwsa-mwd-rev4",
        offset_hole_diameter=24 * 0.0254,
        offset_position=positions,
        **RULE,
    )
    assert isinstance(table, pa.Table)
    assert (
        table.schema.field("sf").metadata is None
        or b"unit" not in table.schema.field("sf").metadata
    )
    assert table.schema.field("toolface").metadata[b"unit"] == b"deg"
    expected = from_manifest[from_manifest.offset.isin(list(offsets))]
    assert table.column("sf").to_numpy() == pytest.approx(expected.sf.to_numpy(), rel=1e-12)


def test_tables_named_by_their_well_metadata():
    offsets = [gp.read(EXAMPLE / "offsets" / f"offset-0{k}.csv") for k in (1, 2)]
    assert [o.attrs["well"]["well"] for o in offsets] == ["ISCWSA offset 01", "ISCWSA offset 02"]
    frame = gp.clearance(
        gp.read(REFERENCE),
        offsets,
        offset_model="ISCWSA-MWD-REV4",
        offset_hole_diameter=0.6096,
        offset_position={"ISCWSA offset 01": (0, 100), "ISCWSA offset 02": (100, 0)},
        **RULE,
    )
    assert sorted(set(frame.offset)) == ["ISCWSA offset 01", "ISCWSA offset 02"]
    # well 01 runs parallel 100 m east: at every station the closest point is abeam
    parallel = frame[frame.offset == "ISCWSA offset 01"]
    assert parallel.distance.to_numpy() == pytest.approx(np.full(100, 100.0), abs=0.02)
    assert parallel.offset_md.to_numpy() == pytest.approx(parallel.md.to_numpy(), abs=0.05)


def test_bad_calls_are_refused_with_what_to_give():
    one = {"A": EXAMPLE / "offsets" / "offset-01.csv"}
    with pytest.raises(ParameterError, match="offset_hole_diameter"):
        gp.clearance(str(REFERENCE), one, **RULE)
    with pytest.raises(ParameterError, match="reference_hole_diameter"):
        gp.clearance(str(REFERENCE), one, offset_hole_diameter=0.3, reference_model="GYRO-NS")
    with pytest.raises(ParameterError, match="unknown tool model 'MWD-7'"):
        gp.clearance(
            str(REFERENCE), one, offset_hole_diameter=0.3, **{**RULE, "reference_model": "MWD-7"}
        )
    with pytest.raises(ParameterError, match="no offset_position for offset well 'A'"):
        gp.clearance(str(REFERENCE), one, offset_hole_diameter=0.3, offset_position={}, **RULE)


def test_gyro_model_without_a_latitude_names_what_is_missing():
    stations = gp.read(REFERENCE)
    stations.attrs["well"] = {"north_reference": "grid", "grid_convergence": 0.0}
    with pytest.raises(GyropipeError) as caught:
        gp.clearance(
            stations,
            {"A": EXAMPLE / "offsets" / "offset-01.csv"},
            offset_hole_diameter=0.3,
            offset_position={"A": (0, 100)},
            reference_model="GYRO-NS",
            reference_hole_diameter=0.3,
            offset_model="GYRO-NS",
        )
    assert isinstance(caught.value.__cause__, MissingSiteError)
    assert "needs the site latitude" in str(caught.value)


def test_grid_north_with_convergence_gives_the_true_north_answer():
    """The same pad described in true north and in grid north (convergence 2°: azimuths and
    slot coordinates turned by −2°): every separation factor is the same."""
    gamma = 2.0
    offsets = {k: gp.read(EXAMPLE / "offsets" / f"offset-0{k}.csv") for k in (3, 5)}
    slots = {3: (0.0, 10.0), 5: (-50.0, -500.0)}

    def run(north: str, turn: float) -> np.ndarray:
        c, s = np.cos(np.radians(turn)), np.sin(np.radians(turn))
        ref = gp.read(REFERENCE)
        frames = {}
        for name, frame in [("reference", ref), *offsets.items()]:
            frame = frame.copy()
            frame["azi"] = (frame.azi - turn) % 360.0
            frame.attrs = {"north_reference": north}
            frames[name] = frame
        reference = frames.pop("reference")
        return gp.clearance(
            reference,
            {f"W{k}": f for k, f in frames.items()},
            offset_model="ISCWSA-MWD-REV4",
            offset_hole_diameter=0.6096,
            offset_position={
                f"W{k}": (n * c + e * s, -n * s + e * c) for k, (n, e) in slots.items()
            },
            well={"latitude": 60.0, "grid_convergence": turn if north == "grid" else 0.0},
            **RULE,
        ).sf.to_numpy()

    with pytest.warns(UserWarning, match="convergence .2.0°. taken: the same grid assumed"):
        on_grid = run("grid", gamma)  # the offsets state none: the reference's
    assert on_grid == pytest.approx(run("true", 0.0), rel=1e-9)


@pytest.mark.parametrize("by", ["manifest", "id"])
def test_an_offset_naming_no_north_takes_none_from_the_reference(tmp_path, by):  # type: ignore[no-untyped-def]
    """An offset listing that names no north reference for its azimuths is refused, as the
    CLI's reader refuses it: it never takes the reference file's (grid here) as its own."""
    silent = tmp_path / "offset-01.csv"
    text = (EXAMPLE / "offsets" / "offset-01.csv").read_text()
    silent.write_text(text.replace("Azimuth Grid (deg)", "Azimuth (deg)"))
    if by == "manifest":
        manifest = tmp_path / "manifest.csv"
        manifest.write_text(
            "well_id,file,model,hole_diameter (in),north (m),east (m)\n"
            "offset-01,offset-01.csv,ISCWSA-MWD-REV4,24,0,100\n"
        )
        call = {"offsets": manifest}
    else:
        call = {
            "offsets": {"offset-01": silent},
            "offset_model": "iscwsa-mwd-rev4",
            "offset_hole_diameter": 24 * 0.0254,
            "offset_position": {"offset-01": (0.0, 100.0)},
        }
    with pytest.raises(GyropipeError, match="no north reference for the azimuths"):
        gp.clearance(str(REFERENCE), **call, **RULE)
    stated = gp.clearance(str(REFERENCE), **call, **RULE, well={"north_reference": "grid"})
    assert np.isfinite(stated.sf).all()
