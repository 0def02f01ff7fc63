"""Write ``data/legacy-covariances.npz``: the covariances the hand-coded error models
(``pipeline.uncertainty.gyro`` and ``.mwd`` as they were at main ``d175d07``, before the tool
models became data files) gave for the test wells, so that the file-driven engine is held to
them (``test_toolmodel_files.py``).

Kept for the record of how the snapshot was made; it is not run by the tests (running it
against today's code would compare the engine with itself), and it runs only at ``d175d07``:
the ``GyroTool``/``gyro_covariance``/``mwd_covariance`` wrappers it calls were removed later
(callers use :mod:`pipeline.uncertainty.engine`). Wells: ISCWSA test well #1 (the
Rev 5 example workbook's survey; to MD 5100 m, the 60° hold, for the gyro models), a synthetic well that is vertical, builds through 90°
to 95°, turns across north (azimuth 350° → 10°) and has a 0.5 m course, and (for a
continuous run from a measured initial azimuth) a straight well at 30°.
Stored per case: the term names, the total NEV covariance at every station and the per-term
covariances at every 30th station (m², float64).

    PYTHONPATH=src python tests/uncertainty/make_legacy_baseline.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from pipeline.uncertainty.mwd import mwd_covariance

from pipeline.earth.site import MagneticReference
from pipeline.survey.mincurve import minimum_curvature
from pipeline.uncertainty.gyro import GyroTool, gyro_covariance
from pipeline.uncertainty.terms import Survey

DATA = Path(__file__).parent / "data"
LAT = 60.0


def well_1() -> tuple[Survey, MagneticReference]:
    data = json.loads((DATA / "iscwsa-well-1-mwdrev5.json").read_text())
    head = data["header"]
    md = np.asarray(data["survey"]["md"], dtype=np.float64)
    inc = np.radians(data["survey"]["inc"])
    azi = np.radians(data["survey"]["azi"])
    field = MagneticReference(
        total_field=head["b_total"], dip=head["dip"], declination=head["declination"]
    )
    return Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd), field


def synthetic() -> Survey:
    md = np.concatenate((np.arange(0.0, 300.0, 30.0), [300.0, 300.5], np.arange(330.0, 2500, 30)))
    inc = np.clip((md - 300.0) / 1500.0 * 95.0, 0.0, 95.0)
    azi = (350.0 + np.clip((md - 300.0) / 40.0, 0.0, 20.0)) % 360.0
    inc_r, azi_r = np.radians(inc), np.radians(azi)
    return Survey.of(md, inc_r, azi_r, minimum_curvature(md, inc_r, azi_r).tvd)


def inclined() -> Survey:
    md = np.arange(0.0, 1201.0, 30.0)
    inc, azi = np.radians(np.full(md.size, 30.0)), np.radians(np.full(md.size, 70.0))
    return Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)


def cases() -> dict[str, tuple[list[str], Any]]:
    w1, field = well_1()
    out: dict[str, tuple[list[str], Any]] = {}
    # the gyro models hold to 60° on well 1 (tan I weights: GYRO-NS is not a horizontal tool)
    keep = w1.inc <= np.radians(60.0) + 1e-9
    w1_gyro = Survey.of(w1.md[keep], w1.inc[keep], w1.azi[keep], w1.tvd[keep])
    for well, survey in (("well1", w1), ("synthetic", synthetic())):
        for model in ("ISCWSA-MWD-REV5", "ISCWSA-MWD-REV5.11"):
            out[f"{well}|{model}|balanced_tangent|1"] = mwd_covariance(survey, field, model)
        survey = w1_gyro if well == "well1" else survey
        for model in ("GYRO-NS", "GYRO-NS-noXCL", "GYRO-NS-CT"):
            out[f"{well}|{model}|balanced_tangent|1"] = gyro_covariance(survey, LAT, model)
        out[f"{well}|GYRO-NS+noise0.3|balanced_tangent|1"] = gyro_covariance(
            survey, LAT, GyroTool().with_measured_noise(0.3, LAT)
        )
    out["well1|ISCWSA-MWD-REV5|min_curve|0"] = mwd_covariance(
        w1, field, "ISCWSA-MWD-REV5", basis="min_curve", surface_tie=False
    )
    out["well1|GYRO-NS-CT|min_curve|0"] = gyro_covariance(
        w1_gyro, LAT, "GYRO-NS-CT", basis="min_curve", surface_tie=False
    )
    ct = GyroTool(continuous=True, sage=0.08, noise_reduction=0.4082, init_sigma_azi=0.5)
    out["inclined|GYRO-NS-CT+init0.5|balanced_tangent|1"] = gyro_covariance(inclined(), LAT, ct)
    return out


def main() -> None:
    arrays: dict[str, Any] = {}
    iu = np.triu_indices(3)
    for key, (names, cov) in cases().items():
        arrays[f"{key}|names"] = np.asarray(names)
        arrays[f"{key}|total"] = cov.sum(axis=0)[:, iu[0], iu[1]]
        arrays[f"{key}|terms"] = cov[:, ::30][:, :, iu[0], iu[1]]
    np.savez_compressed(DATA / "legacy-covariances.npz", **arrays)


if __name__ == "__main__":
    main()
