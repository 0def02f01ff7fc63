"""pyarrow without pandas until something imports pandas.

pyarrow imports pandas (≈ 0.3 s CPU, most of a run's start-up after NumPy and pyarrow
themselves) the first time it converts a NumPy array or a Python value, only to ask
whether the value is a pandas object. A survey run holds no pandas objects.
:func:`defer_pandas` lets pyarrow's first such question find no pandas, and as soon as
anything imports pandas afterwards (a plugin, a notebook, pyarrow's own ``to_pandas``)
has pyarrow load its pandas integration at once, so pyarrow treats pandas objects exactly
as it always does (tests/engine/test_lazy_pandas.py compares with a plain process).

Relies on pyarrow's pandas shim (``pyarrow/pandas-shim.pxi``, read in pyarrow 26): a
failed first import is remembered for the checks, and a later explicit use imports pandas
again. The tests compare with a plain process, so a pyarrow that changes this shows.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
from collections.abc import Sequence
from types import ModuleType

import pyarrow as pa


def defer_pandas() -> None:
    """Keep pandas out of this process until something imports it (see the module). Does
    nothing where pandas is already imported or pyarrow has already looked for it."""
    if "pandas" in sys.modules or any(isinstance(f, _Announce) for f in sys.meta_path):
        return
    held = _HeldBack()
    sys.meta_path.insert(0, held)
    try:
        pa.array([0.0])  # pyarrow's first look for pandas: finds none
    finally:
        sys.meta_path.remove(held)
    if "pandas" not in sys.modules:  # pyarrow had already looked and imported it
        sys.meta_path.insert(0, _Announce())


class _HeldBack(importlib.abc.MetaPathFinder):
    """Refuses ``import pandas`` (only while pyarrow first looks for it)."""

    def find_spec(
        self, name: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if name == "pandas":
            raise ModuleNotFoundError("pandas held back until something imports it")
        return None


class _Announce(importlib.abc.MetaPathFinder):
    """Finds pandas with the other finders, and once pandas' ``__init__`` has run has
    pyarrow load its pandas integration, then leaves ``sys.meta_path`` (stays for another
    try if importing pandas failed)."""

    def find_spec(
        self, name: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if name != "pandas":
            return None
        for finder in sys.meta_path:
            if finder is not self and hasattr(finder, "find_spec"):
                spec = finder.find_spec(name, path, target)
                if spec is not None:
                    break
        else:
            return None
        loader = spec.loader
        if loader is not None and hasattr(loader, "exec_module"):
            run = loader.exec_module

            def exec_module(module: ModuleType) -> None:
                run(module)
                if self in sys.meta_path:
                    sys.meta_path.remove(self)
                pa.lib._pandas_api.pd  # noqa: B018 -- pyarrow imports its pandas integration

            loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec
