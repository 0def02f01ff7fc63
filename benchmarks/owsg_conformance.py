"""Conformance of the OWSG tool library (``models/owsg/`` and the shipped gyro sheets) with
welleng 0.30 on the ISCWSA test wells #1–#3 and the ISCWSA clearance reference well.

Run from the repository root with welleng installed (the bench extra):
``python benchmarks/owsg_conformance.py [--models NAME ...] [--wells 1 2 3 ref]``.
For each model and well it computes σ high side, lateral and along hole (m) at every
station here (balanced-tangent Jacobian, ISCWSA surface tie-on: this project's defaults)
and in welleng (``Survey(..., error_model=NAME)``; a set-B sheet, which welleng's name
index lacks, as its own JSON dict), and prints per model the largest relative deviation at
TD and over the stations where welleng's σ exceeds 0.01 m, with the cause of every
deviation above 0.01 % (:data:`CAUSES`). Where welleng refuses a well (it reaches the
sheet's inclination limit) the cell says so. Exits 1 if a model computed by both deviates
by more than 0.5 % at TD.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.site import MagneticReference
from pipeline.errors import GyropipeError
from pipeline.survey.mincurve import minimum_curvature
from pipeline.uncertainty.ellipse import hla_sigma
from pipeline.uncertainty.engine import MODELS_DIR, covariance, find_model
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.terms import Survey

Floats = NDArray[np.float64]
ROOT = Path(__file__).parents[1]
DATA = ROOT / "tests" / "uncertainty" / "data"
CLEARANCE = ROOT / "tests" / "data" / "iscwsa-clearance" / "wells-01-06.json"
TOLERANCE = 5e-3
"""The done-when bound: σ H/L/A at TD within 0.5 % of welleng's."""
FLOOR = 0.01
"""Stations whose welleng σ is below this (m) are left out of the per-station deviation."""
GYROS = ("GYRO-NS", "GYRO-MWD", "GYRO-NS-CT")
VERTICAL_FIRST_LEG = (
    "welleng's default gives the vertical-hole XYM3/XYM4/CNA terms half the first leg at "
    "station 1 (no surface tie-on), where its own Rev 5 terms and this project give the whole "
    "leg: run with --welleng-default to see it"
)
CNA_LEGACY = (
    "welleng's legacy CNA (set A) gives this vertical-hole term half the first leg at "
    "station 1 whatever the header says (its JSON path, BLIND+TREND and FINDS, gives the whole "
    "leg as here): σ carries 15 m less of the first 30 m leg"
)
#: Models that differ from welleng on purpose (their cause in :data:`CAUSES`): not held to
#: :data:`TOLERANCE`.
DELIBERATE = ("GYRO-NS-CT", "GYRO-NS-CT_Fl")
#: Known causes of deviations, by model name (exact, else the longest prefix that matches).
CAUSES = {
    "BLIND": CNA_LEGACY,
    "BLIND_Fl": CNA_LEGACY,
    "UNKNOWN": CNA_LEGACY,
    "UNKNOWN_Fl": CNA_LEGACY,
    "GYRO-NS-CT": "by design: above the switch inclination the stationary terms are frozen "
    "at their value there, as SPE 90408 states, where welleng keeps evaluating their 1/cos I "
    "weights (3.4e18 m lateral at 90° on #1); on #3, which returns to vertical and re-enters "
    "the continuous mode, also GXY-GRW (welleng carries the walk per continuous section, here "
    "it restarts at the gate: re-initialisation per section)",
}


@dataclass(frozen=True)
class Well:
    name: str
    md: Floats
    inc_deg: Floats
    azi_deg: Floats
    latitude: float
    field: MagneticReference
    g: float

    @property
    def site(self) -> ModelSite:
        return ModelSite(latitude=self.latitude, magnetic=self.field, g=self.g)


def _well(name: str, survey: dict[str, Any], header: dict[str, Any], dip: float) -> Well:
    return Well(
        name,
        np.asarray(survey["md"], float),
        np.asarray(survey["inc"], float),
        np.asarray(survey["azi"], float),
        float(header["latitude"]),
        MagneticReference(
            total_field=float(header["b_total"]), dip=dip, declination=header["declination"]
        ),
        float(header["G"]),
    )


def wells() -> dict[str, Well]:
    """ISCWSA test wells #1 (the Rev 5 example workbook's), #2 and #3 (welleng's test data,
    ``tests/uncertainty/data/README.md``) and the clearance set's reference well (grid =
    true north there, dip given in radians)."""
    out = {}
    for n in ("1", "2", "3"):
        path = DATA / ("iscwsa-well-1-mwdrev5.json" if n == "1" else f"iscwsa-well-{n}.json")
        d = json.loads(path.read_text())
        out[n] = _well(f"ISCWSA #{n}", d["survey"], d["header"], float(d["header"]["dip"]))
    ref = json.loads(CLEARANCE.read_text())["wells"]["Reference well"]
    h = ref["header"]
    survey = {"md": ref["MD"], "inc": ref["IncDeg"], "azi": ref["AziDeg"]}
    out["ref"] = _well("clearance ref", survey, h, float(np.degrees(h["dip"])))
    return out


def ours(model: str, well: Well) -> Floats:
    """σ H/L/A (n, 3) here."""
    inc, azi = np.radians(well.inc_deg), np.radians(well.azi_deg)
    survey = Survey.of(well.md, inc, azi, minimum_curvature(well.md, inc, azi).tvd)
    return hla_sigma(covariance(survey, model, well.site), inc, azi)


def welleng_sigma(model: str, well: Well, tie_every_term: bool = True) -> Floats | str:
    """σ H/L/A (n, 3) in welleng, or why welleng gives none. ``tie_every_term``: the ISCWSA
    surface tie-on (the first station's attitude over the whole first leg) for every term,
    as here (``first_station_allowance=True``); welleng's default leaves it out of the
    vertical-hole branch of XYM3/XYM4 and CNA (:data:`CAUSES`)."""
    import welleng as we
    from welleng.errors import tool_errors

    header = we.survey.SurveyHeader(
        latitude=well.latitude,
        longitude=0.0,
        G=well.g,
        azi_reference="true",
        b_total=well.field.total_field,
        dip=well.field.dip,
        declination=well.field.declination,
    )
    if tie_every_term:
        header.first_station_allowance = True
    chosen: str | dict[str, Any] = model
    if model not in we.error.ERROR_MODELS:
        path = tool_errors._resolve_json_model(model)
        if path is None:
            return "not in welleng"
        chosen = json.loads(Path(path).read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            s = we.survey.Survey(
                md=well.md, inc=well.inc_deg, azi=well.azi_deg, header=header, error_model=chosen
            )
        except AssertionError:
            return "refused (beyond the sheet's inclination range)"
    errors = s.err.errors  # type: ignore[union-attr]
    rad = np.stack((well.md, np.radians(well.inc_deg), np.radians(well.azi_deg)), axis=-1)
    sigma = hla_sigma(np.asarray(errors.cov_NEVs, float), rad[:, 1], rad[:, 2])
    bad = np.flatnonzero(~np.isfinite(sigma).all(axis=1))
    if bad.size:
        k = int(bad[0])
        return (
            f"gives NaN from MD {well.md[k]:g} m (inc {well.inc_deg[k]:g}°, azimuth "
            f"{well.azi_deg[k]:g}°: 1 − sin² I sin² Am = 0, the axial correction's singularity)"
        )
    return sigma


def deviation(a: Floats, b: Floats) -> tuple[float, float]:
    """Largest relative deviation of σ ``a`` from ``b`` at TD and over stations with b >
    :data:`FLOOR` (a zero reference σ: the absolute deviation)."""
    td = np.abs(a[-1] - b[-1]) / np.where(b[-1] > 0, b[-1], 1.0)
    mask = b > FLOOR
    per = np.abs(a - b)[mask] / b[mask] if mask.any() else np.zeros(1)
    return float(td.max()), float(per.max())


def owsg_models() -> list[str]:
    """Every OWSG model shipped: the files of ``models/owsg/`` and the gyro sheets."""
    names = [find_model(p).name for p in sorted((MODELS_DIR / "owsg").glob("*.yaml"))]
    return sorted([*names, *GYROS], key=str.upper)


def cause(model: str) -> str:
    """The known cause of a model's deviation (:data:`CAUSES`), or ""."""
    if model in CAUSES:
        return CAUSES[model]
    return next(
        (CAUSES[k] for k in sorted(CAUSES, key=len, reverse=True) if model.startswith(k)), ""
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--models", nargs="*", default=None)
    parser.add_argument("--wells", nargs="*", default=["1", "2", "3", "ref"])
    parser.add_argument(
        "--welleng-default",
        action="store_true",
        help="welleng's default first leg (no surface tie-on for its vertical-hole XYM3/XYM4/CNA)",
    )
    args = parser.parse_args(argv)
    cases = wells()
    names = args.models or owsg_models()
    print(f"{'model':<28} " + " ".join(f"{cases[w].name:>22}" for w in args.wells))
    print(f"{'':<28} " + " ".join(f"{'TD %':>10} {'stations %':>11}" for _ in args.wells))
    worst = 0.0
    for name in names:
        cells, notes = [], []
        for w in args.wells:
            ref = welleng_sigma(name, cases[w], not args.welleng_default)
            if isinstance(ref, str):
                cells.append(f"{'n/a':>22}")
                notes.append(f"{cases[w].name}: welleng {ref}")
                continue
            try:
                mine = ours(name, cases[w])
            except GyropipeError as exc:
                cells.append(f"{'refused here':>22}")
                notes.append(f"{cases[w].name}: here {str(exc).splitlines()[-1].strip()}")
                continue
            td, per = deviation(mine, ref)
            worst = worst if name in DELIBERATE else max(worst, td)
            cells.append(f"{100 * td:>10.4f} {100 * per:>11.4f}")
            if max(td, per) > 1e-4:
                why = cause(name) or (VERTICAL_FIRST_LEG if args.welleng_default else "unknown")
                notes.append(f"{cases[w].name}: {why}")
        print(f"{name:<28} " + " ".join(cells))
        for note in dict.fromkeys(notes):
            print(f"{'':<30}{note}")
    print(
        f"largest deviation at TD: {100 * worst:.3f} % (bound {100 * TOLERANCE:.1f} %; "
        f"{', '.join(DELIBERATE)} differ by design)"
    )
    return 0 if worst <= TOLERANCE else 1


if __name__ == "__main__":
    sys.exit(main())
