"""gyropipe: gyroscopic well-survey processing as a DAG of pluggable stages over Arrow tables."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gyropipe")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
