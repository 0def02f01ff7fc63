"""The exact shared-error covariance of a sidetrack and its parent (opt-in).

Assumptions: the reference is one survey run from its surface; the sidetrack is the
parent's trunk down to the kick-off — the reference's own stations, surveyed by the
reference's run — then the sidetrack's own run below. Each run's terms are one draw per run
(random terms: one per station), the two runs' terms independent of each other, global and
well-by-well terms included (the separation rule treats wells as independent). The kick-off
must be a reference station.

The relative position error of a reference point and an offset point is then, per error
draw, the difference of its effects on the two; the trunk above the kick-off moves both
alike and cancels. With s the summed effect of a systematic-type term (s_K = Σ_{k<K} e_k +
e*_K) on the reference (``ref``) and on the sidetrack's path (``side``: trunk, kick-off, own
stations):

    C = Σ_R,sys (s_ref − s_side)(…)ᵀ + Σ_R,rand (a − b)(…)ᵀ + C_R,rand,below + C_O

a, b the kick-off station's random effect on each point (the stations above it cancel),
C_R,rand,below the reference's random terms of its stations below the kick-off, C_O the
sidetrack run's own terms. Between stations the effects and covariances are interpolated
linearly in MD. Frame NEV, m, m².
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pipeline.anticollision.models import TermEffects
from pipeline.uncertainty.model import propagate_nev

__all__ = ["SharedErrors"]

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]


def _summed(fx: TermEffects, rows: NDArray[np.bool_]) -> FloatArray:
    """Systematic-type sums s (t, n, 3) of the terms ``rows``."""
    full, star = fx.full[rows], fx.star[rows]
    out: FloatArray = np.cumsum(full, axis=1) - full + star
    return out


def _own(fx: TermEffects, k: int) -> FloatArray:
    """Each term's effect (t, n, 3) of station k on every station: 0 above, e*_k at k, e_k
    below."""
    out = np.zeros_like(fx.full)
    out[:, k] = fx.star[:, k]
    out[:, k + 1 :] = fx.full[:, k : k + 1]
    return out


def _lerp(x: FloatArray, k: IndexArray, f: FloatArray, axis: int) -> FloatArray:
    """x at fractions f between indices k and k + 1 along ``axis`` (k + 1 clipped)."""
    top = x.shape[axis] - 1
    a = np.take(x, k, axis=axis)
    b = np.take(x, np.minimum(k + 1, top), axis=axis)
    shape = [1] * x.ndim
    shape[axis] = f.size
    g = f.reshape(shape)
    out: FloatArray = (1.0 - g) * a + g * b
    return out


class SharedErrors:
    """The relative covariance of reference points below a kick-off and sidetrack points,
    from the terms' effects on the reference (``ref``, its stations from the surface), on
    the sidetrack's path under the reference's model (``side_r``) and under its own
    (``side_o``), the kick-off at station index ``kick`` of both."""

    def __init__(self, ref: TermEffects, side_r: TermEffects, side_o: TermEffects, kick: int):
        sys_r = np.array([m != "random" for m in ref.modes])
        rand_r = ~sys_r
        trunk = (np.arange(side_r.full.shape[1]) <= kick)[None, :, None]
        below_ref = (np.arange(ref.full.shape[1]) > kick)[None, :, None]
        own_o = ~trunk
        self.kick = kick
        self.s_ref = _summed(ref, sys_r)
        trunk_r = TermEffects(
            side_r.names, side_r.modes, side_r.full * trunk, side_r.star * trunk, side_r.tie
        )
        self.s_side = _summed(trunk_r, sys_r)
        self.a = _own(ref, kick)[rand_r]
        self.b = _own(trunk_r, kick)[rand_r]
        modes_r = [m for m, r in zip(ref.modes, rand_r, strict=True) if r]
        self.c_ref: FloatArray = propagate_nev(
            ref.full[rand_r] * below_ref, ref.star[rand_r] * below_ref, modes_r
        ).sum(axis=0)
        self.c_own: FloatArray = propagate_nev(
            side_o.full * own_o, side_o.star * own_o, side_o.modes
        ).sum(axis=0)

    def __call__(
        self, k_ref: IndexArray, f_ref: FloatArray, k_side: IndexArray, f_side: FloatArray
    ) -> FloatArray:
        """Relative covariance (m, 3, 3) of reference points (station index from the
        surface, fraction) and sidetrack points (index on its path, fraction)."""
        s = _lerp(self.s_ref, k_ref, f_ref, 1) - _lerp(self.s_side, k_side, f_side, 1)
        d = _lerp(self.a, k_ref, f_ref, 1) - _lerp(self.b, k_side, f_side, 1)
        out: FloatArray = (
            np.einsum("tmi,tmj->mij", s, s)
            + np.einsum("tmi,tmj->mij", d, d)
            + _lerp(self.c_ref, k_ref, f_ref, 0)
            + _lerp(self.c_own, k_side, f_side, 0)
        )
        return out
