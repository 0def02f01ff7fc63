"""Interpolation on the minimum-curvature path: at any MD, and at a TVD (every crossing).

Between stations 1 and 2 (ΔMD = L, dogleg β, unit tool axes t1, t2) minimum curvature is the
circular arc from t1 to t2. At fraction f = (s − MD1)/L of the step:

    tangent   t(f) = [sin((1 − f)β)·t1 + sin(fβ)·t2] / sin β               (slerp)
    position  r(f) = r1 + L/(β sin β)·[(cos((1 − f)β) − cos β)·t1 + (1 − cos fβ)·t2]

both evaluated through sinc (sin x/x) so that β → 0 reduces to the straight line exactly:

    t(f) = [(1 − f)·S((1 − f)β)·t1 + f·S(fβ)·t2] / S(β)
    r(f) = r1 + L/S(β)·[f(2 − f)/2·S((2 − f)β/2)·S(fβ/2)·t1 + f²/2·S(fβ/2)²·t2]

At f = 1 r(f) is the minimum-curvature step Δ. Inputs are radians and metres; one survey per
call (loop over the surveys of a batch).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pipeline.survey.mincurve import FloatArray, IndexArray, minimum_curvature, step_azimuths

__all__ = ["Interpolated", "MinCurvePath", "interpolate_md", "interpolate_tvd"]

_StepFunc = Callable[[IndexArray, FloatArray], FloatArray]

_BISECTIONS = 64
_VERTICAL_BELOW = 1e-12  # |horizontal tangent| below which the azimuth is taken from a station


@dataclass(frozen=True)
class Interpolated:
    """Points on the path (radians, metres, NED), one row per point."""

    md: FloatArray
    inc: FloatArray
    azi: FloatArray  #: in [0, 2π)
    north: FloatArray
    east: FloatArray
    tvd: FloatArray
    #: index of the requested value (MD or TVD) each point answers.
    target: IndexArray


class MinCurvePath:
    """One survey's stations, positions ``r`` (3, n), tool axes at the ends of each step
    ``t1``, ``t2`` (3, n − 1), doglegs ``beta`` and course lengths ``length`` (rad, m)."""

    def __init__(
        self,
        md: ArrayLike,
        inc: ArrayLike,
        azi: ArrayLike,
        tie: tuple[float, float, float],
    ) -> None:
        self.md, self.inc, self.azi = (np.asarray(x, dtype=np.float64) for x in (md, inc, azi))
        if (
            self.md.ndim != 1
            or self.md.size < 2
            or not (self.md.shape == self.inc.shape == self.azi.shape)
        ):
            raise ValueError(
                "md, inc and azi must be 1-D arrays of equal length >= 2; got shapes "
                f"{self.md.shape}, {self.inc.shape}, {self.azi.shape}"
            )
        if (np.diff(self.md) <= 0.0).any():
            raise ValueError("md must increase strictly")
        mc = minimum_curvature(
            self.md, self.inc, self.azi, tie_north=tie[0], tie_east=tie[1], tie_tvd=tie[2]
        )
        self.r = np.stack([mc.north, mc.east, mc.tvd])  # (3, n)
        # tool axes at the start and end of each step, an undefined azimuth (vertical) filled
        # as minimum curvature fills it (a step with both ends undefined goes straight down)
        filled = step_azimuths(self.azi)
        a1, a2, both = filled if filled is not None else (self.azi[:-1], self.azi[1:], None)
        si, ci = np.sin(self.inc), np.cos(self.inc)
        self.t1 = np.stack([si[:-1] * np.cos(a1), si[:-1] * np.sin(a1), ci[:-1]])
        self.t2 = np.stack([si[1:] * np.cos(a2), si[1:] * np.sin(a2), ci[1:]])
        if both is not None:
            self.t1[:2, both] = 0.0
            self.t2[:2, both] = 0.0
        self.beta = mc.dogleg[1:]
        self.length = np.diff(self.md)

    def locate(self, md: FloatArray) -> tuple[IndexArray, FloatArray]:
        """Step index and fraction of each MD (the last station belongs to the last step)."""
        k = np.clip(np.searchsorted(self.md, md, side="right") - 1, 0, self.md.size - 2)
        return k.astype(np.intp), (md - self.md[k]) / self.length[k]

    def position(self, k: IndexArray, f: FloatArray) -> FloatArray:
        """(3, m) positions at fractions f of steps k."""
        b = self.beta[k]
        sb = _sinc(b)
        half = _sinc(0.5 * f * b)
        c1 = self.length[k] * (0.5 * f * (2.0 - f)) * _sinc(0.5 * (2.0 - f) * b) * half / sb
        c2 = self.length[k] * (0.5 * f * f) * half * half / sb
        out: FloatArray = self.r[:, k] + c1 * self.t1[:, k] + c2 * self.t2[:, k]
        return out

    def tangent(self, k: IndexArray, f: FloatArray) -> FloatArray:
        """(3, m) unit tangents at fractions f of steps k."""
        b = self.beta[k]
        w1 = (1.0 - f) * _sinc((1.0 - f) * b)
        w2 = f * _sinc(f * b)
        t = (w1 * self.t1[:, k] + w2 * self.t2[:, k]) / _sinc(b)
        out: FloatArray = t / np.linalg.norm(t, axis=0)
        return out

    def points(self, md: FloatArray, target: IndexArray) -> Interpolated:
        k, f = self.locate(md)
        r = self.position(k, f)
        t = self.tangent(k, f)
        horizontal = np.hypot(t[0], t[1])
        inc = np.arctan2(horizontal, t[2])
        # vertical tangent: the azimuth the path is heading to (the step's lower station)
        azi = np.where(horizontal < _VERTICAL_BELOW, self.azi[k + 1], np.arctan2(t[1], t[0]))
        # stations are reproduced exactly at their own MD
        at = np.searchsorted(self.md, md)
        at = np.minimum(at, self.md.size - 1)
        hit = self.md[at] == md
        j = at[hit]
        inc[hit] = self.inc[j]
        azi[hit] = self.azi[j]
        r[:, hit] = self.r[:, j]
        azi = np.mod(azi, 2.0 * np.pi)
        azi[azi >= 2.0 * np.pi] = 0.0
        return Interpolated(md, inc, azi, r[0], r[1], r[2], target)


def _sinc(x: FloatArray) -> FloatArray:
    out: FloatArray = np.sinc(x / np.pi)
    return out


def interpolate_md(
    md: ArrayLike,
    inc: ArrayLike,
    azi: ArrayLike,
    at_md: ArrayLike,
    *,
    tie: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Interpolated:
    """Points on the minimum-curvature path of one survey at the MDs ``at_md`` (m, in the
    survey's range, any order), inclination/azimuth in rad. ``tie`` is the first station's
    (north, east, TVD). Stations are reproduced exactly at their own MD.

    Raises:
        ValueError: malformed stations or an MD outside [md[0], md[-1]].
    """
    path = MinCurvePath(md, inc, azi, tie)
    s = np.atleast_1d(np.asarray(at_md, dtype=np.float64))
    if s.ndim != 1:
        raise ValueError(f"at_md must be a scalar or 1-D; got shape {s.shape}")
    outside = ~((s >= path.md[0]) & (s <= path.md[-1]))
    if outside.any():
        raise ValueError(
            f"md {s[np.argmax(outside)]} m is outside the survey [{path.md[0]}, {path.md[-1]}] m"
        )
    return path.points(s, np.arange(s.size, dtype=np.intp))


def interpolate_tvd(
    md: ArrayLike,
    inc: ArrayLike,
    azi: ArrayLike,
    at_tvd: ArrayLike,
    *,
    tie: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Interpolated:
    """Every point where the minimum-curvature path of one survey crosses each TVD of
    ``at_tvd`` (m), sorted by MD; ``target`` says which TVD each answers.

    Each arc is split where its tangent is horizontal (at most once: an arc turns by less than
    π), so TVD is monotonic on every piece and each piece holds at most one crossing, found by
    bisection on the closed-form arc to machine precision. A crossing on a piece boundary is
    reported once (pieces are half-open, the survey's last piece closed); a horizontal piece
    lying at exactly a target TVD reports its start.
    """
    path = MinCurvePath(md, inc, azi, tie)
    targets = np.atleast_1d(np.asarray(at_tvd, dtype=np.float64))
    if targets.ndim != 1:
        raise ValueError(f"at_tvd must be a scalar or 1-D; got shape {targets.shape}")
    n_steps = path.length.size
    steps = np.arange(n_steps, dtype=np.intp)
    # split points where the vertical tangent component changes sign
    tz1, tz2 = path.t1[2], path.t2[2]
    turns = np.flatnonzero(tz1 * tz2 < 0.0).astype(np.intp)
    f_turn = _bisect(lambda k, f: path.tangent(k, f)[2], turns, np.zeros(turns.size), 1.0)
    piece_k = np.concatenate([steps, turns])
    piece_a = np.concatenate([np.zeros(n_steps), f_turn])
    piece_b = np.ones(piece_k.size)
    ends = np.ones(n_steps)
    ends[turns] = f_turn
    piece_b[:n_steps] = ends
    # each piece starts at piece_a; the first pieces end at the turn when there is one
    last = (piece_k == n_steps - 1) & (piece_b == 1.0)
    za = path.position(piece_k, piece_a)[2]
    zb = path.position(piece_k, piece_b)[2]

    pk = np.repeat(np.arange(piece_k.size, dtype=np.intp), targets.size)
    pt = np.tile(np.arange(targets.size, dtype=np.intp), piece_k.size)
    T = targets[pt]
    ga, gb = za[pk] - T, zb[pk] - T
    hit = (ga * gb <= 0.0) & ((gb != 0.0) | last[pk] | (ga == 0.0))
    pk, pt, ga = pk[hit], pt[hit], ga[hit]
    k = piece_k[pk]
    t_ = targets[pt]
    f = _bisect(
        lambda kk, ff: path.position(kk, ff)[2] - t_, k, piece_a[pk], piece_b[pk], sign_lo=ga
    )
    f = np.where(ga == 0.0, piece_a[pk], f)
    md_x = path.md[k] + f * path.length[k]
    md_x = np.where(f == 1.0, path.md[k + 1], md_x)
    order = np.lexsort((pt, md_x))
    return path.points(md_x[order], pt[order].astype(np.intp))


def _bisect(
    func: _StepFunc,
    k: IndexArray,
    lo: FloatArray,
    hi: float | FloatArray,
    *,
    sign_lo: FloatArray | None = None,
) -> FloatArray:
    """Vectorised bisection for the root of ``func(k, f)`` with f in [lo, hi] (a sign change
    assumed), to machine precision; returns whichever end has the smaller residual."""
    lo = lo.astype(np.float64, copy=True)
    hi_a = np.broadcast_to(np.asarray(hi, dtype=np.float64), lo.shape).copy()
    if k.size == 0:
        return lo
    s_lo = np.sign(func(k, lo)) if sign_lo is None else np.sign(sign_lo)
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi_a)
        same = np.sign(func(k, mid)) == s_lo
        lo = np.where(same, mid, lo)
        hi_a = np.where(same, hi_a, mid)
    pick_lo = np.abs(func(k, lo)) <= np.abs(func(k, hi_a))
    out: FloatArray = np.where(pick_lo, lo, hi_a)
    return out
