"""A number as a file writes it: decimal text, not Python's literal syntax."""

from __future__ import annotations

__all__ = ["file_integer", "file_number"]


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
