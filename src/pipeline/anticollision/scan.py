"""Anti-collision scan: every reference station against the closest point of each offset well,
and the least separation factor along each reference course.

All wells are given in one frame: NEV positions (m) from one origin, azimuths from one north
(radians), covariances (m²) in that frame. For each reference station and offset well the
closest point of the offset's minimum-curvature path (:mod:`.geometry`) is found, the
offset's covariance there interpolated linearly in MD between its two stations, and the
separation factor computed by the ISCWSA rule (:mod:`.rule`).

Between stations: along each reference course (station k → k + 1) the reference point moves
on its minimum-curvature arc, its covariance interpolated linearly in MD, and the SF of each
point against the offset's closest point is minimised: where the SF falls inward from both
ends of a course (sampled ``BETWEEN_STEP`` of the course inside each), golden-section search
over the course (to ``BETWEEN_TOL`` of it) finds the least; elsewhere the least of the two
stations stands (a course whose SF rises from both ends, then dips twice, is not looked
into). The
least SF of a course, its end stations included, is reported on the row of its upper
station (the last station: its own SF).

Each offset is scanned against its own view of the reference (:class:`Pair`): the whole
reference, or — for a sidetrack of it — the reference from the common point down, with its
covariance zeroed there.

The travelling-cylinder angle is the direction of the closest approach in the plane normal
to the reference well, clockwise from the high side looking down the hole (90°: right); at a
vertical station, from the direction of the station's azimuth.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.anticollision.geometry import Closest, ClosestPoints
from pipeline.anticollision.rule import (
    RuleLimits,
    Separation,
    SeparationRule,
    levels,
    separation,
)
from pipeline.survey.interpolate import MinCurvePath
from pipeline.survey.north import wrap_360
from pipeline.survey.stations import defined_azimuths

__all__ = ["BETWEEN_STEP", "BETWEEN_TOL", "ClearanceScan", "Pair", "Well", "scan", "scan_pairs"]

FloatArray = NDArray[np.float64]
BETWEEN_STEP = 1e-4
"""Fraction of a course inside each end where the SF is sampled: a course whose SF falls
inward from both ends holds a minimum between its stations."""
BETWEEN_TOL = 1e-6
"""Fraction of the course to which the between-station minimum is refined."""
_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


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


Relative = Callable[[NDArray[np.intp], FloatArray, NDArray[np.intp], FloatArray], FloatArray]
"""The relative covariance (m, 3, 3) of reference points (course, fraction) and offset points
(step, fraction): one pair's wells not independent."""


@dataclass(frozen=True)
class Pair:
    """An offset well and the reference as scanned against it (its rows); ``relative``: the
    covariance of their relative position, where the two are not independent (their own
    covariances then unused)."""

    reference: Well
    offset: Well
    relative: Relative | None = None


@dataclass(frozen=True)
class ClearanceScan:
    """Rows (reference station × offset well), offset-major; lengths m, angles deg.
    ``level`` is decided on ``sf_between`` (or on ``sf`` with ``level_on="station"``)."""

    offset: NDArray[np.str_]
    md: FloatArray
    offset_md: FloatArray
    distance: FloatArray
    sigma_s: FloatArray
    sf: FloatArray
    sf_between: FloatArray
    md_between: FloatArray
    level: NDArray[np.str_]
    toolface: FloatArray


def _normal_plane(inc: FloatArray, azi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """High-side and right unit vectors (n, 3) of the reference at each station."""
    a = defined_azimuths(azi)
    ci, si, ca, sa = np.cos(inc), np.sin(inc), np.cos(a), np.sin(a)
    high = np.stack([ci * ca, ci * sa, -si], axis=1)
    right = np.stack([-sa, ca, np.zeros_like(sa)], axis=1)
    return high, right


def _lerp(a: FloatArray, b: FloatArray, t: FloatArray) -> FloatArray:
    """Covariances (m, 3, 3) a + t·(b − a), exactly ``a`` at t = 0 and ``b`` at t = 1 (so a
    station's own covariance holds there when the next one is NaN, flagged)."""
    g = t[:, None, None]
    out: FloatArray = np.where(g == 0.0, a, np.where(g == 1.0, b, (1.0 - g) * a + g * b))
    return out


class _Course:
    """SF of points along the reference courses against one offset well."""

    def __init__(self, pair: Pair, rule: SeparationRule):
        self.ref, self.off, self.rule = pair.reference, pair.offset, rule
        self.relative = pair.relative
        self.ref_path = self.ref.path()
        self.closest = ClosestPoints(self.off.path())
        self.radii = self.ref.radius + self.off.radius

    def at(self, k: NDArray[np.intp], f: FloatArray) -> tuple[Closest, Separation]:
        """Closest offset points and the separation of reference points at fractions f of
        courses k (f = 0 of course k is station k; course n − 1 ends the path)."""
        last = k >= self.ref.md.size - 1
        kk = np.where(last, k - 1, k)
        ff = np.where(last, 1.0, f)
        p = self.ref_path.position(kk, ff).T
        c_ref = _lerp(self.ref.cov[kk], self.ref.cov[kk + 1], ff)
        near = self.closest(p)
        if self.relative is not None:
            c_ref = self.relative(kk, ff, near.step, near.fraction)
            c_off = np.zeros_like(c_ref)
        else:
            c_off = _lerp(self.off.cov[near.step], self.off.cov[near.step + 1], near.fraction)
        sep = separation(p, c_ref, near.position, c_off, self.radii, self.rule)
        return near, sep

    def sf(self, k: NDArray[np.intp], f: FloatArray) -> FloatArray:
        out: FloatArray = self.at(k, f)[1].sf
        return out

    def least(self, at_stations: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Least SF on each course (end stations included, their SF ``at_stations``) and
        its fraction of the course."""
        n = self.ref.md.size - 1
        if n < 1:
            return np.zeros(0), np.zeros(0)
        start, end = at_stations[:-1], at_stations[1:]
        courses = np.arange(n)
        inward = (self.sf(courses, np.full(n, BETWEEN_STEP)) < start) & (
            self.sf(courses, np.full(n, 1.0 - BETWEEN_STEP)) < end
        )
        least = np.minimum(start, end)
        frac = np.where(end < start, 1.0, 0.0)
        courses = courses[inward]
        if courses.size:
            lo, hi = np.zeros(courses.size), np.ones(courses.size)
            a = hi - _GOLDEN * (hi - lo)
            b = lo + _GOLDEN * (hi - lo)
            fa, fb = self.sf(courses, a), self.sf(courses, b)
            while (hi - lo).max() > BETWEEN_TOL:
                left = fa < fb  # the least lies in [lo, b]: b becomes a, a new point below
                hi = np.where(left, b, hi)
                lo = np.where(left, lo, a)
                x = np.where(left, hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo))
                fx = self.sf(courses, x)
                a, b = np.where(left, x, b), np.where(left, a, x)
                fa, fb = np.where(left, fx, fb), np.where(left, fa, fx)
            f = 0.5 * (lo + hi)
            refined = self.sf(courses, f)
            take = refined < least[courses]
            least[courses[take]] = refined[take]
            frac[courses[take]] = f[take]
        return least, frac


def scan(
    reference: Well,
    offsets: Sequence[Well],
    rule: SeparationRule | None = None,
    limits: RuleLimits | None = None,
    level_on: str = "course",
) -> ClearanceScan:
    """The separation of every reference station from each offset well (at least two
    stations each) by ``rule`` and ``limits`` (default: the ISCWSA rule, SF 1.0 / 1.5)."""
    return scan_pairs([Pair(reference, w) for w in offsets], rule, limits, level_on)


def scan_pairs(
    pairs: Sequence[Pair],
    rule: SeparationRule | None = None,
    limits: RuleLimits | None = None,
    level_on: str = "course",
) -> ClearanceScan:
    """:func:`scan` of each offset well against its own view of the reference; the level
    decided on the least SF along each course (``level_on="course"``) or at the station."""
    if level_on not in ("course", "station"):
        raise ValueError(f"level_on must be 'course' or 'station'; got {level_on!r}")
    rule = rule or SeparationRule()
    parts = []
    for pair in pairs:
        ref = pair.reference
        m = ref.md.size
        course = _Course(pair, rule)
        stations = np.arange(m)
        near, sep = course.at(stations, np.zeros(m))
        least, frac = course.least(sep.sf)
        between = np.append(least, sep.sf[-1])
        md_between = np.append(ref.md[:-1] + frac * np.diff(ref.md), ref.md[-1])
        high, right = _normal_plane(ref.inc, ref.azi)
        d = sep.direction
        toolface = np.degrees(
            np.arctan2(np.einsum("ij,ij->i", d, right), np.einsum("ij,ij->i", d, high))
        )
        parts.append(
            (
                np.full(m, pair.offset.name, dtype=object),
                ref.md,
                near.md,
                sep.distance,
                sep.sigma_s,
                sep.sf,
                between,
                md_between,
                toolface,
            )
        )
    cols = [np.concatenate(c) if parts else np.zeros(0) for c in zip(*parts, strict=True)]
    if not parts:
        cols = [np.zeros(0)] * 9
    decided = cols[6] if level_on == "course" else cols[5]
    return ClearanceScan(
        offset=np.asarray(cols[0], dtype=str),
        md=cols[1],
        offset_md=cols[2],
        distance=cols[3],
        sigma_s=cols[4],
        sf=cols[5],
        sf_between=cols[6],
        md_between=cols[7],
        level=levels(decided, limits or RuleLimits()),
        toolface=wrap_360(cols[8]),
    )
