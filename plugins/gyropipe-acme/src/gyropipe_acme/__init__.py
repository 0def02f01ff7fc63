"""Example gyropipe vendor adapter for the (fictional) Acme GyroLog format: see
:mod:`gyropipe_acme.gyrolog` for the format and :mod:`gyropipe_acme.plugin` for the hooks."""

from gyropipe_acme.gyrolog import read_samples, sniff, write_samples

__all__ = ["read_samples", "sniff", "write_samples"]
