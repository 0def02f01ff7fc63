"""gyropipe's LAS reader (kind ``log``) against lasio on a corpus of LAS files.

Reads every ``*.las`` file under a directory (e.g. the ``tests/examples`` of lasio's source
distribution) with ``lasio.read`` and with ``pipeline.io.las.read_las(path, "log", None)``,
compares the curves' mnemonics, units and values (NaN for nulls) and prints one line per
file and the count of each outcome:

* ``equal``          both read it, with the same mnemonics, units and values
* ``differ``         both read it, with a difference (the first one is printed)
* ``only lasio``     gyropipe refused it (its located error is printed)
* ``only gyropipe``  lasio failed (its error is printed)
* ``neither``        both refused it

Values are compared as lasio gives them, normalised where lasio keeps a curve as text that
gyropipe reads as numbers: a lasio cell that is a text null (``(null)``, ``-``, ``nan``) is
a null, one that is a number is that number; text cells are compared without surrounding
spaces. Such files count as equal, with a note. Where gyropipe knowingly differs, the reason
is printed from :data:`EXPLAINED` (and documented in ``benchmarks/README.md``).

    python benchmarks/lasio_corpus.py /tmp/lasio-sdist/lasio-0.31/tests/examples
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

import lasio
import numpy as np
import pyarrow as pa

from pipeline.contracts import SOURCE_LINE, UNIT_KEY
from pipeline.errors import GyropipeError
from pipeline.io.las import read_las
from pipeline.io.las.header import utf16_codec

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from tests_support import comparable_cell

_UTF16 = (
    "UTF-16 text: lasio decodes it as 8-bit text and finds no section (or garbage); gyropipe "
    "recognises UTF-16 by its byte-order mark or, without one, by the NUL of every other byte"
)
_UTF8 = (
    "UTF-8 text without a byte-order mark: lasio decodes it as Windows-1252 (mojibake such as "
    "'{}'); gyropipe reads bytes that are valid UTF-8 as UTF-8"
)
_FEWER = (
    "~Curve defines 6 curves but every row has 4 values: lasio keeps 4 and fills the other 2 "
    "with NaN, guessing that the missing curves are the last ones; gyropipe names the first "
    "short row (file:line), as which curves the rows lack cannot be known"
)
EXPLAINED: dict[str, str] = {
    "encodings_utf16be.las": _UTF16,
    "encodings_utf16bebom.las": _UTF16,
    "encodings_utf16le.las": _UTF16,
    "encodings_utf16lebom.las": _UTF16,
    "encodings_utf8.las": _UTF8.format("ÂºÁ¶ŸÁΜŒÁ´¬Å„"),
    "sample_cyrillic_depth_unit.las": _UTF8.format("Ð¼ÐµÑ‚ÐµÑ€"),
    "issue79.las": _UTF8.format("ÂµS"),
    "null_policy_ind.las": (
        "'-1.#IND0000' is how Microsoft's C runtime prints an indeterminate value (NaN): lasio "
        "reads it as -1.0 in CN and as NaN in CD (its regular expression only matches the "
        "last column); gyropipe reads NaN in both"
    ),
    "excess_curves.las": _FEWER,
    "issue83.las": _FEWER,
    "sample_write_sect_widths_12.las": (
        "~Curve defines 4 curves (D, A, B, C) but every row has 8 values: lasio appends 4 "
        "curves UNKNOWN:1-4; gyropipe names the first row (file:line), as which 4 of the 8 "
        "columns are D, A, B and C cannot be known"
    ),
    "sample_lastcolblanked.las": (
        "a row lacks its last value: lasio fails to reshape the data; gyropipe names the row"
    ),
    "dodgy_param_sect.las": "a data line inside ~Parameter: both refuse it, gyropipe naming it",
    "issue92.las": "a line of dashes inside ~Curve: both refuse it, gyropipe naming it",
    "not_a_las_file.las": "no ~ section at all: both refuse it",
    "missing_null.las": (
        "the ~Well section has no NULL item and DT starts with -999.25: lasio keeps -999.25 "
        "as a value; gyropipe reads the industry's null marker (-999.25, -9999.25) as a null "
        "in every reader, with or without a NULL item (a DT of -999.25 us/ft is no reading)"
    ),
    "null_policy_runon.las": (
        "values that ran together: '7.330-19508.961' is split at its minus sign by both; "
        "'7.020101130.188' (two values, border unknown) is read as two nulls by both, gyropipe "
        "with a warning naming its line"
    ),
}
"""File name → why gyropipe's reading differs from lasio's and why it is the better one."""


Lasio = tuple[list[str], list[str], list[np.ndarray], float | None]


def lasio_curves(path: Path) -> Lasio:
    """lasio's mnemonics, units, curves and NULL value."""
    logging.disable(logging.CRITICAL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        las = lasio.read(str(path))
    null = las.well["NULL"].value if "NULL" in las.well else None
    return (
        [c.mnemonic for c in las.curves],
        [c.unit for c in las.curves],
        [np.asarray(c.data) for c in las.curves],
        null if isinstance(null, int | float) else None,
    )


def gyropipe_curves(path: Path) -> tuple[list[str], list[str], list[pa.Array], list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table, _ = read_las(path, "log", None)
    fields = [f for f in table.schema if f.name != SOURCE_LINE]
    units = [((f.metadata or {}).get(UNIT_KEY) or b"").decode() for f in fields]
    columns = [table.column(f.name).combine_chunks() for f in fields]
    return [f.name for f in fields], units, columns, [str(w.message) for w in caught]


def compare(
    ours: tuple[list[str], list[str], list[pa.Array], list[str]],
    theirs: Lasio,
) -> tuple[str | None, list[str]]:
    """The first difference (None: equal) and notes on normalisations made."""
    names, units, columns, _ = ours
    their_names, their_units, their_columns, null = theirs
    notes: list[str] = []
    if names != their_names:
        return f"mnemonics {names} vs lasio's {their_names}", notes
    if units != their_units:
        pairs = [(n, a, b) for n, a, b in zip(names, units, their_units, strict=True) if a != b]
        return "units " + ", ".join(f"{n}: {a!r} vs lasio's {b!r}" for n, a, b in pairs), notes
    for name, column, data in zip(names, columns, their_columns, strict=True):
        if len(column) != len(data):
            return f"{name}: {len(column)} rows vs lasio's {len(data)}", notes
        if data.dtype.kind == "f" and pa.types.is_floating(column.type):
            if not np.array_equal(column.to_numpy(zero_copy_only=False), data, equal_nan=True):
                at = int(np.flatnonzero(~np.isclose(column.to_numpy(), data, equal_nan=True))[0])
                return f"{name}: row {at}: {column[at].as_py()!r} vs lasio's {data[at]!r}", notes
            continue
        mine = [comparable_cell(v) for v in column.to_pylist()]
        lasios = [comparable_cell(v, null) for v in data.tolist()]
        if mine != lasios:
            at = next(i for i, (a, b) in enumerate(zip(mine, lasios, strict=True)) if a != b)
            return f"{name}: row {at}: {mine[at]!r} vs lasio's {lasios[at]!r}", notes
        if data.dtype.kind != "f" and pa.types.is_floating(column.type):
            notes.append(f"{name}: lasio keeps text ({sorted({str(v) for v in data})[:3]}…)")
        elif data.dtype.kind != "f" and any(
            isinstance(v, str) and v != v.strip() for v in data.tolist()
        ):
            notes.append(f"{name}: lasio keeps surrounding spaces")
    return None, notes


def _against_utf8_copy(path: Path, ours: Any) -> str:
    """For a UTF-16 file lasio cannot read: how gyropipe's reading compares with lasio's
    reading of the file transcoded to UTF-8."""
    codec = utf16_codec(path.read_bytes())
    if codec is None:
        return ""
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / path.name
        copy.write_text(path.read_bytes().decode(codec).removeprefix("\ufeff"), "utf-8-sig")
        difference, _ = compare(ours, lasio_curves(copy))
    return f"; its UTF-8 copy: {difference or 'equal to lasio reading it'}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("corpus", type=Path, help="directory of LAS files (searched recursively)")
    parser.add_argument("--quiet", action="store_true", help="only the counts")
    args = parser.parse_args()
    files = sorted(p for p in args.corpus.rglob("*") if p.suffix.lower() == ".las")
    outcomes: Counter[str] = Counter()
    for path in files:
        name = str(path.relative_to(args.corpus))
        try:
            theirs = lasio_curves(path)
            lasio_error = ""
        except Exception as exc:  # lasio fails in many ways
            lasio_error = f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
        try:
            ours = gyropipe_curves(path)
            our_error = ""
        except GyropipeError as exc:
            our_error = str(exc).removeprefix(str(path))
        if lasio_error and our_error:
            outcome, detail = "neither", f"lasio: {lasio_error}; gyropipe: {our_error}"
        elif lasio_error:
            outcome, detail = "only gyropipe", f"lasio: {lasio_error}"
            detail += _against_utf8_copy(path, ours)
        elif our_error:
            outcome, detail = "only lasio", f"gyropipe: {our_error}"
        else:
            difference, notes = compare(ours, theirs)
            outcome = "differ" if difference else "equal"
            detail = difference or "; ".join(notes)
        if not our_error and ours[3]:
            detail += (
                (" | " if detail else "")
                + "warning "
                + " | ".join(w.removeprefix(str(path)) for w in ours[3])
            )
        outcomes[outcome] += 1
        if not args.quiet:
            why = f"\n      why: {EXPLAINED[path.name]}" if path.name in EXPLAINED else ""
            print(f"{outcome:<14} {name}" + (f": {detail}" if detail else "") + why)
    read_lasio = outcomes["equal"] + outcomes["differ"] + outcomes["only lasio"]
    read_ours = outcomes["equal"] + outcomes["differ"] + outcomes["only gyropipe"]
    version = lasio.__version__
    print(f"\n{len(files)} files: lasio {version} reads {read_lasio}, gyropipe {read_ours}")
    for outcome in ("equal", "differ", "only lasio", "only gyropipe", "neither"):
        print(f"  {outcome:<14} {outcomes[outcome]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
