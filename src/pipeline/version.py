"""gyropipe's version: the one place it is written (``pyproject.toml`` reads it from here),
so that importing it costs nothing (no ``importlib.metadata``)."""

__version__ = "0.1.0"
