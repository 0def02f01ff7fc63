"""A number as a file writes it: decimal text, not Python's literal syntax; values scaled
to canonical units."""

from __future__ import annotations

import numpy as np

__all__ = ["file_integer", "file_number", "scaled"]


def file_number(text: str) -> float:
    """``text`` as a float by :class:`float`'s syntax, less its digit grouping (``1_5`` is 15
    to Python, a mistyped cell to a file: no export writes one). Raises ``ValueError``."""
    if "_" in text:
        raise ValueError(f"not a number: {text!r}")
    return float(text)


def file_integer(text: str) -> int:
    """``text`` as an int by :class:`int`'s syntax, less its digit grouping (as
    :func:`file_number`). Raises ``ValueError``."""
    if "_" in text:
        raise ValueError(f"not an integer: {text!r}")
    return int(text)


def scaled(values: np.ndarray, factor: float, out: np.ndarray | None = None) -> np.ndarray:
    """``values`` times a unit's conversion ``factor``: a new array, or ``out`` (which may be
    ``values``: scaled in place). A value scaled past the largest double is inf, refused at
    its row by the contract's finite check, without NumPy's overflow warning (printed over
    the reader's located error)."""
    with np.errstate(over="ignore"):
        product: np.ndarray = np.multiply(values, factor, out=out)
    return product
