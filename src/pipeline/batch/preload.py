"""Imported once by the local executor's forkserver, so every worker process forks with
gyropipe's built-in plugins imported and the unit table built (about 2 s saved per worker).
Importing it is done for these side effects; a failure only costs that time."""

from __future__ import annotations

import contextlib
import importlib

from pipeline.batch import worker  # noqa: F401  (the task function workers run)
from pipeline.plugins import BUILTIN_PLUGINS
from pipeline.units import conversion_factor

for _module in BUILTIN_PLUGINS.values():
    with contextlib.suppress(Exception):  # a broken plugin is reported by load_registry
        importlib.import_module(_module)
conversion_factor("m", "length")  # builds the pint unit table (lazy, ~1 s)
