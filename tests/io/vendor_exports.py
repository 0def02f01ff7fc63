"""Survey files as operators' stores and vendors write them, built by the tests: WITSML
1.4.1.1 trajectory exports of a gyro north-seeking survey (angles in rad, DLS in rad/m,
md/tvd in m, ``-999.25``-family nulls in the per-station corrections, a tie-in station
without a tool, the vendor's own TVD/N/E) and CSV station listings."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from tests_support import ROOT

SITE = {"latitude": 58.44, "longitude": 1.887}
"""A North Sea wellhead (WGS84) in the zone of EPSG:23031 (ED50 / UTM 31N)."""
CRS = "EPSG:23031"


@dataclass
class Survey:
    """A J-well: vertical to 300 m, then building 1.5°/30 m to 40° on azimuth 45° (true)."""

    md: np.ndarray = field(default_factory=lambda: np.arange(0.0, 3510.0 + 1e-9, 30.0))

    @property
    def inc(self) -> np.ndarray:
        """Inclination, deg."""
        return np.clip((self.md - 300.0) / 30.0 * 1.5, 0.0, 40.0)

    @property
    def azi(self) -> np.ndarray:
        """Azimuth, deg (true north); 0 where vertical, as vendors write it."""
        return np.where(self.inc > 0.0, 45.0, 0.0)

    def positions(self, azi_deg: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
        """TVD, north, east, DLS (rad/m) by minimum curvature (the vendor's own numbers,
        computed here, apart from gyropipe)."""
        inc = np.radians(self.inc)
        azi = np.radians(self.azi if azi_deg is None else azi_deg)
        tvd, north, east, dls = (np.zeros(self.md.size) for _ in range(4))
        for k in range(1, self.md.size):
            d = self.md[k] - self.md[k - 1]
            i1, i2, a1, a2 = inc[k - 1], inc[k], azi[k - 1], azi[k]
            cos_b = math.cos(i2 - i1) - math.sin(i1) * math.sin(i2) * (1 - math.cos(a2 - a1))
            beta = math.acos(min(1.0, max(-1.0, cos_b)))
            rf = 1.0 if beta < 1e-9 else 2.0 / beta * math.tan(beta / 2.0)
            north[k] = (
                north[k - 1]
                + d / 2 * (math.sin(i1) * math.cos(a1) + math.sin(i2) * math.cos(a2)) * rf
            )
            east[k] = (
                east[k - 1]
                + d / 2 * (math.sin(i1) * math.sin(a1) + math.sin(i2) * math.sin(a2)) * rf
            )
            tvd[k] = tvd[k - 1] + d / 2 * (math.cos(i1) + math.cos(i2)) * rf
            dls[k] = beta / d
        return tvd, north, east, dls


def witsml(
    path: Path,
    survey: Survey | None = None,
    *,
    azi_ref: str = "true north",
    head: str = '<magDeclUsed uom="rad">0</magDeclUsed><gridCorUsed uom="rad">0</gridCorUsed>',
    corrections: str = '<stnMagDeclUsed uom="rad">-999.25</stnMagDeclUsed>'
    '<stnGridCorUsed uom="rad">999.25</stnGridCorUsed>',
    azi_rad: dict[int, str] | None = None,
    angle_uom: str = "rad",
    grid_gamma: float = 0.0,
) -> Path:
    """A vendor's WITSML 1.4.1.1 trajectory of ``survey`` (default :class:`Survey`): the
    tie-in station names no tool, the others ``gyroscopic north seeking``; every station
    carries ``corUsed`` (``corrections``); ``azi_rad`` replaces the azimuth text of a
    station (by index); ``angle_uom`` ``dega`` writes the radian numbers declared degrees;
    ``grid_gamma`` (deg): the listed north/east are referred to a grid north that far east of
    true north, as a vendor lists grid-north azimuths' positions."""
    survey = survey or Survey()
    tvd, true_north, true_east, dls = survey.positions()
    g = math.radians(grid_gamma)
    north = true_north * math.cos(g) + true_east * math.sin(g)
    east = true_east * math.cos(g) - true_north * math.sin(g)
    rows = []
    for k, md in enumerate(survey.md):
        tool = (
            "<typeTrajStation>tie in point</typeTrajStation>"
            if k == 0
            else "<typeTrajStation>gyro north seeking</typeTrajStation>"
            "<typeSurveyTool>gyroscopic north seeking</typeSurveyTool>"
        )
        azi = (azi_rad or {}).get(k, repr(math.radians(survey.azi[k])))
        rows.append(
            f'    <trajectoryStation uid="s{k}">{tool}<md uom="m">{float(md)!r}</md>'
            f'<tvd uom="m">{float(tvd[k])!r}</tvd><incl uom="{angle_uom}">'
            f"{math.radians(survey.inc[k])!r}</incl>"
            f'<azi uom="{angle_uom}">{azi}</azi><dispNs uom="m">{float(north[k])!r}</dispNs>'
            f'<dispEw uom="m">{float(east[k])!r}</dispEw><dls uom="rad/m">{float(dls[k])!r}</dls>'
            f"<corUsed>{corrections}</corUsed></trajectoryStation>"
        )
    text = "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            '<trajectorys xmlns="http://www.witsml.org/schemas/1series" version="1.4.1.1">',
            '  <trajectory uidWell="W-58" uidWellbore="W-58-1" uid="DEF-GYRO">',
            "    <nameWell>58/1-A1</nameWell><nameWellbore>58/1-A1</nameWellbore>",
            "    <name>Definitive gyro survey</name>",
            "    <dTimTrajStart>2026-03-02T08:15:00.000Z</dTimTrajStart>",
            f'    <mdMn uom="m">0</mdMn><mdMx uom="m">{float(survey.md[-1])!r}</mdMx>',
            "    <serviceCompany>North Gyro Services</serviceCompany>",
            f"    {head}",
            f"    <definitive>true</definitive><aziRef>{azi_ref}</aziRef>",
            *rows,
            "  </trajectory>",
            "</trajectorys>",
            "",
        ]
    )
    path.write_text(text)
    return path


def survey_pipeline(
    directory: Path, *stages: dict[str, object], report: bool = False, las: bool = True
) -> Path:
    """``pipelines/survey.yaml`` with ``stages`` inserted after ``read`` (the first takes
    ``read.stations``, the trajectory the last one's), without its report unless ``report``,
    without its LAS export unless ``las`` (a LAS file is one path: the writer refuses
    surveys whose depths run back, a re-survey from surface)."""
    spec = yaml.safe_load((ROOT / "pipelines" / "survey.yaml").read_text())
    kept = [
        s
        for s in spec["stages"]
        if (report or s["uses"] != "report") and (las or s["id"] != "export_las")
    ]
    source = "read.stations"
    added = []
    for stage in stages:
        added.append({**stage, "inputs": {"stations": source}})
        source = f"{stage['id']}.stations"
    for stage in kept:
        if stage["id"] == "trajectory":
            stage["inputs"] = {"stations": source}
    spec["stages"] = [kept[0], *added, *kept[1:]]
    path = directory / "survey.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path
