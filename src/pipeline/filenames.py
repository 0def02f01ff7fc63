"""Names of the files a stage writes into the run's output directory.

:data:`OutputFilename` is the one type of every stage parameter that names an output file
(``write``, ``export``, the report stages, and any plugin's): a plain file name, checked when
the pipeline is validated, so a name that would leave the output directory, overwrite the
run's manifest or be refused by the file system is a located problem at its YAML line, not
a failure in the middle of a run.
"""

from __future__ import annotations

import re
from typing import Annotated

from pydantic import AfterValidator, Field

from pipeline.manifest import MANIFEST

MAX_LENGTH = 200
"""Longest output file name (file systems allow 255 bytes; report stages add ``.html``)."""
RESERVED = frozenset({MANIFEST})
"""Names the runner itself writes in the output directory."""
NAME_CHARACTERS = r"[A-Za-z0-9][A-Za-z0-9._-]*"
PLAIN = re.compile(rf"{NAME_CHARACTERS}\Z")
"""A plain name, matched to its very end (``$`` would also match before a final newline)."""


def check_output_filename(name: str) -> str:
    """``name`` if it is a plain output file name; else a ``ValueError`` saying why."""
    if not name:
        raise ValueError("an output file name must not be empty")
    if "/" in name or "\\" in name:
        raise ValueError(
            "a path, not a file name: an output file name has no directory ('/', '\\'); "
            "every output is written into the run's output directory"
        )
    if name in (".", ".."):
        raise ValueError("not a file name")
    if name.casefold() in RESERVED:  # one file on a case-insensitive file system
        raise ValueError(f"{name} is the run's manifest: choose another output file name")
    if len(name) > MAX_LENGTH:
        raise ValueError(f"an output file name has at most {MAX_LENGTH} characters")
    if not PLAIN.match(name):
        raise ValueError(
            "not a plain file name: letters, digits, '.', '_' and '-', starting with a letter "
            "or digit"
        )
    return name


OutputFilename = Annotated[
    str,
    AfterValidator(check_output_filename),
    Field(json_schema_extra={"pattern": f"^{NAME_CHARACTERS}$", "maxLength": MAX_LENGTH}),
]
"""A stage parameter naming a file in the run's output directory (see the module doc)."""
