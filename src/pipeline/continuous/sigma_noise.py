"""The azimuth error that the inclination's sample noise makes (:mod:`pipeline.continuous.sigma`),
accumulated over the run a chunk of samples at a time.

A station row p (over samples) integrates the rate error and applies the closure; the rate
error is ``∂Ȧ/∂I·δI + ∂Ȧ/∂İ·D₁δI`` and ``δI = n_acc/g − sin I·D₂ n_odo/g``, so the row seen by
the white noises is ``q = p·∂Ȧ/∂I + D₁ᵀ(p·∂Ȧ/∂İ)`` (accelerometer) and ``D₂ᵀ(q·sin I)``
(odometer). The row is ``p = g·Δs/Φ`` with g one constant before the station's sample
(``Φ_k − w Φ_T``) and another from it on (``−w Φ_T``): away from the station (farther than
the two filters' half-widths) q and the odometer row are those constants times the
station-free rows ``Q`` and ``D₂ᵀ(Q·sin I)``, whose squares are summed by prefix sums; near it
they are evaluated exactly, as a quadratic form in the two constants (Φ_T is known only at the
run's end). Units: times s, angles rad.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

from pipeline.continuous.filters import convolve_full, convolve_same, savgol_coeffs
from pipeline.continuous.store import carried_cumsum
from pipeline.earth.frames import FloatArray
from pipeline.earth.gravity import STANDARD_GRAVITY

__all__ = ["InclinationNoise", "NoiseSums", "derivative_kernel"]


@dataclass(frozen=True)
class InclinationNoise:
    """Per-sample noise of the inclination the integration uses."""

    dt: float
    """sample interval, s"""
    accel: float
    """accelerometer white noise per sample, m/s²"""
    odometer: float
    """odometer white noise per sample, m"""
    odometer_points: int | None
    """samples of the cubic fit differentiating the odometer (None: finite differences)"""
    inc_rate_points: int | None
    """samples of the quadratic fit giving İ (None: finite differences)"""
    gravity: float = STANDARD_GRAVITY
    """m/s²"""


def derivative_kernel(points: int | None, order: int, deriv: int, dt: float) -> FloatArray:
    """Convolution kernel of the Savitzky–Golay derivative (or, for None, of np.gradient)."""
    if points is None:
        first = np.array([1.0, 0.0, -1.0]) / (2.0 * dt)
        kernel: FloatArray = first if deriv == 1 else np.convolve(first, first)
        return kernel
    return savgol_coeffs(points, order, deriv, dt)


class NoiseSums:
    """Sums over the run that give each station's inclination-noise variance, fed chunk by
    chunk in integration order (:meth:`add`), finished by :meth:`variance`.

    ``index``: each station's sample (the first at or after its time); ``cells``: the most
    neighbourhood cells evaluated at once."""

    def __init__(
        self,
        noise: InclinationNoise,
        size: int,
        index: NDArray[np.integer[Any]],
        cells: int = 500_000,
    ) -> None:
        self.noise, self.size = noise, size
        self.d1 = derivative_kernel(noise.inc_rate_points, 2, 1, noise.dt)[::-1]  # transposed
        self.d2 = derivative_kernel(noise.odometer_points, 3, 2, noise.dt)[::-1]
        spread = self.d1.size // 2 + self.d2.size // 2
        self.near = spread + 1  # half-width where the rows differ from the station-free ones
        self.halo = self.near + spread  # half-width of the samples a neighbourhood depends on
        self.offsets = np.arange(-self.halo, self.halo + 1)
        self.index = np.asarray(index, dtype=np.int64)
        self.first = np.clip(self.index - self.near, 0, size)  # first sample of the neighbourhood
        self.last = np.clip(self.index + self.near + 1, 0, size)  # one past its last
        self.keys = np.unique(np.concatenate([self.first, self.last, [0, size]]))
        self.prefix = np.zeros((2, self.keys.size))  # Σ Q², Σ odo² before each key
        self.carry = np.zeros(2)
        self.quadratic = np.zeros((self.index.size, 6))  # near: q and odo, (bb, ba, aa)
        self.block = max(1, cells // self.offsets.size)

    def add(
        self,
        lo: int,
        hi: int,
        start: int,
        step: FloatArray,
        d_inc: FloatArray,
        d_inc_rate: FloatArray,
        sin_i: FloatArray,
    ) -> None:
        """The samples ``[lo, hi)`` (integration order), from per-sample arrays given over
        ``[start, start + len)`` ⊇ ``[lo − halo, hi + halo)`` ∩ the run: the step divided by Φ
        (s), ∂Ȧ/∂I, ∂Ȧ/∂İ and sin I."""
        q_free = step * d_inc + convolve_same(step * d_inc_rate, self.d1)
        odo_free = convolve_same(q_free * sin_i, self.d2)
        own = slice(lo - start, hi - start)
        keys = np.flatnonzero((self.keys > lo) & (self.keys <= hi))
        ends = self.keys[keys] - lo  # the sums to each key: over [0, end) of the chunk
        cuts = np.concatenate([[0], ends[ends < hi - lo]])
        for row, free in enumerate((q_free, odo_free)):
            # the squares summed between the keys, then those sums run (not every sample's)
            running = carried_cumsum(np.add.reduceat(free[own] ** 2, cuts), float(self.carry[row]))
            self.prefix[row, keys] = running[: ends.size]
            self.carry[row] = running[-1]
        stations = np.flatnonzero((self.index >= lo) & (self.index < hi))
        length = step.size
        for b in range(0, stations.size, self.block):
            which = stations[b : b + self.block]
            columns = self.index[which, None] + self.offsets[None, :]  # sample index
            arrays = (step, d_inc, d_inc_rate, sin_i, q_free, odo_free)
            first = columns[:, 0] - start
            if first.min() >= 0 and first.max() + self.offsets.size <= length:  # rows inside
                near = [sliding_window_view(x, self.offsets.size)[first] for x in arrays]
            else:  # zeros beyond the arrays, which end at the run's ends or ≥ halo beyond [lo, hi)
                given = (columns >= start) & (columns < start + length)
                at = np.clip(columns - start, 0, length - 1)
                near = [np.where(given, x[at], 0.0) for x in arrays]
            step_n, d_inc_n, d_rate_n, sin_n, q_n, odo_n = near
            qb, ob = self._station_rows(step_n, d_inc_n, d_rate_n, sin_n)
            window = slice(self.halo - self.near, self.halo + self.near + 1)  # |offset| ≤ near
            qa, oa = q_n[:, window] - qb, odo_n[:, window] - ob
            within = (columns[:, window] >= 0) & (columns[:, window] < self.size)
            if not within.all():  # a neighbourhood past the run's ends
                qb, ob, qa, oa = (np.where(within, x, 0.0) for x in (qb, ob, qa, oa))
            self.quadratic[which] = np.stack(
                [
                    np.sum(qb * qb, axis=1),
                    np.sum(qb * qa, axis=1),
                    np.sum(qa * qa, axis=1),
                    np.sum(ob * ob, axis=1),
                    np.sum(ob * oa, axis=1),
                    np.sum(oa * oa, axis=1),
                ],
                axis=1,
            )

    def _station_rows(
        self, step: FloatArray, d_inc: FloatArray, d_inc_rate: FloatArray, sin_i: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The rows q and odo (accelerometer, odometer) of the samples before each station's
        (p = step there, 0 from it on) at offsets −near … near from it, from the per-sample
        values at offsets −halo … halo (rows: stations). The rows from the station on are
        the station-free rows less these (the rows are linear in p; inside the neighbourhood
        the free rows see the same p: the filters reach < halo). Each filter is applied by
        full convolution to the part of its input that is not zero and reaches the offsets
        wanted (p before the station; q from −near − h₂): an FFT of half the neighbourhood's
        length."""
        h1, h2, halo, near = self.d1.size // 2, self.d2.size // 2, self.halo, self.near
        p = step[:, :halo]  # offsets −halo … −1
        q = convolve_full(p * d_inc_rate[:, :halo], self.d1)[:, h1:]  # −halo … h1 − 1
        q[:, :halo] += p * d_inc[:, :halo]
        # odo from q at −near − h₂ … h1 − 1 (q is 0 past h1 − 1): at −near … near − 2
        odo = convolve_full(q[:, h1:] * sin_i[:, h1 : halo + h1], self.d2)[:, 2 * h2 :]
        width = 2 * near + 1
        qb, ob = np.zeros((step.shape[0], width)), np.zeros((step.shape[0], width))
        qb[:, : near + h1] = q[:, halo - near :]
        ob[:, : odo.shape[1]] = odo
        return qb, ob

    def variance(self, before: FloatArray, after: FloatArray) -> FloatArray:
        """Variance (rad²) at each station, with ``before``/``after`` the row's constants
        before the station's sample and from it on."""
        at = {int(k): i for i, k in enumerate(self.keys)}
        first = np.array([at[int(k)] for k in self.first], dtype=np.int64)
        last = np.array([at[int(k)] for k in self.last], dtype=np.int64)
        end = at[self.size]
        far = [
            before**2 * self.prefix[row, first]
            + after**2 * (self.prefix[row, end] - self.prefix[row, last])
            for row in (0, 1)
        ]
        qd = self.quadratic
        near_q = before**2 * qd[:, 0] + 2 * before * after * qd[:, 1] + after**2 * qd[:, 2]
        near_o = before**2 * qd[:, 3] + 2 * before * after * qd[:, 4] + after**2 * qd[:, 5]
        out: FloatArray = (self.noise.accel / self.noise.gravity) ** 2 * (far[0] + near_q) + (
            self.noise.odometer / self.noise.gravity
        ) ** 2 * (far[1] + near_o)
        return out
