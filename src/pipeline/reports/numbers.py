"""How numbers are printed in a report: fixed decimals, significant digits, uncertainties
and azimuths. Shared by the document content and the figures."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

UNDEFINED = "undefined"
"""What an uncertainty prints as when it does not exist (infinite or NaN)."""
SIGMA_DIGITS = 2
"""Significant digits of a printed σ."""
SIGMA_FIXED_BELOW = -4
"""A σ whose decimal exponent is at least this prints in fixed notation (0.00012), a
smaller one in scientific notation (4.0e−5)."""


def _minus(text: str) -> str:
    return text.replace("-", "−")


def fmt(value: float | None, decimals: int = 2) -> str:
    """A number with fixed decimals; blank for null, '—' for NaN."""
    if value is None:
        return ""
    if math.isnan(value):
        return "—"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    text = f"{value:.{decimals}f}"
    if text[0] != "-":  # the only place a minus can be
        return text
    return _minus(text) if text.strip("-0. ") else text[1:]


def fmt_each(values: NDArray[np.float64], decimals: int = 2) -> list[str]:
    """:func:`fmt` of each of ``values``: those that print as they are (finite, sign bit
    clear) by one ``%`` of them all — ``"%.2f"`` writes a float as ``f"{v:.2f}"`` does —
    the others (NaN, ±∞, negative, −0) by :func:`fmt`."""
    plain = values.tolist()  # Python floats: faster to format than NumPy's
    texts = (f"%.{decimals}f\n" * len(plain) % tuple(plain)).split("\n")[:-1]
    for i in np.flatnonzero(~np.isfinite(values) | np.signbit(values)).tolist():
        texts[i] = fmt(plain[i], decimals)
    return texts


def fmt_sig(value: float | None, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (small σ, p-values)."""
    if value is None:
        return ""
    if not math.isfinite(value):
        return fmt(value)
    return _minus(f"{value:.{digits}g}")


def fmt_sigma(value: float | None) -> str:
    """A standard deviation with :data:`SIGMA_DIGITS` significant digits: fixed notation
    down to 1e−4 (``0.031``, ``1.2``, ``0.00012``), scientific below (``4.0e−5``); zero as
    ``0``; :data:`UNDEFINED` where it is infinite or NaN (no finite σ exists)."""
    if value is None:
        return ""
    if not math.isfinite(value):
        return UNDEFINED
    if value == 0:
        return "0"
    form = _sigma_form(value, f"{value:.{SIGMA_DIGITS - 1}e}")
    return form if isinstance(form, str) else _minus(f"{value:.{form}f}")


def _sigma_form(value: float, scientific: str) -> str | int:
    """How :func:`fmt_sigma` prints a finite, non-zero ``value`` whose ``%.1e`` text is
    ``scientific``: that text (below 1e−4), else the decimals to print it fixed with (as
    :func:`sigma_decimals`)."""
    mantissa, exponent = scientific.split("e")
    power = int(exponent)
    if power < SIGMA_FIXED_BELOW:
        return _minus(f"{mantissa}e{power}")
    return max(SIGMA_DIGITS - 1 - power, 0) if value > 0 else 0


def fmt_sigmas(values: NDArray[np.float64]) -> list[str]:
    """:func:`fmt_sigma` of each of ``values``: their ``%.1e`` texts (which give the
    exponents) by one ``%`` of them all, then the fixed ones of each count of decimals (a
    column has a few) by one ``%`` each — the same format specifications, so the same text."""
    plain = values.tolist()
    scientific = (f"%.{SIGMA_DIGITS - 1}e\n" * len(plain) % tuple(plain)).split("\n")
    texts = [UNDEFINED] * len(plain)
    fixed: dict[int, list[int]] = {}  # decimals → the values printed with them
    for i, value in enumerate(plain):
        if value == 0:
            texts[i] = "0"
        elif math.isfinite(value):
            form = _sigma_form(value, scientific[i])
            if isinstance(form, str):
                texts[i] = form
            else:
                fixed.setdefault(form, []).append(i)
    for decimals, chosen in fixed.items():
        made = f"%.{decimals}f\n" * len(chosen) % tuple(plain[i] for i in chosen)
        for i, text in zip(chosen, made.split("\n"), strict=False):
            texts[i] = _minus(text)
    return texts


def sigma_decimals(sigma: float) -> int:
    """Decimals down to the last of :data:`SIGMA_DIGITS` significant digits of ``sigma``
    (0 for a σ of 10 or more, or one that is zero or not finite)."""
    if not math.isfinite(sigma) or sigma <= 0:
        return 0
    power = int(f"{sigma:.{SIGMA_DIGITS - 1}e}".split("e")[1])
    return max(SIGMA_DIGITS - 1 - power, 0)


def fmt_measured(value: float | None, sigma: float | None, decimals: int = 2) -> str:
    """A measured value with at least ``decimals`` decimals, and more where its σ is finer
    (down to the σ's last printed digit): a value smaller than the usual decimals but known
    better than them never prints as 0.000 (4.1e−6 ± 2.0e−7 °/h prints 0.0000041)."""
    if value is None or sigma is None or not math.isfinite(sigma):
        return fmt(value, decimals)
    return fmt(value, max(decimals, sigma_decimals(sigma)))


def azimuth_value(value: float, decimals: int) -> float:
    """``value`` (deg) in [0, 360) as printed with ``decimals``: a value that rounds to
    360 (or a −1e−13 that wraps to it) is 0."""
    wrapped = value % 360.0
    return 0.0 if round(wrapped, decimals) >= 360.0 else wrapped


def fmt_azimuth(value: float | None, decimals: int = 2) -> str:
    """An azimuth (deg) in [0, 360) with fixed decimals: never '360.00', never '−0.00';
    :data:`UNDEFINED` for NaN (no azimuth exists: vertical)."""
    if value is not None and math.isnan(value):
        return UNDEFINED
    if value is None or not math.isfinite(value):
        return fmt(value, decimals)
    return fmt(azimuth_value(value, decimals), decimals)


def fmt_azimuths(values: NDArray[np.float64], decimals: int = 2) -> list[str]:
    """:func:`fmt_azimuth` of each of ``values``: wrapped into [0, 360) at once (NumPy's
    remainder is Python's ``%``), those that may round to 360 by :func:`azimuth_value`,
    then all printed by :func:`fmt_each`; NaN as :data:`UNDEFINED`."""
    with np.errstate(invalid="ignore"):  # ±∞: NaN, printed from the value itself
        wrapped = np.remainder(values, 360.0)
    for i in np.flatnonzero(wrapped >= 360.0 - 10.0**-decimals).tolist():  # round() ≥ 360?
        wrapped[i] = azimuth_value(float(values[i]), decimals)
    texts = fmt_each(np.where(np.isinf(values), values, wrapped), decimals)
    for i in np.flatnonzero(np.isnan(values)).tolist():
        texts[i] = UNDEFINED
    return texts


INCH = 0.0254
"""Metres per inch."""
_QUARTERS = {2: "¼", 4: "½", 6: "¾"}
"""Eighths printed as a Latin-1 fraction glyph (the report fonts' repertoire has no ⅛)."""


def fmt_inches(metres: float | None) -> str:
    """A hole or casing size in inches as the industry writes it: whole eighths as a
    fraction (0.3112 m → '12¼', 0.2159 m → '8½', 0.9144 m → '36', 0.1556 m → '6 1/8'),
    others to 3 decimals ('12.350'); blank for null."""
    if metres is None or not math.isfinite(metres):
        return fmt(metres)
    inches = metres / INCH
    eighths = round(inches * 8)
    if abs(inches * 8 - eighths) > 0.02:  # 0.3112 m is 12.252 in: 12¼ as drilled
        return fmt(inches, 3)
    whole, part = divmod(eighths, 8)
    if part % 2:
        return f"{whole} {part}/8" if whole else f"{part}/8"
    return f"{whole if whole or not part else ''}{_QUARTERS.get(part, '')}"
