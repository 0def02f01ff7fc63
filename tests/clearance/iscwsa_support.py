"""The ISCWSA standard clearance set (tests/data/iscwsa-clearance, see its README) as
gyropipe inputs: stations DataFrames, the offset wells' first-station positions, the site
and the rule's parameters as the set states them; and the set's precision (it computes its
separation factors from D and each well's σ rounded to 0.01 m)."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tests_support import ROOT, CliResult, gyropipe_cli

DATA = ROOT / "tests" / "data" / "iscwsa-clearance"
INCH = 0.0254
OFFSETS = [f"{k:02d} - well" for k in range(1, 12)]
ROUNDING = 0.005
"""Half the 0.01 m to which the set rounds D and each well's σ before its SF."""


@cache
def data() -> dict[str, Any]:
    """Both files of the set merged: the rule and every well (reference, 01–11)."""
    first, second = (
        json.loads((DATA / f).read_text()) for f in ("wells-01-06.json", "wells-07-11.json")
    )
    return {"acr": first["acr"], "wells": {**first["wells"], **second["wells"]}}


def rounding_band(
    distance: np.ndarray, sigma_s: np.ndarray, *, sigmas: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """The least and greatest SF the set's arithmetic can give from D and σ_S (m) rounded as
    it rounds them: D ± 0.005 m, and (``sigmas``) each of the two wells' σ along the line
    within one 0.01 m step of its rounding (± 0.01 m) — bounded through σ_S alone,
    |Σ r(σ_i)² − σ_S²| ≤ 0.02·√2·σ_S + 2e-4 m². The rule's constants are the set's."""
    acr = data()["acr"]
    radii = 0.5 * (acr["reference_h_and_c"] + acr["offset_h_and_c"]) * INCH + acr["Sm"]
    spread = (0.02 * np.sqrt(2.0) * sigma_s + 2e-4) if sigmas else np.zeros_like(sigma_s)
    lo_var = np.clip(sigma_s**2 - spread, 0.0, None) + acr["sigmapa"] ** 2
    hi_var = sigma_s**2 + spread + acr["sigmapa"] ** 2
    k = acr["k"]
    ends = [
        (distance + dd - radii) / (k * np.sqrt(v))
        for dd in (-ROUNDING, ROUNDING)
        for v in (lo_var, hi_var)
    ]
    return np.min(ends, axis=0), np.max(ends, axis=0)


def stations(name: str) -> pd.DataFrame:
    """A well's stations (MD m, inclination and grid azimuth deg), with the set's grid
    convergence in its well metadata."""
    w = data()["wells"][name]
    frame = pd.DataFrame({"md": w["MD"], "inc": w["IncDeg"], "azi": w["AziDeg"]})
    frame.attrs["north_reference"] = "grid"
    frame.attrs["well"] = {"grid_convergence": site()["grid_convergence"]}
    return frame


def expected_sf(name: str) -> np.ndarray:
    return np.asarray(data()["wells"][name]["SF"], dtype=float)


def site() -> dict[str, Any]:
    """The set's site as well metadata, and its geomagnetic reference (dip stored in rad)."""
    h = data()["wells"]["Reference well"]["header"]
    return {
        "latitude": h["latitude"],
        "longitude": h["longitude"],
        "survey_date": h["survey_date"],
        "grid_convergence": h["convergence"],
        "declination": h["declination"],
    }


def magnetic() -> dict[str, float]:
    h = data()["wells"]["Reference well"]["header"]
    return {
        "total_field": h["b_total"],
        "dip": float(np.degrees(h["dip"])),
        "declination": h["declination"],
    }


def clearance_options(model: str) -> dict[str, Any]:
    """Keyword arguments of ``gp.clearance`` for the set, every well surveyed by ``model``."""
    acr = data()["acr"]
    return {
        "offset_model": model,
        "offset_hole_diameter": acr["offset_h_and_c"] * INCH,
        "offset_position": {
            n: tuple(data()["wells"][n][c][0] for c in ("N", "E", "TVD")) for n in OFFSETS
        },
        "reference_model": model,
        "reference_hole_diameter": acr["reference_h_and_c"] * INCH,
        "k": acr["k"],
        "sigma_pa": acr["sigmapa"],
        "surface_margin": acr["Sm"],
        "magnetic": magnetic(),
        "well": site(),
    }


def run_clearance(
    manifest: str | Path, out: Path, *settings: str, check: bool = False
) -> CliResult:
    """`gyropipe run pipelines/clearance.yaml` on the bundled reference well against the
    offset wells ``manifest`` lists (the set's 36 in reference hole), ``settings`` as
    ``--set`` values."""
    sets = [
        arg for s in ("clearance.reference_hole_diameter=0.9144", *settings) for arg in ("--set", s)
    ]
    return gyropipe_cli(
        "run",
        "pipelines/clearance.yaml",
        "--input",
        "reference=examples/clearance/reference.csv",
        "--input",
        f"offsets={manifest}",
        *sets,
        "--out",
        str(out),
        check=check,
    )


def write_set(folder: Path) -> Path:
    """The set's offset wells 01–11 as stations files and a manifest (24 in holes, MWD Rev 4,
    each first station's position) in ``folder``; the manifest's path."""
    folder.mkdir(parents=True, exist_ok=True)
    rows = ["well_id,file,model,hole_diameter (in),north (m),east (m),tvd (m)"]
    for name in OFFSETS:
        w = data()["wells"][name]
        lines = ["MD (m),Inc (deg),Azimuth Grid (deg)"]
        lines += [f"{m},{i},{a}" for m, i, a in zip(w["MD"], w["IncDeg"], w["AziDeg"], strict=True)]
        file = folder / f"offset-{name[:2]}.csv"
        file.write_text("\n".join(lines) + "\n")
        rows.append(
            f"{name},{file.name},ISCWSA-MWD-REV4,{data()['acr']['offset_h_and_c']},"
            f"{w['N'][0]},{w['E'][0]},{w['TVD'][0]}"
        )
    manifest = folder / "manifest.csv"
    manifest.write_text("\n".join(rows) + "\n")
    return manifest
