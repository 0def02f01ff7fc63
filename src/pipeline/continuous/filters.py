"""Savitzky–Golay filters, short convolutions and derivatives in time, in NumPy alone.

The same filters as SciPy's ``scipy.signal.savgol_coeffs`` / ``savgol_filter`` (mode
``interp``; more accurately) and ``oaconvolve(mode="same")`` for odd kernels, written here
so that a continuous run does not import ``scipy.signal`` (with it most of SciPy: ≈ 80 MiB
of the process's memory floor, issue #20); convolutions by NumPy's FFT. ``np.gradient`` of
several series on the same times, to the bit, its weights computed once
(:class:`TimeGradient`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray

__all__ = [
    "TimeGradient",
    "convolve_full",
    "convolve_same",
    "savgol_coeffs",
    "savgol_filter",
    "savgol_filters",
]


@functools.lru_cache(maxsize=64)
def savgol_coeffs(points: int, order: int, deriv: int = 0, delta: float = 1.0) -> FloatArray:
    """Convolution kernel (odd ``points``) of the ``deriv``-th derivative of the local
    least-squares polynomial of degree ``order`` at the window's centre, sample interval
    ``delta`` (read-only: one array per kernel, kept for the passes that reuse it). The
    positions are scaled to [−1, 1] (SciPy's are not): the powers of positions up to ±100
    made the least squares ill-conditioned, the taps off by up to 9e-13 relative (201
    points, order 3), so much that a fit of MD near 1,500 m moved by 3e-9 m; scaled, within
    5e-15 of the exact taps."""
    half = points // 2
    x = np.arange(-half, points - half, dtype=np.float64)[::-1] / max(half, 1)  # reversed
    design = x ** np.arange(order + 1)[:, None]
    target = np.zeros(order + 1)
    target[deriv] = math.factorial(deriv) / (delta * max(half, 1)) ** deriv
    coeffs = np.asarray(np.linalg.lstsq(design, target, rcond=None)[0], dtype=np.float64)
    coeffs.setflags(write=False)
    return coeffs


def convolve_same(values: FloatArray, kernel: FloatArray) -> FloatArray:
    """``values`` (1-D, or each row of a 2-D array) convolved with the odd-length ``kernel``,
    centred, zero beyond the ends: ``out[i] = Σ_j kernel[j]·values[i + h − j]`` (rows by
    FFT, as ``scipy.signal.oaconvolve(mode="same")``; a long series by FFTs of blocks,
    :func:`_blocked`, a short one or a short kernel directly). The FFT's rounding is ≈ 1e-16
    of the series' largest value: a filter of a series far from zero (an odometer's MD of
    kilometres) goes through its steps instead (:func:`savgol_filter`)."""
    n, m = values.shape[-1], kernel.size
    if values.ndim == 1:
        return _convolve_series(values, (kernel,))[0]
    out: FloatArray = convolve_full(values, kernel)[..., m // 2 : m // 2 + n]
    return out


def convolve_full(rows: FloatArray, kernel: FloatArray) -> FloatArray:
    """Each row's full convolution with ``kernel`` (``n + m − 1`` values:
    ``out[i] = Σ_j kernel[j]·rows[i − j]``), by real FFTs of the power of two ≥ n + m − 1
    (rounding ≈ 1e-16 of the rows' largest value)."""
    n, m = rows.shape[-1], kernel.size
    size = 1 << (n + m - 2).bit_length()
    full = np.fft.irfft(np.fft.rfft(rows, size) * _spectrum(kernel, size), size)
    out: FloatArray = full[..., : n + m - 1]
    return out


def _convolve_series(values: FloatArray, kernels: Sequence[FloatArray]) -> list[FloatArray]:
    """:func:`convolve_same` of a 1-D series with each of ``kernels`` (odd, all of one
    length): by FFTs of blocks (the series' spectrum taken once for them all) where the
    series is long and the kernels are too, else directly."""
    n, m = values.size, kernels[0].size
    if m < _FFT_TAPS or n < _BLOCKS * _block_size(m):
        return [np.convolve(values, k, mode="full")[m // 2 : m // 2 + n] for k in kernels]
    return _blocked(values, kernels)


_FFT_TAPS = 64
"""Kernels this long and longer are applied to a long series by FFT (direct below)."""
_BLOCKS = 4
"""Fewest blocks of a series convolved by FFT."""


def _block_size(taps: int) -> int:
    """FFT length of the blocks for a kernel of ``taps``: the power of two above 8× the
    kernel's span (the quickest here for 101 and 201 taps: 1024 and 2048)."""
    return 1 << (8 * (taps - 1)).bit_length()


def _blocked(values: FloatArray, kernels: Sequence[FloatArray]) -> list[FloatArray]:
    """:func:`convolve_same` of a long 1-D series with each of ``kernels`` (of one length
    ``m``) by overlap-add: the series cut into blocks of ``size − m + 1`` samples, each
    convolved by one FFT of ``size`` (all blocks at once; their spectrum shared by the
    kernels), each block's tail of ``m − 1`` added to the next block's start (rounding:
    ≈ 1e-16 of the values' largest magnitude)."""
    n, m = values.size, kernels[0].size
    size = _block_size(m)
    step = size - m + 1
    whole, rest = divmod(n, step)
    count = whole + (rest > 0)
    padded = np.zeros((count, size))  # each block zero-padded to the FFT's length
    padded[:whole, :step] = values[: whole * step].reshape(whole, step)
    padded[whole:, :rest] = values[whole * step :]
    spectrum = np.fft.rfft(padded)
    product = np.empty_like(spectrum)
    outs = []
    for kernel in kernels:
        blocks = np.fft.irfft(np.multiply(spectrum, _spectrum(kernel, size), out=product), size)
        full = np.empty((count + 1) * step)
        full[: count * step].reshape(count, step)[...] = blocks[:, :step]
        full[count * step :] = 0.0
        tails = full[step:].reshape(count, step)
        tails[:, : m - 1] += blocks[:, step:]
        outs.append(full[m // 2 : m // 2 + n])
    return outs


def _spectrum(kernel: FloatArray, size: int) -> NDArray[np.complex128]:
    """The real FFT of length ``size`` of ``kernel`` (computed once per kernel and size)."""
    return _kernel_spectrum(np.ascontiguousarray(kernel, np.float64).tobytes(), size)


@functools.lru_cache(maxsize=16)
def _kernel_spectrum(kernel: bytes, size: int) -> NDArray[np.complex128]:
    """The real FFT of length ``size`` of a kernel (its float64 bytes), kept for the chunks
    and passes that reuse it."""
    spectrum = np.fft.rfft(np.frombuffer(kernel, dtype=np.float64), size)
    spectrum.setflags(write=False)
    return spectrum


def savgol_filter(
    values: FloatArray,
    points: int,
    order: int,
    deriv: int = 0,
    delta: float = 1.0,
    ends: tuple[bool, bool] = (True, True),
) -> FloatArray:
    """The Savitzky–Golay fit (its ``deriv``-th derivative) at every sample: the kernel of
    :func:`savgol_coeffs` inside (applied to the steps of ``values``,
    :func:`_through_steps`), and within half a window of either end the polynomial fitted
    to the first or last ``points`` samples (SciPy's mode ``interp``); ``ends``: the (first,
    last) half windows fitted so (not: left invalid, for a caller that discards them). A
    non-finite value spreads over a whole FFT block (2,048 samples for 201 taps), not only
    the taps' span: the samples reach a filter finite (their contract)."""
    return savgol_filters(values, points, order, (deriv,), delta, ends)[0]


def savgol_filters(
    values: FloatArray,
    points: int,
    order: int,
    derivs: Sequence[int],
    delta: float = 1.0,
    ends: tuple[bool, bool] = (True, True),
) -> list[FloatArray]:
    """:func:`savgol_filter` of one series for each derivative of ``derivs``, each to the bit
    as alone: the steps, their spectrum and the end fits are taken once for them all."""
    if values.size < points:
        raise ValueError(f"{values.size} samples: the filter needs at least {points}")
    kernels = [savgol_coeffs(points, order, d, delta) for d in derivs]
    outs = _through_steps(values, kernels, derivs)
    half = points // 2
    scale = max(half, 1)
    position = (np.arange(points, dtype=np.float64) - half) / scale  # [−1, 1], as the taps
    fits = ((slice(0, points), slice(0, half)), (slice(-points, None), slice(points - half, None)))
    for (window, at), fitted in zip(fits, ends, strict=True):
        if not fitted:
            continue
        # about the window's middle value: a fit of kilometres of MD rounded relative to
        # their variation, not to kilometres
        centre = float(values[window][half])
        fitted_poly = np.asarray(np.polyfit(position, values[window] - centre, order), np.float64)
        for out, deriv in zip(outs, derivs, strict=True):
            poly = fitted_poly
            if deriv:
                poly = np.asarray(np.polyder(poly, deriv), dtype=np.float64)
            fit = np.polyval(poly, position[at]) / (delta * scale) ** deriv
            out[window][at] = fit + centre if deriv == 0 else fit
    return outs


def _through_steps(
    values: FloatArray, kernels: Sequence[FloatArray], derivs: Sequence[int]
) -> list[FloatArray]:
    """``convolve_same(values, kernel)`` for each Savitzky–Golay kernel of ``kernels`` (of
    the derivatives ``derivs``; one length) at the samples at least half a kernel from
    either end (the first and last half kernel: not valid), taken from the steps
    ``Δv[n] = v[n] − v[n−1]`` by parts: with the kernel less the unit impulse at its centre
    where the derivative is 0, its taps sum to zero (a fit reproduces a constant; its
    derivatives annihilate it), so ``Σ_j k[j]·v[i+h−j] = Σ_j K[j]·Δv[i+h−j]`` with ``K``
    their cumulative sums (the last, zero, taken as exactly so), plus ``v[i]`` for the fit
    itself. The convolution's rounding (≈ 1e-16 of the largest step by FFT) is then that of
    the steps, not of the values: an odometer's MD of kilometres moves ~1 cm a sample, so
    this is more accurate than the sums of products of the values taken directly (each
    rounded relative to kilometres) and as fast as an FFT."""
    cumulative = []
    for kernel, deriv in zip(kernels, derivs, strict=True):
        taps = np.array(kernel, dtype=np.float64)
        if deriv == 0:
            taps[taps.size // 2] -= 1.0
        summed = np.cumsum(taps)
        summed[-1] = 0.0
        cumulative.append(summed)
    steps = np.empty_like(values, dtype=np.float64)
    steps[0] = 0.0
    np.subtract(values[1:], values[:-1], out=steps[1:])
    outs = _convolve_series(steps, cumulative)
    for out, deriv in zip(outs, derivs, strict=True):
        if deriv == 0:
            out += values
    return outs


class TimeGradient:
    """``np.gradient(f, t)`` (first-order edges) of series ``f`` sampled at the times ``t``
    (s; at least two): NumPy's weights of the non-uniform central differences (or its step,
    where the steps are all equal) computed once for all the series on the same times, and
    applied as NumPy applies them, so the derivatives (per s) are np.gradient's to the bit."""

    def __init__(self, t: FloatArray) -> None:
        step = np.diff(np.asarray(t, dtype=np.float64))
        if step.size < 1:
            raise ValueError("a gradient needs at least two samples")
        self._edges = step[0], step[-1]
        self._uniform = bool((step == step[0]).all())
        if self._uniform:
            self._twice = 2.0 * step[0]
        else:
            dx1, dx2 = step[:-1], step[1:]
            self._weights = (
                -dx2 / (dx1 * (dx1 + dx2)),
                (dx2 - dx1) / (dx1 * dx2),
                dx1 / (dx2 * (dx1 + dx2)),
            )

    def __call__(self, f: FloatArray) -> FloatArray:
        """d``f``/dt at every sample (``f`` float64, one value per time)."""
        out: FloatArray = np.empty_like(f, dtype=np.float64)
        if self._uniform:
            out[1:-1] = (f[2:] - f[:-2]) / self._twice
        else:
            a, b, c = self._weights
            out[1:-1] = a * f[:-2] + b * f[1:-1] + c * f[2:]
        out[0] = (f[1] - f[0]) / self._edges[0]
        out[-1] = (f[-1] - f[-2]) / self._edges[1]
        return out
