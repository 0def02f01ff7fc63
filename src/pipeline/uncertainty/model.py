"""ISCWSA (SPE 67616) position-uncertainty propagation, vectorised over stations and terms.

Every error source ε contributes, at each station k, a weight vector
w_k = ∂(MD, I, α)/∂ε scaled by its 1σ magnitude: ``e_dia[k] = σ·w_k``. Here α = A·sin I is
the *horizontal* azimuth tilt (rad), used instead of A so that terms whose azimuth weight
carries 1/sin I (XYM3E, XYM4E) stay finite at vertical stations; ∂r/∂α = (∂r/∂A)/sin I is
finite for every leg.

A station's error moves the two minimum-curvature legs it bounds:

    e_k  = (∂Δ_k/∂p_k + ∂Δ_{k+1}/∂p_k)·e_dia[k]     effect on every station below k
    e*_k = ∂Δ_k/∂p_k·e_dia[k]                        effect on station k itself

and the covariance of station K sums over k < K by propagation mode:

    random       C_K = Σ_{k<K} e_k e_kᵀ + e*_K e*_Kᵀ
    systematic   C_K = s_K s_Kᵀ,  s_K = Σ_{k<K} e_k + e*_K
    well_by_well as systematic within one survey (correlated between the legs of a well)
    global       as systematic within one survey (correlated between wells too)

Frame: NEV = north, east, vertical (down positive). Lengths m, angles rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Basis",
    "Propagation",
    "StationJacobians",
    "leg_effects",
    "propagate",
    "propagate_nev",
    "station_jacobians",
]

FloatArray = NDArray[np.float64]
Propagation = Literal["random", "systematic", "well_by_well", "global"]
Basis = Literal["min_curve", "balanced_tangent"]

#: Below this dogleg (rad) RF'(β)/sin β is its series 1/6 + 11β²/180 (error < 1e-13).
_G_SERIES_BELOW = 1e-3


@dataclass(frozen=True)
class StationJacobians:
    """Position Jacobians of each station's measurements (n, 3 NEV, 3 (MD, I, α))."""

    #: ∂Δ_k/∂p_k: the leg into station k (zero at station 0 unless a surface root).
    into: FloatArray
    #: ∂Δ_{k+1}/∂p_k: the leg out of station k (zero at the last station).
    out: FloatArray


def _tangent_parts(inc: FloatArray, azi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tool axis t, ∂t/∂I and ∂t/∂α (= ∂t/∂A / sin I), each (n, 3)."""
    si, ci, sa, ca = np.sin(inc), np.cos(inc), np.sin(azi), np.cos(azi)
    t = np.stack((si * ca, si * sa, ci), axis=-1)
    dt_di = np.stack((ci * ca, ci * sa, -si), axis=-1)
    dt_da = np.stack((-sa, ca, np.zeros_like(sa)), axis=-1)
    return t, dt_di, dt_da


def _rf_and_g(t1: FloatArray, t2: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Dogleg β, RF(β) = tan(β/2)/(β/2) and g(β) = RF'(β)/sin β per leg."""
    diff = np.linalg.norm(t2 - t1, axis=-1)
    beta = 2.0 * np.arcsin(np.clip(0.5 * diff, 0.0, 1.0))
    b2 = beta * beta
    rf = 1.0 + b2 * (1.0 / 12.0 + b2 * (1.0 / 120.0 + b2 * (17.0 / 20160.0)))
    g = 1.0 / 6.0 + b2 * (11.0 / 180.0)
    big = beta >= _G_SERIES_BELOW
    bb = beta[big]
    half = 0.5 * bb
    tan_h = np.tan(half)
    rf[big] = tan_h / half
    drf = 1.0 / (np.cos(half) ** 2 * bb) - 2.0 * tan_h / (bb * bb)
    g[big] = drf / np.sin(bb)
    return beta, rf, g


def station_jacobians(
    md: ArrayLike,
    inc: ArrayLike,
    azi: ArrayLike,
    *,
    basis: Basis = "balanced_tangent",
    surface_tie: bool = True,
) -> StationJacobians:
    """Jacobians of the legs around each station with respect to its (MD, I, α).

    ``basis="balanced_tangent"`` (default) is the ISCWSA standard's approximation (RF = 1, as
    in SPE 67616 and the ISCWSA example workbook); ``"min_curve"`` differentiates the
    minimum-curvature step exactly (RF included), an opt-in.
    ``surface_tie`` applies the ISCWSA Rev 5 surface tie-on allowance: station 0's own depth
    error moves it along its tangent, and the first leg's angle weights are doubled (slot
    attitude) in place of station 0's own measurement errors. Off by default: the first
    station is a perfectly known tie-in.
    """
    md_a = np.asarray(md, dtype=np.float64)
    inc_a = np.asarray(inc, dtype=np.float64)
    azi_a = np.asarray(azi, dtype=np.float64)
    n = md_a.size
    t, dt_di, dt_da = _tangent_parts(inc_a, azi_a)
    into = np.zeros((n, 3, 3))
    out = np.zeros((n, 3, 3))
    if n < 2:
        if surface_tie and n == 1:
            into[0, :, 0] = t[0]
        return StationJacobians(into=into, out=out)
    t1, t2 = t[:-1], t[1:]
    half = 0.5 * np.diff(md_a)[:, None]
    tsum = t1 + t2
    if basis == "min_curve":
        _, rf, g = _rf_and_g(t1, t2)
        rf_c = rf[:, None]
        g_c = g[:, None]

        def leg(dt: FloatArray, other: FloatArray) -> FloatArray:
            dot = np.einsum("ij,ij->i", other, dt)[:, None]
            out_: FloatArray = half * (dt * rf_c - tsum * g_c * dot)
            return out_

        into[1:, :, 0] = 0.5 * tsum * rf_c
        out[:-1, :, 0] = -0.5 * tsum * rf_c
        into[1:, :, 1] = leg(dt_di[1:], t1)
        into[1:, :, 2] = leg(dt_da[1:], t1)
        out[:-1, :, 1] = leg(dt_di[:-1], t2)
        out[:-1, :, 2] = leg(dt_da[:-1], t2)
    elif basis == "balanced_tangent":
        into[1:, :, 0] = 0.5 * tsum
        out[:-1, :, 0] = -0.5 * tsum
        into[1:, :, 1] = half * dt_di[1:]
        into[1:, :, 2] = half * dt_da[1:]
        out[:-1, :, 1] = half * dt_di[:-1]
        out[:-1, :, 2] = half * dt_da[:-1]
    else:
        raise ValueError(f"unknown basis {basis!r}; expected 'min_curve' or 'balanced_tangent'")
    if surface_tie:
        into[0, :, 0] = t[0]
        into[1, :, 1:] *= 2.0
        out[0, :, 1:] = 0.0  # station 0's own angle errors are the doubled allowance above
    return StationJacobians(into=into, out=out)


def leg_effects(e_dia: ArrayLike, jac: StationJacobians) -> tuple[FloatArray, FloatArray]:
    """Each term's NEV effect (full e_k, own e*_k), each (m, n, 3), of the 1σ station errors
    ``e_dia`` (m, n, 3) of (MD, I, α) (m, rad, rad)."""
    e = np.asarray(e_dia, dtype=np.float64)
    if e.ndim != 3 or e.shape[2] != 3:
        raise ValueError(f"e_dia must be (m, n, 3); got {e.shape}")
    if e.shape[1] != jac.into.shape[0]:
        raise ValueError("e_dia and the Jacobians disagree on the number of stations")
    star = _apply(jac.into, e)
    return star + _apply(jac.out, e), star


def propagate(
    e_dia: ArrayLike,
    modes: Sequence[Propagation],
    jac: StationJacobians,
) -> FloatArray:
    """NEV covariance (m, n, 3, 3) of each of m error terms at each of n stations.

    ``e_dia`` is (m, n, 3): each term's 1σ error of (MD, I, α) at each station (m, rad, rad).
    """
    e = np.asarray(e_dia, dtype=np.float64)
    if e.ndim != 3 or len(modes) != e.shape[0]:
        raise ValueError(f"e_dia must be (m, n, 3) with m = len(modes); got {e.shape}")
    full, star = leg_effects(e, jac)
    return propagate_nev(full, star, modes)


def propagate_nev(full: FloatArray, star: FloatArray, modes: Sequence[Propagation]) -> FloatArray:
    """NEV covariance (m, n, 3, 3) from each term's NEV effects (m, n, 3) on the stations
    below (``full``, e_k) and on its own station (``star``, e*_k), by propagation mode."""
    if full.shape != star.shape or full.ndim != 3 or len(modes) != full.shape[0]:
        raise ValueError(f"full and star must be (m, n, 3) with m = len(modes); got {full.shape}")
    unknown = set(modes) - set(get_args(Propagation))
    if unknown:
        raise ValueError(f"unknown propagation modes {sorted(unknown)}")
    cov = np.zeros((*full.shape[:2], 3, 3))
    if full.shape[1] == 0:
        return cov
    for k, mode in enumerate(modes):  # per term: 2× faster than stacked, cache-sized arrays
        f, s = full[k], star[k]
        if mode == "random":  # C_K = Σ_{k<K} e_k e_kᵀ + e*_K e*_Kᵀ
            acc = cov[k]
            acc[0] = 0.0
            np.cumsum(f[:-1, :, None] * f[:-1, None, :], axis=0, out=acc[1:])
            acc += s[:, :, None] * s[:, None, :]
        else:  # s_K = Σ_{k<K} e_k + e*_K, C_K = s_K s_Kᵀ
            tot = np.empty_like(f)
            tot[0] = 0.0
            np.cumsum(f[:-1], axis=0, out=tot[1:])
            tot += s
            np.multiply(tot[:, :, None], tot[:, None, :], out=cov[k])
    return cov


def _apply(jac: FloatArray, e: FloatArray) -> FloatArray:
    """(n, 3, 3) Jacobians times (m, n, 3) errors → (m, n, 3), as three fused column sums."""
    out: FloatArray = jac[None, :, :, 0] * e[:, :, None, 0]
    out += jac[None, :, :, 1] * e[:, :, None, 1]
    out += jac[None, :, :, 2] * e[:, :, None, 2]
    return out
