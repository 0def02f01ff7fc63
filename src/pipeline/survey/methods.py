"""Legacy survey calculation methods, batched and vectorised like :mod:`.mincurve`.

Same frame and units as minimum curvature: NED (north, east, TVD down), inclination I from
vertical, azimuth A clockwise from north, radians and metres. Per step (station 1 → 2,
ΔMD = L, t(I, A) = (sin I cos A, sin I sin A, cos I)):

    tangential            Δ = L · t(I2, A2)                      (the lower station's angles)
    balanced tangential   Δ = L/2 · (t(I1, A1) + t(I2, A2))
    average angle         Δ = L · t(Ī, Ā),  Ī = (I1 + I2)/2,  Ā = A1 + wrap(A2 − A1)/2
    radius of curvature   ΔTVD = L (sin I2 − sin I1)/(I2 − I1)
                          H    = L (cos I1 − cos I2)/(I2 − I1)
                          ΔN   = H (sin A2 − sin A1)/(A2 − A1)
                          ΔE   = H (cos A1 − cos A2)/(A2 − A1)
                          with the limits L cos I, L sin I, H cos A, H sin A where I1 = I2 or
                          A1 = A2. Evaluated as the average-angle step scaled by
                          sinc(ΔI/2) (vertical), sinc(ΔI/2)·sinc(ΔA/2) (horizontal), which is
                          the same expression without the 0/0.

ΔA is always wrapped into (−π, π] (the short way round). The dogleg and DLS columns are the
method-independent angle between consecutive tool axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, TypeAlias, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pipeline.survey.mincurve import (
    FloatArray,
    IndexArray,
    _bounds,
    _cumsum_per_survey,
    _stations,
    _ties,
    minimum_curvature,
    step_azimuths,
)

__all__ = [
    "METHODS",
    "Method",
    "MethodResult",
    "build_turn_rates",
    "dogleg",
    "survey_positions",
]

Method: TypeAlias = Literal[
    "minimum_curvature", "tangential", "balanced_tangential", "average_angle", "radius_of_curvature"
]
METHODS: tuple[Method, ...] = get_args(Method)

_DEG_PER_30M = np.degrees(1.0) * 30.0  # rad/m → deg/30 m


@dataclass(frozen=True)
class MethodResult:
    """Per-station results, aligned with the input arrays (NED positions in m)."""

    north: FloatArray
    east: FloatArray
    tvd: FloatArray
    #: rad, dogleg from the previous station (0 at each survey's first station).
    dogleg: FloatArray
    #: rad/m, dogleg / ΔMD (0 at each survey's first station and for zero-length steps).
    dls: FloatArray


def wrap_pi(angle: FloatArray) -> FloatArray:
    """Angles wrapped into (−π, π]."""
    out: FloatArray = np.pi - np.mod(np.pi - angle, 2.0 * np.pi)
    return out


def _sinc(x: FloatArray) -> FloatArray:
    """sin x / x (1 at 0)."""
    out: FloatArray = np.sinc(x / np.pi)
    return out


def _step_displacements(
    method: Method, md: FloatArray, inc: FloatArray, a1: FloatArray, a2: FloatArray
) -> FloatArray:
    """(3, n − 1) displacements of the steps between consecutive stations, from the
    azimuths at the start and end of each step (:func:`step_azimuths`)."""
    length = np.diff(md)
    i1, i2 = inc[:-1], inc[1:]
    if method == "tangential":
        si = np.sin(i2)
        tangential: FloatArray = length * np.stack([si * np.cos(a2), si * np.sin(a2), np.cos(i2)])
        return tangential
    if method == "balanced_tangential":
        s1, s2 = np.sin(i1), np.sin(i2)
        balanced: FloatArray = (0.5 * length) * np.stack(
            [
                s1 * np.cos(a1) + s2 * np.cos(a2),
                s1 * np.sin(a1) + s2 * np.sin(a2),
                np.cos(i1) + np.cos(i2),
            ]
        )
        return balanced
    d_inc = i2 - i1
    d_azi = wrap_pi(a2 - a1)
    i_mean = i1 + 0.5 * d_inc
    a_mean = a1 + 0.5 * d_azi
    vertical = length * np.cos(i_mean)
    horizontal = length * np.sin(i_mean)
    if method == "radius_of_curvature":
        f_inc = _sinc(0.5 * d_inc)
        vertical = vertical * f_inc
        horizontal = horizontal * (f_inc * _sinc(0.5 * d_azi))
    elif method != "average_angle":
        raise ValueError(f"unknown survey method {method!r}; expected one of {METHODS}")
    return np.stack([horizontal * np.cos(a_mean), horizontal * np.sin(a_mean), vertical])


def dogleg(inc: FloatArray, a1: FloatArray, a2: FloatArray) -> FloatArray:
    """(n − 1) doglegs (rad) between consecutive tool axes, from the azimuths at the start
    and end of each step (haversine form, stable when small)."""
    hav = np.sin(0.5 * (a2 - a1)) ** 2 * np.sin(inc[:-1]) * np.sin(inc[1:])
    hav += np.sin(0.5 * (inc[1:] - inc[:-1])) ** 2
    out: FloatArray = 2.0 * np.arcsin(np.sqrt(np.clip(hav, 0.0, 1.0)))
    return out


def survey_positions(
    method: Method,
    md: ArrayLike,
    inc: ArrayLike,
    azi: ArrayLike,
    *,
    offsets: ArrayLike | None = None,
    tie_north: ArrayLike = 0.0,
    tie_east: ArrayLike = 0.0,
    tie_tvd: ArrayLike = 0.0,
) -> MethodResult:
    """Integrate one or many surveys (CSR ``offsets``) by ``method`` in one vectorised pass.

    Arguments as :func:`pipeline.survey.mincurve.minimum_curvature` (md m, inc/azi rad, a tie
    position per survey or shared). ``"minimum_curvature"`` delegates to it.

    Raises:
        ValueError: unknown method, malformed shapes or offsets (and, for minimum curvature,
            a reversal).
    """
    if method == "minimum_curvature":
        mc = minimum_curvature(
            md,
            inc,
            azi,
            offsets=offsets,
            tie_north=tie_north,
            tie_east=tie_east,
            tie_tvd=tie_tvd,
        )
        return MethodResult(mc.north, mc.east, mc.tvd, mc.dogleg, mc.dls)
    if method not in METHODS:
        raise ValueError(f"unknown survey method {method!r}; expected one of {METHODS}")
    md_a, inc_a, azi_a = _stations(md, inc, azi)
    n = md_a.size
    bounds = _bounds(offsets, n)
    ties = _ties(bounds.size - 1, tie_north=tie_north, tie_east=tie_east, tie_tvd=tie_tvd)
    a1, a2, both = _filled(azi_a)
    steps = np.empty((3, n))
    steps[:, 1:] = _step_displacements(method, md_a, inc_a, a1, a2)
    steps[:2, 1:][:, both] = 0.0  # both ends vertical: straight down
    first = bounds[:-1]
    steps[:, first] = ties
    dl = np.zeros(n)
    dl[1:] = dogleg(inc_a, a1, a2)
    dl[first] = 0.0
    dls = _per_md(dl, md_a, first)
    north, east, tvd = _cumsum_per_survey(steps, bounds)
    return MethodResult(north=north, east=east, tvd=tvd, dogleg=dl, dls=dls)


def build_turn_rates(
    md: ArrayLike, inc: ArrayLike, azi: ArrayLike, *, offsets: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Build rate ΔI/ΔMD and turn rate wrap(ΔA)/ΔMD of each station from the previous one, in
    deg/30 m (inputs in m and rad). 0 at each survey's first station and on zero-length steps.
    Turn is the short way round, positive clockwise (to the right looking down)."""
    md_a, inc_a, azi_a = _stations(md, inc, azi)
    first = _bounds(offsets, md_a.size)[:-1]
    d_inc = np.zeros(md_a.size)
    d_azi = np.zeros(md_a.size)
    d_inc[1:] = np.diff(inc_a)
    a1, a2, _ = _filled(azi_a)
    d_azi[1:] = wrap_pi(a2 - a1)  # no turn into or out of an undefined (vertical) azimuth
    build = _per_md(d_inc, md_a, first) * _DEG_PER_30M
    turn = _per_md(d_azi, md_a, first) * _DEG_PER_30M
    return build, turn


def _filled(azi: FloatArray) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Each step's start and end azimuths with undefined ones filled as minimum curvature
    fills them (:func:`pipeline.survey.mincurve.step_azimuths`), and the steps with both
    ends undefined."""
    filled = step_azimuths(azi)
    if filled is None:
        return azi[:-1], azi[1:], np.zeros(max(azi.size - 1, 0), dtype=bool)
    return filled


def _per_md(change: FloatArray, md: FloatArray, first: IndexArray) -> FloatArray:
    """change / ΔMD per station (0 at survey starts and zero-length steps)."""
    dmd = np.zeros(md.size)
    dmd[1:] = np.diff(md)
    dmd[first] = 0.0
    out = np.zeros(md.size)
    np.divide(change, dmd, out=out, where=dmd != 0.0)
    out[first] = 0.0
    return out
