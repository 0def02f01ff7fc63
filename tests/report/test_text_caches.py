"""A batch worker renders report after report: the widths of texts it has measured are kept
in bounded caches, not one entry for every well name, number and date of the batch."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipeline.reports import pdf_canvas, pdf_layout
from pipeline.reports.charts import scene
from pipeline.reports.pdf_canvas import RUNS, Page, write_pdf
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


def _pdf(path: Path, texts: list[str]) -> bytes:
    page = Page(8.27, 11.69)
    for k, content in enumerate(texts):
        page.text(1.0, 10.0 - 0.02 * (k % 400), content, 7.5)
    write_pdf([page], path, "t", "gyropipe")
    return path.read_bytes()


def test_glyph_runs_kept_across_files_write_what_a_fresh_process_writes(tmp_path: Path):
    """A kerned text's glyph runs are kept by the font subset from one PDF to the next
    (boundedly): a file written after others is the file written with nothing kept."""
    texts = ["AVAWAY To Ta", "Wave: 1,234.5 m", "Yours, LT 7.0°"]
    pdf_canvas._PROGRAMS.clear()  # nothing kept: as a fresh process
    fresh = _pdf(tmp_path / "fresh.pdf", texts)
    _pdf(tmp_path / "other.pdf", [*texts[:2], "VA Ty", "AT&T"])
    assert _pdf(tmp_path / "again.pdf", texts) == fresh
    kept = next(p.runs for p in pdf_canvas._PROGRAMS.values() if p.runs)  # the sans subset's
    assert set(texts) <= kept.keys()
    _pdf(tmp_path / "many.pdf", [f"AV {k}" for k in range(RUNS + 100)])
    assert len(kept) <= RUNS
    assert _pdf(tmp_path / "last.pdf", texts) == fresh
