"""Batched, vectorised minimum-curvature integration of inclination/azimuth surveys.

Frame: NED — north, east, true vertical depth (down positive). Inclination I is measured from
vertical, azimuth A clockwise from north, so the tool axis is t = (sin I cos A, sin I sin A, cos I).
Angles are in radians and lengths in metres; the stage layer converts.

An undefined azimuth (NaN, a vertical station) takes the other end's azimuth in each step;
a step with both ends undefined goes straight down (:func:`step_azimuths`).

Per step (station 1 → 2):

    β   = 2·asin(√(sin²((I2−I1)/2) + sin I1 sin I2 sin²((A2−A1)/2)))      dogleg
    RF  = tan(β/2)/(β/2)                                                   ratio factor
    Δ   = ΔMD/2 · (t1 + t2) · RF                                           displacement
    DLS = β/ΔMD
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["MinCurveResult", "closure", "minimum_curvature", "step_azimuths", "vertical_section"]

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]

#: Below this dogleg (rad) RF is its Taylor series 1 + β²/12 + β⁴/120 + 17β⁶/20160, whose
#: truncation error there is < 1e-36. tan(β/2)/(β/2) has no cancellation (it is accurate to a
#: few ulp for any β > 0), so the threshold only has to keep it away from 0/0.
SERIES_BELOW = 1e-4

#: Steps whose dogleg is within this margin (rad) of π are rejected with a ValueError. At β = π
#: the tool axes are opposite, every plane through them holds a 180° arc and RF is infinite;
#: near π the haversine dogleg loses accuracy as ~3e-16/(π−β)², i.e. ~4e-10 of ΔMD at the margin.
REVERSAL_MARGIN = 1e-3

_TWO_PI = 2.0 * np.pi
_BLOCK = 4096  # stations per block: keeps the temporaries of the step arithmetic in cache


@dataclass(frozen=True)
class MinCurveResult:
    """Per-station results, aligned with the input arrays.

    Positions are in metres (NED, TVD down positive), with each survey's first station at that
    survey's tie-in point.
    """

    north: FloatArray
    east: FloatArray
    tvd: FloatArray
    #: rad, dogleg from the previous station (0 at each survey's first station).
    dogleg: FloatArray
    #: rad/m, dogleg / ΔMD (0 at each survey's first station and for zero-length steps).
    dls: FloatArray


def minimum_curvature(
    md: ArrayLike,
    inc: ArrayLike,
    azi: ArrayLike,
    *,
    offsets: ArrayLike | None = None,
    tie_north: ArrayLike = 0.0,
    tie_east: ArrayLike = 0.0,
    tie_tvd: ArrayLike = 0.0,
) -> MinCurveResult:
    """Integrate one or many surveys by minimum curvature in a single vectorised pass.

    Args:
        md: measured depth (m), 1-D; several surveys may be concatenated.
        inc: inclination from vertical (rad), same shape as ``md``.
        azi: azimuth clockwise from north (rad), same shape as ``md``.
        offsets: CSR bounds of the surveys, ints of length n_surveys + 1, strictly increasing
            from 0 to ``len(md)``; ``None`` means a single survey.
        tie_north, tie_east, tie_tvd: position (m) of each survey's first station, a scalar or
            one value per survey.

    Each survey is accumulated on its own, so its result does not depend on the batch it is in.
    Value checks (finite, MD increasing, inclination range) are the caller's contracts.

    Raises:
        ValueError: on malformed shapes or offsets, or on a step whose dogleg is within
            ``REVERSAL_MARGIN`` of π (named by survey and station).
    """
    md_a, inc_a, azi_a = _stations(md, inc, azi)
    n = md_a.size
    bounds = _bounds(offsets, n)
    ties = _ties(bounds.size - 1, tie_north=tie_north, tie_east=tie_east, tie_tvd=tie_tvd)

    steps = np.empty((3, n))  # displacement from the previous station (tie-in at first ones)
    dogleg = np.zeros(n)
    dls = np.zeros(n)
    for lo in range(0, n - 1, _BLOCK):
        hi = min(lo + _BLOCK, n - 1) + 1
        _steps(
            md_a[lo:hi],
            inc_a[lo:hi],
            azi_a[lo:hi],
            steps[:, lo + 1 : hi],
            dogleg[lo + 1 : hi],
            dls[lo + 1 : hi],
        )
    first = bounds[:-1]  # the step into a survey's first station comes from the previous survey
    dogleg[first] = 0.0
    dls[first] = 0.0
    _reject_reversals(dogleg, bounds)
    steps[:, first] = ties
    north, east, tvd = _cumsum_per_survey(steps, bounds)
    return MinCurveResult(north=north, east=east, tvd=tvd, dogleg=dogleg, dls=dls)


def vertical_section(north: ArrayLike, east: ArrayLike, azimuth_rad: ArrayLike) -> FloatArray:
    """Horizontal displacement (m) projected on the vertical plane of azimuth ``azimuth_rad``."""
    az = np.asarray(azimuth_rad, dtype=np.float64)
    vs: FloatArray = np.asarray(north, dtype=np.float64) * np.cos(az)
    vs += np.asarray(east, dtype=np.float64) * np.sin(az)
    return vs


def closure(north: ArrayLike, east: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Closure distance (m) and direction (rad in [0, 2π), clockwise from north)."""
    n = np.asarray(north, dtype=np.float64)
    e = np.asarray(east, dtype=np.float64)
    direction = np.arctan2(e, n)
    direction = np.where(direction < 0.0, direction + _TWO_PI, direction)
    # a tiny negative angle + 2π rounds to exactly 2π, which is north again
    direction = np.where(direction < _TWO_PI, direction, 0.0)
    return np.hypot(n, e), direction


def _steps(
    md: FloatArray,
    inc: FloatArray,
    azi: FloatArray,
    steps: FloatArray,
    dogleg: FloatArray,
    dls: FloatArray,
) -> None:
    """Write the (3, k) displacements, doglegs and DLS of the k steps between k + 1 stations."""
    sin_i, cos_i = np.sin(inc), np.cos(inc)
    filled = step_azimuths(azi)
    a1, a2, both = filled if filled is not None else (azi[:-1], azi[1:], None)
    hav = np.sin(0.5 * (a2 - a1))
    hav *= hav
    hav *= sin_i[:-1]
    hav *= sin_i[1:]
    hav += np.sin(0.5 * (inc[1:] - inc[:-1])) ** 2
    np.clip(hav, 0.0, 1.0, out=hav)
    np.arcsin(np.sqrt(hav, out=hav), out=dogleg)
    dogleg *= 2.0
    dmd = md[1:] - md[:-1]
    np.divide(dogleg, dmd, out=dls, where=dmd != 0.0)

    if filled is None:  # every azimuth defined: one sin/cos per station
        sin_a, cos_a = np.sin(azi), np.cos(azi)
        t_north = np.multiply(sin_i, cos_a, out=cos_a)
        t_east = np.multiply(sin_i, sin_a, out=sin_a)
        np.add(t_north[:-1], t_north[1:], out=steps[0])
        np.add(t_east[:-1], t_east[1:], out=steps[1])
    else:
        steps[0] = sin_i[:-1] * np.cos(a1) + sin_i[1:] * np.cos(a2)
        steps[1] = sin_i[:-1] * np.sin(a1) + sin_i[1:] * np.sin(a2)
        steps[:2, both] = 0.0
    np.add(cos_i[:-1], cos_i[1:], out=steps[2])
    dmd *= 0.5
    dmd *= _ratio_factor(dogleg)
    steps *= dmd


def step_azimuths(
    azi: FloatArray,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]] | None:
    """Azimuths at the start and end of each step, and the steps with both undefined. An
    undefined (NaN) azimuth — a vertical station, where the azimuth does not move the
    position — takes the other end's, the usual practice for a step leaving or reaching
    vertical. Where both are undefined the step has no horizontal direction: its azimuth is
    taken as 0 (for the dogleg) and its horizontal displacement as zero, the mean over an
    unknown direction (exact at I = 0; an inclination that only noise or an accelerometer
    bias gives does not walk the well off north). None when every azimuth is defined."""
    undefined = np.isnan(azi)
    if not undefined.any():
        return None
    a1, a2 = azi[:-1], azi[1:]
    both = undefined[:-1] & undefined[1:]
    a1 = np.where(undefined[:-1], a2, a1)
    a2 = np.where(undefined[1:], a1, a2)
    return np.nan_to_num(a1, nan=0.0), np.nan_to_num(a2, nan=0.0), both


def _ratio_factor(beta: FloatArray) -> FloatArray:
    """RF = tan(β/2)/(β/2); its Taylor series below ``SERIES_BELOW``, so no 0/0 at β = 0."""
    b2 = beta * beta
    rf: FloatArray = 1.0 + b2 * (1.0 / 12.0 + b2 * (1.0 / 120.0 + b2 * (17.0 / 20160.0)))
    half = 0.5 * beta
    np.divide(np.tan(half), half, out=rf, where=beta >= SERIES_BELOW)
    return rf


def _stations(md: ArrayLike, inc: ArrayLike, azi: ArrayLike) -> tuple[FloatArray, ...]:
    arrays = tuple(np.asarray(x, dtype=np.float64) for x in (md, inc, azi))
    shapes = [a.shape for a in arrays]
    if arrays[0].ndim != 1 or len(set(shapes)) != 1:
        raise ValueError(f"md, inc and azi must be 1-D arrays of equal length; got shapes {shapes}")
    return arrays


def _bounds(offsets: ArrayLike | None, n: int) -> IndexArray:
    if offsets is None:
        if n == 0:
            raise ValueError("expected at least one station; md, inc and azi are empty")
        return np.array([0, n], dtype=np.intp)
    bounds = np.asarray(offsets)
    if bounds.ndim != 1 or bounds.size < 2 or not np.issubdtype(bounds.dtype, np.integer):
        raise ValueError(
            "offsets must be a 1-D integer array of length n_surveys + 1 >= 2; "
            f"got dtype {bounds.dtype} and shape {bounds.shape}"
        )
    if bounds[0] != 0 or bounds[-1] != n:
        raise ValueError(
            f"offsets must start at 0 and end at len(md) = {n}; got {bounds[0]} and {bounds[-1]}"
        )
    empty = np.flatnonzero(bounds[1:] <= bounds[:-1])
    if empty.size:
        k = int(empty[0])
        raise ValueError(
            "offsets must be strictly increasing (every survey needs a station); "
            f"got offsets[{k}] = {bounds[k]} and offsets[{k + 1}] = {bounds[k + 1]}"
        )
    return bounds.astype(np.intp, copy=False)


def _ties(n_surveys: int, **ties: ArrayLike) -> FloatArray:
    out = np.empty((3, n_surveys))
    for row, (name, value) in enumerate(ties.items()):
        tie = np.asarray(value, dtype=np.float64)
        if tie.ndim > 1 or (tie.ndim == 1 and tie.size != n_surveys):
            raise ValueError(
                f"{name} must be a scalar or a 1-D array with one value per survey "
                f"({n_surveys}); got shape {tie.shape}"
            )
        out[row] = tie
    return out


def _reject_reversals(dogleg: FloatArray, bounds: IndexArray) -> None:
    limit = np.pi - REVERSAL_MARGIN
    if dogleg.max() > limit:
        station = int(np.argmax(dogleg > limit))
        survey = int(np.searchsorted(bounds, station, side="right")) - 1
        raise ValueError(
            f"survey {survey}, station {station - bounds[survey]} (index {station}): dogleg "
            f"{dogleg[station]:.6f} rad from the previous station is within {REVERSAL_MARGIN} "
            "rad of π; a reversal has no unique circular arc"
        )


def _cumsum_per_survey(steps: FloatArray, bounds: IndexArray) -> FloatArray:
    """Cumulative sums of ``steps`` (3, n) along axis 1, restarting at every survey.

    Each survey is summed sequentially along its own row of a zero-padded grid, so its sums are
    bit-identical whether it is integrated alone or in any batch. Surveys are grouped by
    power-of-two length class, one grid each, which keeps the padding below 2x for any mix of
    lengths.
    """
    lengths = np.diff(bounds)
    length_class = np.frexp(lengths)[1]
    row_start = np.empty(lengths.size, dtype=np.intp)  # first grid cell of each survey
    grids: list[tuple[int, int, int]] = []  # (first cell, rows, width) of each class's grid
    size = 0
    for cls in np.unique(length_class):
        ids = np.flatnonzero(length_class == cls)
        width = int(lengths[ids].max())
        row_start[ids] = size + np.arange(ids.size) * width
        grids.append((size, ids.size, width))
        size += ids.size * width
    cell = np.repeat(row_start - bounds[:-1], lengths)
    cell += np.arange(cell.size)
    padded = np.zeros((3, size))
    for src, dst in zip(steps, padded, strict=True):
        dst[cell] = src
    for first, rows, width in grids:
        grid = padded[:, first : first + rows * width].reshape(3, rows, width)
        np.cumsum(grid, axis=2, out=grid)
    return np.take(padded, cell, axis=1)
