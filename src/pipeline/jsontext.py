"""JSON text that files carry (schema and channel metadata), parsed with a depth limit.

Metadata is a few flat objects; a document nested deeper than :data:`MAX_DEPTH` levels is
refused with :class:`TooDeep` (a ``ValueError``, so callers that report bad JSON report it
with their location), never the ``RecursionError`` of the parser or of a walk over the value.
"""

from __future__ import annotations

import json
from typing import Any

MAX_DEPTH = 64
"""Deepest nesting of arrays and objects accepted in JSON metadata."""


class TooDeep(ValueError):
    """JSON text nested deeper than :data:`MAX_DEPTH`."""

    def __init__(self) -> None:
        super().__init__(f"JSON nested deeper than {MAX_DEPTH} levels: refused")


def loads(text: str | bytes) -> Any:
    """``json.loads(text)``, refusing nesting deeper than :data:`MAX_DEPTH` (:class:`TooDeep`);
    other bad text raises ``ValueError`` as ``json.loads`` does."""
    try:
        value = json.loads(text)
    except RecursionError:
        raise TooDeep() from None
    if _depth(value) > MAX_DEPTH:
        raise TooDeep()
    return value


def _depth(value: Any) -> int:
    """Nesting depth of a parsed JSON value (a scalar: 0), without recursion."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        children = node.values() if isinstance(node, dict) else node
        if isinstance(node, dict | list):
            deepest = max(deepest, depth)
            if depth <= MAX_DEPTH:
                stack.extend((child, depth + 1) for child in children)
    return deepest
