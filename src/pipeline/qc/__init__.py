"""Validity checks of raw sensor data against the Earth references (DOMAIN.md §3): checks of
point-survey readings and of sliding windows of continuous data, and isolation of the
faulty sensor."""
