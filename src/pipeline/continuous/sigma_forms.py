"""The azimuth budget's forms over its cells (:func:`pipeline.continuous.sigma.azimuth_budget`):
the stations' rows (a rate error's integral up to each station less the closure's share),
their products with cell vectors and their quadratic forms with a bias kernel — the
Gauss–Markov kernel by its semi-separable form, others evaluated a block of cells at a time.

Units: cells' times s, angles rad; the forms are in the units of what they are given.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray

__all__ = ["Evaluated", "Kernel", "StationRows", "markov_kernel"]


@dataclass(frozen=True)
class StationRows:
    """The stations' rows over the budget's cells, ``a[k, j] = u_k = Φ_k − c_k`` before the
    station (its ``n_k`` cells) and ``v_k = −c_k`` after it: a rate error's integral up to
    station k less the closure's share ``c_k = w_k·Φ_T`` of the whole. Its products with
    cell vectors and its quadratic forms by sums over the cells before and after each
    station: O(cells + stations²) (the quadratic forms O(cells² + cells·stations)), the
    (stations, cells) matrix never made. The sums after a station are taken as such (from
    the end), not as the whole less those before: near the closing stop (Φ_k ≈ c_k, few
    cells after) a difference of the whole's sums would cancel to a few ε of them."""

    phi: FloatArray
    """Φ at each station"""
    closure: FloatArray
    """w·Φ_T at each station (0: no closure)"""
    before: NDArray[np.intp]
    """cells before each station"""
    cells: int

    @property
    def _u(self) -> FloatArray:
        return self.phi - self.closure

    def linear(self, g: FloatArray) -> FloatArray:
        """``a @ g``: ``u_k·G(before n_k) + v_k·G(from n_k)``, the running sums of ``g``
        (per cell) from the start and from the end."""
        head, tail = running(g), running(g[::-1])[::-1]
        out: FloatArray = self._u * head[self.before] - self.closure * tail[self.before]
        return out

    def diagonal(self, d: FloatArray) -> FloatArray:
        """``a·diag(d)·aᵀ`` (``d ≥ 0`` per cell): the block sums over the cells before both
        stations, D(min(n_k, n_l)), after both, T(max(n_k, n_l)), and between them (before
        k, after l), D(n_k) − D(n_l) where n_k > n_l — D and T the running sums of d from
        the start and from the end."""
        head = running(d)[self.before]
        tail = running(d[::-1])[::-1][self.before]
        between = np.subtract.outer(head, head)
        np.maximum(between, 0.0, out=between)
        # D not decreasing, T not increasing: D(min(n_k, n_l)) and T(max(n_k, n_l)) are
        # the lesser of each pair
        return self._form(np.minimum.outer(head, head), between, np.minimum.outer(tail, tail))

    def quadratic(self, g: FloatArray, mid: FloatArray, kernel: Kernel) -> FloatArray:
        """``a·diag(g)·K·diag(g)·aᵀ`` with ``K[i, j] = K(mid[i], mid[j])`` (``g`` and ``mid``
        per cell; K symmetric): the sums of ``g_i K_ij g_j`` over the cells before each pair
        of stations (``kernel.before_sums``), and after them — the same sums over the cells
        in reverse order."""
        at = np.append(self.before, self.cells)
        before = kernel.before_sums(g, mid, at)
        backward = np.ascontiguousarray(g[::-1]), np.ascontiguousarray(mid[::-1])
        after = kernel.before_sums(*backward, self.cells - at[:-1])
        between = before[:-1, -1:] - before[:-1, :-1]  # before k, after l
        return self._form(before[:-1, :-1], between, after)

    def _form(self, before: FloatArray, between: FloatArray, after: FloatArray) -> FloatArray:
        """The form from its block sums over the cells before stations k and l
        (``before[k, l]``), before k and after l (``between[k, l]``; after k and before l is
        its transpose, K symmetric), and after both (``after[k, l]``):
        ``uuᵀ∘before + uvᵀ∘between + (uvᵀ∘between)ᵀ + vvᵀ∘after``, v = −c."""
        u = self._u
        out: FloatArray = np.multiply.outer(u, u)
        out *= before
        cross = np.multiply.outer(u, -self.closure)
        cross *= between
        out += cross
        out += cross.T
        cross = np.multiply.outer(self.closure, self.closure, out=cross)
        cross *= after
        out += cross
        return out


def before_sums(
    g: FloatArray,
    mid: FloatArray,
    kernel: Callable[[FloatArray, FloatArray], FloatArray],
    at: NDArray[np.intp],
) -> FloatArray:
    """``[k, l]``: the sum of ``g_i K_ij g_j`` over the cells ``i < at_k``, ``j < at_l``
    (``at`` not decreasing), K made a block of rows at a time (a day-long run has millions
    of cells) and summed along its rows, then down its columns."""
    cells = g.size
    table = np.zeros((at.size, at.size))
    along = np.zeros((KERNEL_ROWS, cells + 1))  # [i, j]: Σ over j' < j
    down = np.empty((KERNEL_ROWS + 1, at.size))  # [r, l]: Σ over i < lo + r, j < at_l
    down[0] = 0.0
    for lo in range(0, cells, KERNEL_ROWS):
        hi = min(lo + KERNEL_ROWS, cells)
        block = kernel(mid[lo:hi, None], mid[None, :])
        block *= g[lo:hi, None]
        block *= g[None, :]
        np.cumsum(block, axis=1, out=along[: hi - lo, 1:])
        np.cumsum(along[: hi - lo, at], axis=0, out=down[1 : hi - lo + 1])
        down[1 : hi - lo + 1] += down[0]
        here = np.flatnonzero((at >= lo) & (at <= hi))
        table[here] = down[at[here] - lo]
        down[0] = down[hi - lo]
    return table


KERNEL_ROWS = 256


class Kernel(Protocol):
    """A covariance kernel K(x, y) of cells at their mid times (s), by its sums
    ``[k, l] = Σ g_i K_ij g_j`` over the cells ``i < at_k``, ``j < at_l`` (``mid``
    monotone, either way)."""

    def before_sums(self, g: FloatArray, mid: FloatArray, at: NDArray[np.intp]) -> FloatArray: ...


@dataclass(frozen=True)
class Evaluated:
    """Any kernel, evaluated cell by cell (:func:`before_sums`; O(cells²))."""

    function: Callable[[FloatArray, FloatArray], FloatArray]

    def before_sums(self, g: FloatArray, mid: FloatArray, at: NDArray[np.intp]) -> FloatArray:
        return before_sums(g, mid, self.function, at)


@dataclass(frozen=True)
class Exponential:
    """``exp(−|x − y|/τ)`` (τ s, a first-order Gauss–Markov process), by its semi-separable
    form (O(cells + cuts²), no cell-by-cell matrix): for ``i < p ≤ j``,
    ``e^(−(s_j − s_i)/τ) = e^(−(s_p−1 − s_i)/τ)·e^(−(s_j − s_p−1)/τ)``, so

        [k, l] = D(p) + F(p)·Σ_{p ≤ j < q} g_j e^(−(s_j − s_p−1)/τ)    (p = at_k ≤ q = at_l)

    with D(p) the sums over ``i, j < p`` and F(p) = Σ_{i<p} g_i e^(−(s_p−1 − s_i)/τ), the
    last sum over the cuts' blocks, each relative to its first cell. Every exponent is of a
    distance (≥ 0, or bounded within a segment: :func:`decayed`) and, where ``g ≥ 0``,
    every sum of terms ≥ 0: within a few ε of the explicit sums (test_sigma)."""

    tau: float

    def before_sums(self, g: FloatArray, mid: FloatArray, at: NDArray[np.intp]) -> FloatArray:
        cells, tau = g.size, self.tau
        s = mid if mid[0] <= mid[-1] else -mid  # increasing, the same distances
        below = decayed(g, s, tau)  # L_j = Σ_{i<j} g_i e^(−(s_j − s_i)/τ)
        diagonal = running(g * (g + 2.0 * below))  # D(p) = Σ_{j<p} g_j (g_j + 2 L_j)
        order = np.argsort(at, kind="stable")
        cut = at[order]
        back = np.maximum(cut - 1, 0)
        reach = np.where(cut > 0, below[back] + g[back], 0.0)  # F(p) = L_(p−1) + g_(p−1)
        # each cell's block: from the last cut at or before it (cells before the first: none)
        owner = np.searchsorted(cut, np.arange(cells), side="right") - 1
        first = np.minimum(cut[np.maximum(owner, 0)], cells - 1)
        lift = np.minimum(s[first] - s, 0.0)  # (cells before the first cut: 0, not kept)
        terms = g * np.exp(np.divide(lift, tau, out=lift), out=lift)
        kept = owner >= 0
        block = np.bincount(owner[kept], weights=terms[kept], minlength=cut.size)
        # [k, m]: block m's sum decayed to the cell before cut k (m ≥ k; else 0)
        ahead = np.subtract.outer(s[back], s[np.minimum(cut, cells - 1)])
        np.minimum(ahead, 0.0, out=ahead)
        decay = np.exp(np.divide(ahead, tau, out=ahead), out=ahead)
        decay *= block
        decay = np.triu(decay)
        upper = np.zeros((cut.size, cut.size))
        np.cumsum(decay[:, :-1], axis=1, out=upper[:, 1:])  # Σ over the blocks k … l − 1
        upper *= reach[:, None]
        upper += diagonal[cut][:, None]
        upper = np.triu(upper)
        out = np.empty_like(upper)
        out[np.ix_(order, order)] = upper + np.triu(upper, 1).T
        return out


SPAN = 32.0
"""Correlation times a segment of :func:`decayed` spans (its factors within e^±32)."""


def decayed(g: FloatArray, s: FloatArray, tau: float) -> FloatArray:
    """``L_j = Σ_{i<j} g_i e^(−(s_j − s_i)/τ)`` (``s`` increasing): per segment of under
    :data:`SPAN`·τ from its first cell r, ``e^(−(s_j − r)/τ)·(L_r + Σ_{r ≤ i < j} g_i
    e^((s_i − r)/τ))``, summed in sequence."""
    cells = g.size
    cuts = (np.flatnonzero(np.diff(np.floor((s - s[0]) / (SPAN * tau)))) + 1).tolist()
    out = np.empty(cells)
    carry = 0.0  # L at the segment's first cell
    for lo, hi in zip([0, *cuts], [*cuts, cells], strict=True):
        lift = (s[lo:hi] - s[lo]) / tau
        sums = np.empty(hi - lo + 1)
        sums[0] = carry
        np.multiply(g[lo:hi], np.exp(lift), out=sums[1:])
        np.cumsum(sums, out=sums)
        out[lo:hi] = sums[:-1] * np.exp(-lift)
        if hi < cells:
            carry = float(sums[-1] * np.exp(-(s[hi] - s[lo]) / tau))
    return out


def markov_kernel(tau: float) -> Kernel:
    """The first-order Gauss–Markov bias's kernel ``exp(−|x − y|/τ)`` (τ s)."""
    return Exponential(tau)


def running(values: FloatArray) -> FloatArray:
    """0 and the running sums of ``values``."""
    out = np.zeros(values.size + 1)
    np.cumsum(values, out=out[1:])
    return out
