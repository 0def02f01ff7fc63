"""Tick positions and labels: 'nice' linear steps (1, 2, 2.5, 5 × 10ⁿ) and decades on a
logarithmic axis; negative numbers with a true minus sign."""

from __future__ import annotations

import math

import numpy as np

STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def nice_step(span: float, most: int) -> float:
    """The smallest nice step that divides ``span`` into at most ``most`` intervals."""
    raw = span / max(most, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    return next((s * power for s in STEPS if s * power >= raw * (1 - 1e-9)), 10 * power)


def linear_ticks(lo: float, hi: float, most: int) -> tuple[list[float], float]:
    """Ticks within [lo, hi] (at most ``most`` + 1 of them) and their step."""
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        return [lo], 1.0
    step = nice_step(hi - lo, most)
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    return [k * step for k in range(first, last + 1)], step


def _decimals(step: float) -> int:
    """Decimals that show every multiple of ``step`` exactly (2.5 → 1, 0.25 → 2)."""
    for decimals in range(12):
        if abs(step * 10**decimals - round(step * 10**decimals)) < 1e-6 * step * 10**decimals:
            return decimals
    return 12


def label(value: float, step: float) -> str:
    """Tick label of ``value`` on a linear axis of ``step``."""
    text = f"{value:.{_decimals(step)}f}"
    if float(text) == 0:
        text = text.lstrip("-")
    return text.replace("-", "−")


def log_ticks(lo: float, hi: float) -> tuple[list[float], list[float]]:
    """Decades within [lo, hi] (and 2 and 5 × them when fewer than two decades show), and
    the minor ticks 2…9 × each decade."""
    first, last = math.floor(math.log10(lo) + 1e-9), math.ceil(math.log10(hi) - 1e-9)
    decades = [10.0**k for k in range(first, last + 1)]
    major = [d for d in decades if lo * (1 - 1e-9) <= d <= hi * (1 + 1e-9)]
    minor = [d * m for d in decades for m in range(2, 10) if lo <= d * m <= hi]
    if len(major) < 2:
        major = sorted({*major, *(d * m for d in decades for m in (2, 5) if lo <= d * m <= hi)})
        minor = [v for v in minor if v not in major]
    return major, minor


def log_label(value: float) -> str:
    """A log-axis label: plain for 0.001 … 10 000, else 10 with a superscript exponent."""
    exponent = math.floor(math.log10(value) + 1e-9)
    if -3 <= exponent <= 4:
        return f"{value:.{max(0, -exponent)}f}"
    mantissa = value / 10.0**exponent
    head = f"{mantissa:g}×" if abs(mantissa - 1) > 1e-9 else ""
    return f"{head}10{str(exponent).translate(SUPERSCRIPT)}"
