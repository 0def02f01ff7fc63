"""Anti-collision scan: every reference station against the closest point of each offset well.

All wells are given in one frame: NEV positions (m) from one origin, azimuths from one north
(radians), covariances (m²) in that frame. For each reference station and offset well the
closest point of the offset's minimum-curvature path (:mod:`.geometry`) is found, the
offset's covariance there interpolated linearly in MD between its two stations, and the
separation factor computed by the ISCWSA rule (:mod:`.rule`).

The travelling-cylinder angle is the direction of the closest approach in the plane normal
to the reference well, clockwise from the high side looking down the hole (90°: right); at a
vertical station, from the direction of the station's azimuth.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.anticollision.geometry import closest_points
from pipeline.anticollision.rule import RuleLimits, SeparationRule, levels, separation
from pipeline.survey.interpolate import MinCurvePath
from pipeline.survey.mincurve import minimum_curvature
from pipeline.survey.north import wrap_360
from pipeline.survey.stations import defined_azimuths

__all__ = ["ClearanceScan", "Well", "scan"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Well:
    """One well: stations (MD m, inclination and azimuth rad; NaN azimuth at vertical), the
    position of its first station (north, east, TVD, m), per-station NEV covariance
    (n, 3, 3, m²) and hole radius (m)."""

    name: str
    md: FloatArray
    inc: FloatArray
    azi: FloatArray
    tie: tuple[float, float, float]
    cov: FloatArray
    radius: float

    def path(self) -> MinCurvePath:
        return MinCurvePath(self.md, self.inc, self.azi, self.tie)


@dataclass(frozen=True)
class ClearanceScan:
    """Rows (reference station × offset well), offset-major; lengths m, angles deg."""

    offset: NDArray[np.str_]
    md: FloatArray
    offset_md: FloatArray
    distance: FloatArray
    sigma_s: FloatArray
    sf: FloatArray
    level: NDArray[np.str_]
    toolface: FloatArray


def _normal_plane(inc: FloatArray, azi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """High-side and right unit vectors (n, 3) of the reference at each station."""
    a = defined_azimuths(azi)
    ci, si, ca, sa = np.cos(inc), np.sin(inc), np.cos(a), np.sin(a)
    high = np.stack([ci * ca, ci * sa, -si], axis=1)
    right = np.stack([-sa, ca, np.zeros_like(sa)], axis=1)
    return high, right


def scan(
    reference: Well,
    offsets: Sequence[Well],
    rule: SeparationRule | None = None,
    limits: RuleLimits | None = None,
) -> ClearanceScan:
    """The separation of every reference station from each offset well (at least two
    stations each) by ``rule`` and ``limits`` (default: the ISCWSA rule, SF 1.0 / 1.5)."""
    m = reference.md.size
    mc = minimum_curvature(
        reference.md,
        reference.inc,
        reference.azi,
        tie_north=reference.tie[0],
        tie_east=reference.tie[1],
        tie_tvd=reference.tie[2],
    )
    p_ref = np.stack([mc.north, mc.east, mc.tvd], axis=1)
    parts = []
    for well in offsets:
        path = well.path()
        near = closest_points(path, p_ref)
        f = near.fraction[:, None, None]
        cov = (1.0 - f) * well.cov[near.step] + f * well.cov[near.step + 1]
        parts.append((near.md, near.position, cov, well.radius))
    n = len(offsets)
    p_off = np.concatenate([p[1] for p in parts]) if parts else np.zeros((0, 3))
    c_off = np.concatenate([p[2] for p in parts]) if parts else np.zeros((0, 3, 3))
    radii = reference.radius + np.repeat([p[3] for p in parts], m)
    sep = separation(
        np.tile(p_ref, (n, 1)),
        np.tile(reference.cov, (n, 1, 1)),
        p_off,
        c_off,
        radii,
        rule or SeparationRule(),
    )
    high, right = _normal_plane(reference.inc, reference.azi)
    d = sep.direction
    toolface = np.degrees(
        np.arctan2(
            np.einsum("ij,ij->i", d, np.tile(right, (n, 1))),
            np.einsum("ij,ij->i", d, np.tile(high, (n, 1))),
        )
    )
    return ClearanceScan(
        offset=np.repeat(np.array([w.name for w in offsets], dtype=str), m),
        md=np.tile(reference.md, n),
        offset_md=np.concatenate([p[0] for p in parts]) if parts else np.zeros(0),
        distance=sep.distance,
        sigma_s=sep.sigma_s,
        sf=sep.sf,
        level=levels(sep.sf, limits or RuleLimits()),
        toolface=wrap_360(toolface),
    )
