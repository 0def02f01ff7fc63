"""A failed run's error as a reader wants it: the stage's plugin and the error's class
dropped, paths shortened to file names (:func:`cause`, the terminal), and the stage too
(:func:`plain_cause`, the fleet page's readers do not know the pipeline's stages)."""

from __future__ import annotations

import re
from collections.abc import Callable

STAGE_FAILED = re.compile(r"^stage '([^']+)' \([^)]*\) failed: (?:\w+Error: )?")
PATH = re.compile(r"(?:[^\s:'\"]*/)+([^\s:/'\"]+)")


def cause(detail: str) -> str:
    """``stage: file:line: message``."""
    return _shortened(detail, lambda m: f"{m.group(1)}: ")


def plain_cause(detail: str) -> str:
    """``file:line: message``."""
    return _shortened(detail, "")


def _shortened(detail: str, stage: str | Callable[[re.Match[str]], str]) -> str:
    """``detail`` on one line, its ``stage '…' (…) failed: XError:`` prefix replaced by
    ``stage``, paths shortened to file names."""
    text = STAGE_FAILED.sub(stage, " ".join(detail.split()))
    return PATH.sub(lambda m: m.group(1), text)
