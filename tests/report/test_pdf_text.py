"""The PDF writer's text: every character a report prints comes back out of the file
(pdftotext), from the shared subset of the usual repertoire and from an exact subset when
a text leaves it (a Cyrillic well name)."""

from __future__ import annotations

import gc
import os
import shutil
import subprocess
import warnings
from pathlib import Path

import pytest

from pipeline.reports.document import Document, Fields, Paragraph, Section
from pipeline.reports.pdf import render_pdf
from pipeline.reports.pdf_fonts import FONTS, REPERTOIRE

USUAL = "Azimuth σ 0.12° ≤ 3.0°, closure 45.2 m @ 37.1° — χ² = 1.2 (p = 0.55) ± 2 µm"
CYRILLIC = "Скважина Самотлор-7"


def pdf_text(pdf: Path) -> str:
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext not found: apt-get install poppler-utils")
    done = subprocess.run(["pdftotext", str(pdf), "-"], check=True, capture_output=True)
    return " ".join(done.stdout.decode("utf-8").split())


def document(subject: str) -> Document:
    return Document(
        title="Gyro survey report",
        subject=subject,
        subtitle="",
        issued="today",
        footer="gyropipe test",
        sections=(
            Section("Summary", (Fields("Results", (("Closure", USUAL),)), Paragraph(USUAL))),
        ),
    )


@pytest.mark.parametrize("subject", ["W-12", CYRILLIC])
def test_every_character_comes_back_out(tmp_path: Path, subject: str):
    pdf = tmp_path / "report.pdf"
    render_pdf(document(subject), pdf)
    text = pdf_text(pdf)
    assert subject in text and text.count(USUAL) == 2
    assert (set(subject) <= REPERTOIRE) == (subject == "W-12")


def test_fonts_leave_no_file_open(tmp_path: Path):
    """Text outside the repertoire reads the whole fonts and subsets them: no font file stays
    open, and none is left to the garbage collector (a ``ResourceWarning`` then, which
    pytest reports from whatever test runs at the time)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ResourceWarning)
        render_pdf(document(CYRILLIC + " ЖЩЮ"), tmp_path / "report.pdf")
        gc.collect()
    assert not [w for w in caught if issubclass(w.category, ResourceWarning)]
    fds = Path("/proc/self/fd")
    if fds.is_dir():
        open_files = [os.path.realpath(fds / fd) for fd in os.listdir(fds)]
        assert not [f for f in open_files if f.startswith(str(FONTS))]


def test_glyph_ids_are_written_as_four_hex_digits_each():
    """A text's glyph ids in a PDF string: each character's id as four capital hex digits,
    over the whole 16-bit range (ids in the surrogates' range too)."""
    from pipeline.reports.pdf_canvas import _glyph_hex

    ids = [0, 1, 0x41, 0xFF, 0x100, 0xD7FF, 0xD800, 0xDBFF, 0xDC00, 0xDFFF, 0xE000, 0xFFFF]
    text = "".join(chr(0x400 + k) for k in range(len(ids))) + "a"
    codes = {0x400 + k: chr(g) for k, g in enumerate(ids)} | {ord("a"): chr(0x2A)}
    assert _glyph_hex(text, codes) == "".join(f"{g:04X}" for g in [*ids, 0x2A])
    assert _glyph_hex("", codes) == ""
