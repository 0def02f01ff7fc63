"""Helpers importable by test modules (pytest puts tests/ on sys.path)."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def gyropipe() -> list[str]:
    """Command line that runs the installed ``gyropipe`` console script."""
    exe = Path(sys.executable).parent / "gyropipe"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("gyropipe")
    assert found, "the gyropipe console script is not installed"
    return [found]
