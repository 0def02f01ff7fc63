"""The standard frame positions of multi-position gyrocompassing (DOMAIN.md §5)."""

from __future__ import annotations

DEFAULT_POSITIONS = (0.0, 90.0, 180.0, 270.0, 0.0)
"""Frame positions of seed 004's five-position scheme, deg."""
