"""Bounds every reader puts on the shape of an input, whatever its size on disk."""

from __future__ import annotations

__all__ = ["MAX_COLUMNS"]

MAX_COLUMNS = 1_000
"""Most columns an input table may have: CSV header cells, LAS curves, Parquet leaf columns
(a survey table has tens; 10⁶ CSV cells took 16 s and 430 MB, 10⁵ LAS curves 12 s and
660 MB)."""
