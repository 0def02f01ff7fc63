"""A package's public names loaded on first use (PEP 562): importing the package, or one of
its modules, does not import the modules behind all its names."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_names(
    package: str, homes: Mapping[str, tuple[str, ...]], namespace: dict[str, Any]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of ``package``: each name of
    ``homes`` (module → the names it defines) is imported from its module on first use and
    kept in ``namespace`` (the package's ``globals()``); ``dir()`` lists the package's
    ``__all__`` (else the names of ``homes``) and its dunders, as tab completion should."""
    home_of = {name: module for module, names in homes.items() for name in names}

    def getattr_(name: str) -> Any:
        module = home_of.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def dir_() -> list[str]:
        # the curated names (``__all__``, else every lazy one) and the dunders: not what the
        # package's own imports leave in its namespace (TYPE_CHECKING, annotations, modules)
        public = namespace.get("__all__", home_of)
        return sorted({*public, *(n for n in namespace if n.startswith("__"))})

    return getattr_, dir_
