"""Fixtures of the report tests (helpers in report_support.py)."""

from report_support import browser

__all__ = ["browser"]
