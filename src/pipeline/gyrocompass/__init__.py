"""Gyrocompassing: north from the Earth rate measured by gyros (DOMAIN.md §5)."""
