"""The frame positions' weighted least squares (the gyro model of
:mod:`pipeline.gyrocompass.solve`, step 2), for the stations of a record at once.

A station's problem is set up alone (:func:`design`: its rejects, in its own order); the
problems of one shape are then solved together (:func:`fit_all`), one call of each numpy
routine on their stack. The stacked routines work matrix by matrix as on one, so every
station gets its own fit's numbers; the stack only saves the per-call overhead that
dominates on these tiny matrices (28 stations of 5 positions: ~2.5 → ~0.8 ms). Rates in
°/h, times in s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.earth_rate import StationReject
from pipeline.gyrocompass.precision import position_design

MAX_CONDITION = 1e10
"""The largest condition number (2-norm) of a fit's normal matrix that is solved."""
ILL_CONDITIONED = "the frame positions do not span the circle (ill-conditioned fit)"
"""Why a fit whose normal matrix's condition number exceeds :data:`MAX_CONDITION` is not."""


@dataclass(frozen=True)
class Design:
    """One station's weighted least squares: design matrix ``a`` (rows, columns), weights
    ``w`` = 1/σ² ((°/h)⁻²) and readings ``y`` (°/h) of the rows, the axes one after the other."""

    a: FloatArray
    w: FloatArray
    y: FloatArray
    terms: int


@dataclass(frozen=True)
class Fit:
    """One station's fitted parameters: the Earth rate's (u, v) (°/h) and the parameters'
    covariance, the first axis' bias (°/h) and trend (°/h/s), the residuals' rms (°/h), χ²
    and its degrees of freedom."""

    uv: FloatArray
    cov: FloatArray
    bias: float
    trend: float
    rms: float
    chi2: float
    dof: int


def design(
    alpha: FloatArray, t: FloatArray, gyro: FloatArray, sigma: FloatArray, terms: int
) -> Design:
    """The problem of one station's positions at frame angles ``alpha`` (rad) and times ``t``
    (s), readings ``gyro`` (n, axes) and their ``sigma`` (°/h), with ``terms`` extra unknowns
    per transverse axis: 0 none, 1 a bias, 2 a bias and a trend. A :class:`StationReject`
    when a σ is not positive or the positions are too few for the unknowns."""
    n, m = gyro.shape
    if not (sigma > 0).all():
        raise StationReject("a position's gyro σ is zero (noise-free data?): set noise_floor")
    axes = min(m, 2)
    a = position_design(alpha, t, axes, terms)
    columns = a.shape[1]
    y = gyro[:, :axes].T.ravel()
    w = 1.0 / sigma[:, :axes].T.ravel() ** 2
    if len(y) < columns:
        what = ("Earth rate", "bias", "trend")[: 1 + terms]
        raise StationReject(
            f"{n} position(s) cannot resolve {columns} unknowns ({', '.join(what)}); "
            "use more positions or trend: false"
        )
    return Design(a, w, y, terms)


def fit_all(designs: Sequence[Design]) -> list[Fit | StationReject]:
    """Each problem's fit, in order, or the :class:`StationReject` of one whose normal
    matrix is ill-conditioned (never inverted)."""
    fits: dict[int, Fit | StationReject] = {}
    shapes: dict[tuple[int, ...], list[int]] = {}
    for i, d in enumerate(designs):
        shapes.setdefault((*d.a.shape, d.terms), []).append(i)
    for members in shapes.values():
        a = np.stack([designs[i].a for i in members])
        w = np.stack([designs[i].w for i in members])
        y = np.stack([designs[i].y for i in members])
        normal = a.mT @ (a * w[..., None])
        solved = np.linalg.cond(normal) <= MAX_CONDITION
        index = np.asarray(members)
        for i in index[~solved].tolist():
            fits[i] = StationReject(ILL_CONDITIONED)
        a, w, y = a[solved], w[solved], y[solved]
        cov = np.asarray(np.linalg.inv(normal[solved]), dtype=np.float64)
        params = (cov @ (a.mT @ (w * y)[..., None]))[..., 0]
        res = y - (a @ params[..., None])[..., 0]
        rms = np.sqrt((res**2).mean(axis=-1))
        chi2 = (w * res**2).sum(axis=-1)
        terms = designs[members[0]].terms
        rows, columns = a.shape[1:]
        for j, i in enumerate(index[solved].tolist()):
            fits[i] = Fit(
                uv=params[j, :2],
                cov=cov[j],
                bias=float(params[j, 2]) if terms else 0.0,
                trend=float(params[j, 3]) if terms == 2 else 0.0,
                rms=float(rms[j]),
                chi2=float(chi2[j]),
                dof=rows - columns,
            )
    return [fits[i] for i in range(len(designs))]
