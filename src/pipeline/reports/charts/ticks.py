"""Tick positions and labels: 'nice' linear steps (1, 2, 2.5, 5 × 10ⁿ) and decades on a
logarithmic axis; negative numbers with a true minus sign. Linear labels of very large or
very small numbers are short mantissas with a shared power of ten (and an offset where the
ticks differ only in far decimals), shown once at the axis end (:func:`linear_labels`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

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
    """Tick label of ``value`` on a linear axis of ``step``, in full."""
    text = f"{value:.{_decimals(step)}f}"
    if float(text) == 0:
        text = text.lstrip("-")
    return text.replace("-", "−")


PLAIN = (1e-3, 1e5)
"""Tick values whose largest magnitude lies in [1e-3, 1e5) are labelled in full, as a log
axis labels its decades (:func:`log_label`): at most five digits before the point (any
depth in m or ft) or two zeros after it (0.0012). Beyond that a label needs six or more
digits that only count the magnitude (1000000, 0.000002), which crowd a 7.5 pt axis and
are easily misread; the ticks are then labelled 1.0, 2.0 … with ×10ⁿ once."""
SHARED = 1e4
"""Ticks whose largest magnitude is at least this many times their span share four or
more leading digits (MD 10000.001 … 10000.004 m): they are labelled as the difference
from a round offset, shown once (+10000). A zoom of an ordinary axis (2500.0 … 2500.5 m)
stays in full."""


def power(exponent: int) -> str:
    """10 with ``exponent`` as superscript digits (10⁻⁶)."""
    return f"10{str(exponent).translate(SUPERSCRIPT)}"


def _offset_text(offset: float, unit: float) -> str:
    """An offset (a multiple of ``unit``) with its sign, its digits in full: it is printed
    once, where its exact value matters more than its length; beyond [1e-3, 1e9) as a
    mantissa ×10ⁿ."""
    sign = "−" if offset < 0 else "+"
    magnitude = abs(offset)
    if 1e-3 <= magnitude < 1e9:
        digits = f"{magnitude:.{_decimals(unit)}f}"
        return sign + (digits.rstrip("0").rstrip(".") if "." in digits else digits)
    exponent = math.floor(math.log10(magnitude))
    mantissa = f"{magnitude / 10.0**exponent:.{_decimals(unit / 10.0**exponent)}f}"
    mantissa = mantissa.rstrip("0").rstrip(".") if "." in mantissa else mantissa
    return f"{sign}{mantissa}×{power(exponent)}"


def linear_labels(values: Sequence[float], step: float) -> tuple[list[str], str]:
    """Labels of the ticks ``values`` (``step`` apart) on a linear axis and the note to
    show once at the axis end ('' when the labels read in full): tick value = label ×
    10ⁿ + offset for a note '×10ⁿ +offset' (thresholds: :data:`PLAIN`, :data:`SHARED`)."""
    finite = [v for v in values if math.isfinite(v)]
    if not finite or step <= 0:
        return [label(v, step) for v in values], ""
    low, high = min(finite), max(finite)
    offset, notes = 0.0, []
    if high > low and max(abs(low), abs(high)) >= SHARED * (high - low):
        unit = 10.0 ** math.ceil(math.log10(high - low))
        offset = (math.floor(low / unit) if low > 0 else math.ceil(high / unit)) * unit
        notes.append(_offset_text(offset, unit))
    largest = max(abs(v - offset) for v in finite)
    scale = 1.0
    if largest > 0 and not PLAIN[0] <= largest < PLAIN[1]:
        exponent = math.floor(math.log10(largest) + 1e-9)
        scale = 10.0**exponent
        notes.insert(0, f"×{power(exponent)}")
    if not notes:
        return [label(v, step) for v in values], ""
    return [label((v - offset) / scale, step / scale) for v in values], " ".join(notes)


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
    return f"{head}{power(exponent)}"
