"""gyropipe: gyroscopic well-survey processing as a DAG of pluggable stages over Arrow tables."""

from pipeline.version import __version__

__all__ = ["__version__"]
