"""The PDF writer's text: every character a report prints comes back out of the file
(pdftotext), from the shared subset of the usual repertoire and from an exact subset when
a text leaves it (a Cyrillic well name)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from pipeline.reports.document import Document, Fields, Paragraph, Section
from pipeline.reports.pdf import render_pdf
from pipeline.reports.pdf_fonts import REPERTOIRE

USUAL = "Azimuth σ 0.12° ≤ 3.0°, closure 45.2 m @ 37.1° — χ² = 1.2 (p = 0.55) ± 2 µm"
CYRILLIC = "Скважина Самотлор-7"


def pdf_text(pdf: Path) -> str:
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext not found: apt-get install poppler-utils")
    done = subprocess.run(["pdftotext", str(pdf), "-"], check=True, capture_output=True)
    return " ".join(done.stdout.decode("utf-8").split())


@pytest.mark.parametrize("subject", ["W-12", CYRILLIC])
def test_every_character_comes_back_out(tmp_path: Path, subject: str):
    doc = Document(
        title="Gyro survey report",
        subject=subject,
        subtitle="",
        issued="today",
        footer="gyropipe test",
        sections=(
            Section("Summary", (Fields("Results", (("Closure", USUAL),)), Paragraph(USUAL))),
        ),
    )
    pdf = tmp_path / "report.pdf"
    render_pdf(doc, pdf)
    text = pdf_text(pdf)
    assert subject in text and text.count(USUAL) == 2
    assert (set(subject) <= REPERTOIRE) == (subject == "W-12")
