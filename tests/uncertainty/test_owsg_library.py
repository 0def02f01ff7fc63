"""The OWSG tool library (``models/owsg/``, issue 29 item 7): every file parses, names its
OWSG sheet and revision and states the sheet's inclination range; the floating-rig variants
extend their fixed-rig sheets; the models reproduce welleng 0.30's σ at TD on the ISCWSA
test wells (stored figures, and — where welleng is installed — a live subset of
``benchmarks/owsg_conformance.py``); they are selected by name through the API and listed
by ``gyropipe models``.
"""

from __future__ import annotations

import importlib.util
import json
import re
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import pipeline as gp
import pipeline.uncertainty as pu
from pipeline.errors import ToolModelError
from pipeline.tables import Stations
from pipeline.uncertainty.engine import MODELS_DIR
from tests_support import gyropipe_cli

ROOT = Path(__file__).parents[2]
OWSG = MODELS_DIR / "owsg"
FILES = sorted(OWSG.glob("*.yaml"))


def _harness() -> ModuleType:
    """``benchmarks/owsg_conformance.py`` (its wells and σ, the same code the benchmark runs)."""
    path = ROOT / "benchmarks" / "owsg_conformance.py"
    spec = importlib.util.spec_from_file_location("owsg_conformance", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("owsg_conformance", module)
    spec.loader.exec_module(module)
    return module


H = _harness()
WELLS = H.wells()


def test_the_library_ships_the_owsg_sets_each_file_naming_its_sheet() -> None:
    models = [pu.find_model(path) for path in FILES]
    assert len(models) == 94  # with GYRO-NS, GYRO-MWD, GYRO-NS-CT: 97 OWSG models
    names = {m.name for m in models}
    assert {
        "MWD+SRGM",
        "MWD+SRGM+SAG",
        "MWD+SRGM+AX",
        "MWD+SRGM+AX+SAG",
        "MWD+IFR1",
        "MWD+IFR1+AX",
        "MWD+IFR1+MS",
        "MWD+IFR2+SAG+MS",
        "EMS+SRGM",
        "EMS+SRGM+AX+SAG",
        "DIPMETER",
        "CB_Film_MMS",
        "CB_Film_MSS",
        "BLIND",
        "INC-ONLY",
        "INC-ONLY_PLANNED_5_DEG",
        "UNKNOWN",
        "ZERO-ERROR",
        "MWD+HRGM+AX",
        "EMS+LRGM+SAG",
        "FINDS",
        "BLIND+TREND",
        "GYRO-NS_Fl",
        "GYRO-NS-CT_Fl",
    } <= names
    for model in models:
        assert re.match(r"OWSG tool code [AB]\d{3}[A-Z][a-z] \S+, Rev \d", model.source), model
        assert model.revision and model.title.startswith("OWSG"), model.name
        assert pu.find_model(model.name).file == model.file  # found by its name
    ranges = {m.name: m.inclination_range_deg for m in models}
    assert ranges["INC-ONLY"] == (0.0, 30.0) and ranges["INC-ONLY_PLANNED_5_DEG"] == (0.0, 5.0)
    assert ranges["GYRO-NS_Fl"] == (0.0, 89.0) and ranges["GYRO-NS-CT_Fl"] == (0.0, 150.0)
    assert ranges["MWD+SRGM+AX"] == (0.0, 180.0)


def test_floating_rig_variants_extend_their_sheet_with_the_rig_depth_terms() -> None:
    """Every ``_Fl`` model is its fixed-rig sheet with the OWSG floating-rig depth-reference
    terms, DRFR 2.2 m (random) and DRFS 1 m (systematic); its other terms are the sheet's."""
    floating = [p for p in FILES if p.stem.endswith("_fl")]
    assert len(floating) == 47
    for path in floating:
        fl = pu.find_model(path)
        base = pu.find_model(fl.name.removesuffix("_Fl"))
        assert "extends: " + base.name in path.read_text()
        other = {(t.name, t.mode, t.sigma) for t in fl.terms if t.code != "DREF"}
        assert other == {(t.name, t.mode, t.sigma) for t in base.terms if t.code != "DREF"}
        drfs = fl.term("DRFS")
        assert (drfs.mode, drfs.sigma, fl.term("DRFR").sigma) == ("systematic", 1.0, 2.2)


#: welleng 0.30's σ high side, lateral, along hole (m) at TD, by model and well: from
#: ``welleng.survey.Survey(md, inc, azi, header, error_model=NAME)`` (a set-B sheet: its
#: ``iscwsa_json`` dict) with the ISCWSA surface tie-on for every term
#: (``header.first_station_allowance = True``), σ of its ``err.errors.cov_NEVs`` rotated to
#: high side/lateral/along hole — ``welleng_sigma`` of ``benchmarks/owsg_conformance.py``,
#: run 2026-12-01, printed to six significant digits.
WELLENG_TD = {
    ("MWD+SRGM+AX", "1"): (22.656, 202.739, 10.5848),
    ("MWD+IFR2+SAG+MS_Fl", "2"): (3.95335, 4.47503, 4.06714),
    ("EMS+LRGM+AX+SAG", "ref"): (3.42448, 16.8102, 2.34786),
    ("DIPMETER", "3"): (20.7483, 23.0046, 38.5294),
    ("BLIND+TREND", "1"): (313.468, 4701.57, 152.325),
    ("FINDS", "2"): (2.65448, 0.49291, 2.58651),
    ("CB_Film_MMS_Fl", "1"): (36.9189, 196.766, 19.7175),
    ("MWD+HRGM", "3"): (9.93063, 7.91049, 9.70027),
}


@pytest.mark.parametrize(("model", "well"), sorted(WELLENG_TD))
def test_reproduces_wellengs_sigma_at_td(model: str, well: str) -> None:
    sigma = H.ours(model, WELLS[well])[-1]
    np.testing.assert_allclose(sigma, WELLENG_TD[model, well], rtol=1e-5)


def test_an_axial_correction_model_refuses_a_horizontal_east_west_hole() -> None:
    """ISCWSA #3 runs horizontal at 283° true, 270° magnetic: 1 − sin² I sin² Am = 0, where
    the +AX sheets exclude the hole (15°); the weight is refused at its station, never a
    number (welleng gives NaN there)."""
    with pytest.raises(ToolModelError, match=r"ABIXY-TI1S: weight not finite at .*MD 3030 m"):
        H.ours("MWD+SRGM+AX_Fl", WELLS["3"])


def test_an_owsg_model_by_name_through_the_api_and_the_cli() -> None:
    well = WELLS["2"]
    stations = Stations.compiled().make_table(
        {"md": well.md, "inc": well.inc_deg, "azi": well.azi_deg}, north_reference="true"
    )
    trajectory = gp.minimum_curvature(stations, tie_tvd=0.0)
    out = gp.position_uncertainty(trajectory, model="mwd+ifr1+ax_fl", magnetic=well.field.__dict__)
    inc, azi = np.radians(well.inc_deg), np.radians(well.azi_deg)
    tvd = out.column("tvd").to_numpy()
    cov = pu.covariance(pu.Survey.of(well.md, inc, azi, tvd), "MWD+IFR1+AX_Fl", well.site)
    np.testing.assert_allclose(out.column("cov_ee").to_numpy(), cov[:, 1, 1], rtol=1e-9)

    listed = gyropipe_cli("models", check=True).stdout.splitlines()
    start = listed.index("# OWSG tool library, sets A and B (models/owsg/): 94 models")
    rows = listed[start + 1 : start + 95]
    assert [r.split()[0] for r in rows] == sorted(
        (m.name for m in map(pu.find_model, FILES)), key=str.upper
    )
    assert all(re.search(r" \d+–\d+° +\d+ terms ", r) for r in rows)
    assert any(r.startswith("INC-ONLY ") and " 0–30° " in r for r in rows)
    shown = json.loads(gyropipe_cli("models", "INC-ONLY_Fl", "--json", check=True).stdout)
    assert shown["inclination_range"] == [0.0, 30.0]
    assert "valid for inclinations 0–30°" in gyropipe_cli("models", "INC-ONLY", check=True).stdout


#: A fast subset of the conformance run: one model of each family on ISCWSA #1 and #2.
SUBSET = ("MWD+SRGM+AX_Fl", "MWD+IFR1+MS", "EMS+HRGM+SAG", "DIPMETER_Fl", "FINDS", "ZERO-ERROR")


@pytest.mark.parametrize("model", SUBSET)
def test_agrees_with_welleng_on_iscwsa_wells_1_and_2(model: str) -> None:
    pytest.importorskip("welleng")
    for key in ("1", "2"):
        ref = H.welleng_sigma(model, WELLS[key])
        assert not isinstance(ref, str), ref
        td, per_station = H.deviation(H.ours(model, WELLS[key]), ref)
        assert td <= 1e-9 and per_station <= 1e-9, (model, key, td, per_station)


def test_welleng_refuses_a_well_beyond_the_sheets_range() -> None:
    pytest.importorskip("welleng")
    assert H.welleng_sigma("INC-ONLY", WELLS["2"]).startswith("refused")


def test_a_files_validity_is_read_inherited_and_checked(tmp_path: Path) -> None:
    """``validity: {inclination_deg: [lo, hi]}`` (the sheet's range, deg) is kept on the
    model and inherited by a file that extends it without one; an unknown key in it is a
    ``ToolModelError`` at its line."""
    child = tmp_path / "child.yaml"
    child.write_text("format: gyropipe-tool-model/1\nname: C\nextends: INC-ONLY\n")
    assert pu.find_model(child).inclination_range_deg == (0.0, 30.0)
    child.write_text(child.read_text() + "validity: {inclination_deg: [0, 20]}\n")
    assert pu.find_model(child).inclination_range_deg == (0.0, 20.0)
    child.write_text(child.read_text().replace("[0, 20]}", "[0, 20], azimuth: 1}"))
    with pytest.raises(ToolModelError, match=r"child\.yaml:4:.*azimuth"):
        pu.find_model(child)


def test_the_generator_writes_the_committed_files_from_wellengs_transcription(
    tmp_path: Path,
) -> None:
    """``benchmarks/make_owsg_models.py`` (the files' documented origin) writes exactly the
    committed files from welleng 0.30's transcription of the OWSG sheets."""
    pytest.importorskip("welleng")
    path = ROOT / "benchmarks" / "make_owsg_models.py"
    spec = importlib.util.spec_from_file_location("make_owsg_models", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("make_owsg_models", module)  # its dataclasses look it up
    spec.loader.exec_module(module)
    assert module.main(["--out", str(tmp_path)]) == 0
    written = sorted(tmp_path.glob("*.yaml"))
    assert [p.name for p in written] == [p.name for p in FILES]
    for new, old in zip(written, FILES, strict=True):
        assert new.read_text() == old.read_text(), old.name
