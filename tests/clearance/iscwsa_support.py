"""The ISCWSA standard clearance set (tests/data/iscwsa-clearance, see its README) as
gyropipe inputs: stations DataFrames, the offset wells' first-station positions, the site
and the rule's parameters as the set states them."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tests_support import ROOT, CliResult, gyropipe_cli

DATA = ROOT / "tests" / "data" / "iscwsa-clearance" / "wells-01-06.json"
INCH = 0.0254
OFFSETS = [f"0{k} - well" for k in range(1, 7)]


@cache
def data() -> dict[str, Any]:
    loaded: dict[str, Any] = json.loads(DATA.read_text())
    return loaded


def stations(name: str) -> pd.DataFrame:
    """A well's stations (MD m, inclination and grid azimuth deg)."""
    w = data()["wells"][name]
    frame = pd.DataFrame({"md": w["MD"], "inc": w["IncDeg"], "azi": w["AziDeg"]})
    frame.attrs["north_reference"] = "grid"
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
            n: (data()["wells"][n]["N"][0], data()["wells"][n]["E"][0]) for n in OFFSETS
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
