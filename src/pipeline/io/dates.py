"""Dates as survey file headers write them, one rule for every reader (a LAS DATE item, a
CSV title's date): ISO (``2026-11-21``, ``20261121``) or another unambiguous form —
``13-DEC-1986``, ``Dec 13, 1986``, ``13/12/1986`` (a two-digit year after a month name is the
latest such year not after today); ``05/06/2024`` is refused as ambiguous. A time of day
after the date is ignored.
"""

from __future__ import annotations

import calendar
import datetime as dt
import re

_MONTHS = {name.upper(): i for i, name in enumerate(calendar.month_name) if name}
_TIME_OF_DAY = re.compile(
    r"[T\s]+\d{1,2}:\d{2}(:\d{2}(\.\d*)?)?\s*(Z|UTC|GMT|[+-]\d{2}:?\d{2})?$", re.IGNORECASE
)


def header_date(value: str) -> dt.date:
    """The date a header value writes (see the module docstring). Raises ``ValueError``."""
    try:
        return _parse_date(_TIME_OF_DAY.sub("", value.strip()))
    except OverflowError as exc:  # a day past C long
        raise ValueError(str(exc)) from None


def _parse_date(text: str) -> dt.date:
    """ISO and other unambiguous dates; see the module docstring."""
    if re.fullmatch(r"\d{8}", text):
        return dt.date(int(text[:4]), int(text[4:6]), int(text[6:]))
    tokens = re.findall(r"[A-Za-z]+|\d+", text)
    words = [t for t in tokens if t.isalpha()]
    numbers = [t for t in tokens if t.isdigit()]
    if not re.fullmatch(r"[A-Za-z0-9\s,./-]+", text) or len(tokens) != 3 or len(words) > 1:
        raise ValueError("not a date")
    if words:
        where = tokens.index(words[0])
        if where == 2:
            raise ValueError("not a date")
        year, day = numbers if where == 1 and len(numbers[0]) == 4 else numbers[::-1]
        return dt.date(_year(year), _month(words[0]), int(day))
    if len(numbers[0]) == 4:
        return dt.date(int(numbers[0]), int(numbers[1]), int(numbers[2]))
    if len(numbers[2]) != 4:
        raise ValueError("ambiguous order of day, month and a two-digit year")
    a, b = int(numbers[0]), int(numbers[1])
    if a != b and a <= 12 and b <= 12:
        raise ValueError(f"ambiguous: day {a} of month {b}, or day {b} of month {a}")
    day, month = (a, b) if a > 12 or a == b else (b, a)
    return dt.date(int(numbers[2]), month, day)


def _month(word: str) -> int:
    matches = [i for name, i in _MONTHS.items() if len(word) >= 3 and name.startswith(word.upper())]
    if len(matches) != 1:
        raise ValueError(f"{word!r} is not a month")
    return matches[0]


def _year(text: str) -> int:
    """A four-digit year, or a two-digit one as the latest such year not after today."""
    if len(text) not in (2, 4):
        raise ValueError(f"year {text!r}")
    if len(text) == 4:
        return int(text)
    this_year = dt.date.today().year
    return this_year - (this_year - int(text)) % 100
