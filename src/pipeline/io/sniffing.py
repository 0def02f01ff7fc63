"""What readers' ``sniff`` functions share: the head of a file, read without raising."""

from __future__ import annotations

from pathlib import Path


def file_head(path: Path, size: int) -> bytes | None:
    """The first ``size`` bytes of ``path``; None if it cannot be read (a sniffer never
    raises)."""
    try:
        with path.open("rb") as fh:
            return fh.read(size)
    except OSError:
        return None
