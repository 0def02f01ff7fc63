"""``pipeline.lazy``: the names of ``pipeline`` and ``pipeline.continuous`` loaded on first use."""

from __future__ import annotations

import json
from typing import Any

import pytest

import pipeline as gp
import pipeline.continuous
from pipeline.lazy import lazy_names


def test_a_name_is_imported_from_its_module_on_first_use_and_kept() -> None:
    namespace: dict[str, Any] = {}
    getattr_, dir_ = lazy_names("toy", {"json": ("dumps", "loads")}, namespace)
    assert dir_() == ["dumps", "loads"]
    namespace.update(__all__=["loads"], __doc__="toy", TYPE_CHECKING=False)
    assert dir_() == ["__all__", "__doc__", "loads"]
    namespace.clear()
    assert getattr_("dumps") is json.dumps
    assert namespace == {"dumps": json.dumps}
    with pytest.raises(AttributeError, match="module 'toy' has no attribute 'dump'"):
        getattr_("dump")


def test_the_packages_list_and_load_their_names() -> None:
    assert {n for n in dir(gp) if not n.startswith("__")} == set(gp.__all__) - {"__version__"}
    assert set(pipeline.continuous.__all__) <= set(dir(pipeline.continuous))
    from pipeline.continuous.options import ContinuousOptions

    assert pipeline.continuous.ContinuousOptions is ContinuousOptions
    with pytest.raises(AttributeError, match=r"module 'pipeline\.continuous' has no attribute"):
        pipeline.continuous.integrate_continously  # noqa: B018
