"""Bounds every reader puts on the shape of an input, whatever its size on disk."""

from __future__ import annotations

__all__ = ["HEADER_LINE_MAX", "MAX_COLUMNS", "TEXT_MAX", "too_long"]

MAX_COLUMNS = 1_000
"""Most columns an input table may have: CSV header cells, LAS curves, Parquet leaf columns
(a survey table has tens; 10⁶ CSV cells took 16 s and 430 MB, 10⁵ LAS curves 12 s and
660 MB)."""

TEXT_MAX = 65_536
"""Most characters of one header text gyropipe reads or writes: a CSV title value, a LAS
item's mnemonic, unit, value or description, a WITSML element's text or attribute value.
16 times WITSML 1.4.1.1's longest string (``abstractCommentString``, 4,000 characters); a
real header's names, numbers and dates are tens of characters, gyropipe's longest, a
``# tie_on=`` record, about 110 a survey. Bounds what one text costs: a 5-million-character
well name was read and copied into every table, header and file written from it."""

HEADER_LINE_MAX = TEXT_MAX + 1_024
"""Most characters of one header line of a CSV title block or a LAS section read: a text of
:data:`TEXT_MAX` and room for its key, unit and description (a LAS 2.0 line is of tens)."""


def too_long(text: str, what: str, longest: int = TEXT_MAX) -> str | None:
    """Why ``text`` (``what`` of a header, e.g. ``"the value of 'Well'"``) is refused when it
    is longer than ``longest`` characters, else None."""
    if len(text) <= longest:
        return None
    return (
        f"{what} is {len(text):,} characters, longer than the {longest:,} gyropipe reads in a "
        "header (a real one's names, numbers and dates are tens of characters): refused"
    )
