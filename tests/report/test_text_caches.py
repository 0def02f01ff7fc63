"""A batch worker renders report after report: the widths of texts it has measured are kept
in bounded caches, not one entry for every well name, number and date of the batch."""

from __future__ import annotations

import pytest

from pipeline.reports import pdf_layout
from pipeline.reports.charts import scene
from pipeline.reports.pdf_fonts import TEXTS


def test_text_widths_kept_are_bounded_and_stay_right() -> None:
    first = pdf_layout.text_width("W-0", 9.0)
    for k in range(TEXTS + 500):  # more distinct texts than a process keeps
        pdf_layout.text_width(f"W-{k}", 9.0)
        scene.text_width(f"W-{k}", 9.0)
    assert pdf_layout.text_width.cache_info().currsize <= TEXTS
    assert scene.text_width.cache_info().currsize <= TEXTS
    assert pdf_layout.text_width("W-0", 9.0) == first  # measured again after eviction
    assert scene.text_width("W-0", 9.0) == pytest.approx(first * 72.0, rel=1e-12)  # points
