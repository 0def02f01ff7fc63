"""The shipped tool-model files reproduce the covariances of the hand-coded error models they
replace (``data/legacy-covariances.npz``, written by ``make_legacy_baseline.py`` from main at
``d175d07``): ISCWSA MWD Rev 5 and Rev 5.11, GYRO-NS, GYRO-NS without XCL and GYRO-NS-CT
on ISCWSA test well #1 and a synthetic well, a measured noise, a continuous run from a
measured initial azimuth, both Jacobian bases and both surface conventions.

One change since: the gyro models' course-length terms XCLA/XCLH are in position (the ISCWSA
Rev 5 NEV form of the MWD models, one implementation for every tool; issue 29), where the
hand-coded gyro model had the OWSG sheets' inclination/azimuth form. For those models every
other term is held to the snapshot, and XCLA/XCLH to the MWD Rev 5.11 model's on the survey.

Criterion: within 1e-12 m² (and 1e-12 relative, for the large elements), as the issue asked:
the engine evaluates the same float operations in the same order, but the snapshot was written
on one CPU, and NumPy's vectorised sin/cos/sqrt round the last bit differently on another
(AVX-512: 2.3e-13 m² apart on these sums of many terms).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

import pipeline.uncertainty as pu
from pipeline.earth.site import MagneticReference
from pipeline.survey.mincurve import minimum_curvature
from pipeline.uncertainty.gyro import with_initial_azimuth, with_measured_noise

DATA = Path(__file__).parent / "data"
LEGACY = np.load(DATA / "legacy-covariances.npz")
LAT = 60.0
IU = np.triu_indices(3)
Floats = NDArray[np.float64]


def _well_1() -> tuple[pu.Survey, MagneticReference]:
    data = json.loads((DATA / "iscwsa-well-1-mwdrev5.json").read_text())
    head = data["header"]
    md = np.asarray(data["survey"]["md"], dtype=np.float64)
    inc, azi = np.radians(data["survey"]["inc"]), np.radians(data["survey"]["azi"])
    field = MagneticReference(
        total_field=head["b_total"], dip=head["dip"], declination=head["declination"]
    )
    return pu.Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd), field


def _of(md: Floats, inc_deg: Floats, azi_deg: Floats) -> pu.Survey:
    inc, azi = np.radians(inc_deg), np.radians(azi_deg)
    return pu.Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)


def _surveys() -> dict[str, pu.Survey]:
    """The snapshot's wells (as ``make_legacy_baseline.py`` builds them)."""
    w1, _ = _well_1()
    keep = w1.inc <= np.radians(60.0) + 1e-9
    md = np.concatenate((np.arange(0.0, 300.0, 30.0), [300.0, 300.5], np.arange(330.0, 2500, 30)))
    inc = np.clip((md - 300.0) / 1500.0 * 95.0, 0.0, 95.0)
    azi = (350.0 + np.clip((md - 300.0) / 40.0, 0.0, 20.0)) % 360.0
    flat = np.arange(0.0, 1201.0, 30.0)
    return {
        "well1": w1,
        "well1-gyro": pu.Survey.of(w1.md[keep], w1.inc[keep], w1.azi[keep], w1.tvd[keep]),
        "synthetic": _of(md, inc, azi),
        "inclined": _of(flat, np.full(flat.size, 30.0), np.full(flat.size, 70.0)),
    }


def _cases() -> list[tuple[str, str, Any, str, str, bool]]:
    """(snapshot key, survey, model, site kind, basis, surface tie)."""
    out: list[tuple[str, str, Any, str, str, bool]] = []
    for well in ("well1", "synthetic"):
        gyro_well = "well1-gyro" if well == "well1" else well
        for name in ("ISCWSA-MWD-REV5", "ISCWSA-MWD-REV5.11"):
            out.append(
                (f"{well}|{name}|balanced_tangent|1", well, name, "mag", "balanced_tangent", True)
            )
        for name in ("GYRO-NS", "GYRO-NS-noXCL", "GYRO-NS-CT"):
            out.append(
                (
                    f"{well}|{name}|balanced_tangent|1",
                    gyro_well,
                    name,
                    "lat",
                    "balanced_tangent",
                    True,
                )
            )
        noisy = with_measured_noise(pu.find_model("GYRO-NS"), 0.3, LAT)
        out.append(
            (
                f"{well}|GYRO-NS+noise0.3|balanced_tangent|1",
                gyro_well,
                noisy,
                "lat",
                "balanced_tangent",
                True,
            )
        )
    out.append(
        ("well1|ISCWSA-MWD-REV5|min_curve|0", "well1", "ISCWSA-MWD-REV5", "mag", "min_curve", False)
    )
    out.append(
        ("well1|GYRO-NS-CT|min_curve|0", "well1-gyro", "GYRO-NS-CT", "lat", "min_curve", False)
    )
    init = with_initial_azimuth(pu.find_model("GYRO-NS-CT"), 0.5)
    out.append(
        (
            "inclined|GYRO-NS-CT+init0.5|balanced_tangent|1",
            "inclined",
            init,
            "lat",
            "balanced_tangent",
            True,
        )
    )
    return out


SURVEYS = _surveys()
CASES = _cases()


def _close(ours: Floats, ref: Floats) -> None:
    """Covariances (m²) equal to the snapshot's within its CPU's rounding (see the module)."""
    np.testing.assert_allclose(ours, ref, rtol=1e-12, atol=1e-12)


def test_every_snapshot_case_is_covered() -> None:
    keys = {k.rsplit("|", 1)[0] for k in LEGACY.files}
    assert keys == {case[0] for case in CASES}


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_model_files_reproduce_the_hand_coded_models(case: tuple[Any, ...]) -> None:
    key, well, model, kind, basis, tie = case
    _, field = _well_1()
    site = pu.ModelSite(magnetic=field) if kind == "mag" else pu.ModelSite(latitude=LAT)
    names, cov = pu.term_covariances(SURVEYS[well], model, site, basis=basis, surface_tie=tie)
    assert names == list(LEGACY[f"{key}|names"])
    terms = cov[:, ::30][:, :, IU[0], IU[1]]
    if kind == "mag" or "XCLA" not in names:  # as the snapshot
        _close(cov.sum(axis=0)[:, IU[0], IU[1]], LEGACY[f"{key}|total"])
        _close(terms, LEGACY[f"{key}|terms"])
        return
    xcl = [names.index("XCLA"), names.index("XCLH")]
    rest = [k for k in range(len(names)) if k not in xcl]
    _close(terms[rest], LEGACY[f"{key}|terms"][rest])
    legacy_rest = LEGACY[f"{key}|total"][::30] - LEGACY[f"{key}|terms"][xcl].sum(axis=0)
    _close(terms[rest].sum(axis=0), legacy_rest)
    mwd_names, mwd = pu.term_covariances(
        SURVEYS[well],
        "ISCWSA-MWD-REV5.11",
        pu.ModelSite(magnetic=field),
        basis=basis,
        surface_tie=tie,
    )
    np.testing.assert_array_equal(cov[xcl], mwd[[mwd_names.index("XCLA"), mwd_names.index("XCLH")]])
