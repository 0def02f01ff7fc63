"""Helpers of the report tests: runs through the `gyropipe` command, the HTML inspected in
headless Chromium (Debian's, driven by Playwright), the PDF rasterised by pdftoppm. A
report's figures are inline SVG in the HTML and vector drawings in the PDF."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
PDF_DPI = 50


@dataclass
class PageReport:
    """What Chromium saw when it loaded a report."""

    console_errors: list[str]
    requests: list[str]
    svgs: list[dict[str, Any]]
    """every inline SVG: its figure, size as laid out and shown (CSS px)"""
    tables: dict[str, list[list[str]]]
    headers: dict[str, list[str]]
    units: dict[str, list[str]]
    figures: list[str]
    text: str


INSPECT = """async () => {
  const svgs = Array.from(document.querySelectorAll('svg'));
  const tables = {}, headers = {}, units = {};
  document.querySelectorAll('table').forEach((t, k) => {
    const key = t.classList[0] + (tables[t.classList[0]] ? '-' + k : '');
    tables[key] = Array.from(t.tBodies[0].rows).map(r => Array.from(r.cells).map(c => c.textContent));
    headers[key] = Array.from(t.tHead.rows[0].cells).map(c => c.firstChild.textContent);
    units[key] = Array.from(t.tHead.rows[0].cells).map(
      c => c.querySelector('.unit') ? c.querySelector('.unit').textContent.trim() : '');
  });
  return {
    svgs: svgs.map(s => ({
      figure: s.closest('figure') ? s.closest('figure').id : null,
      width: s.width.baseVal.value, height: s.height.baseVal.value,
      shown: s.getBoundingClientRect().width, texts: s.querySelectorAll('text').length,
    })),
    tables, headers, units,
    figures: Array.from(document.querySelectorAll('figure')).map(f => f.id),
    text: document.body.innerText,
  };
}"""


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    """A headless Chromium context with a fresh profile (skipped without Chromium)."""
    if not Path(CHROMIUM).exists():
        pytest.skip(f"Chromium not found at {CHROMIUM}: apt-get install chromium")
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1100, "height": 900},
        )
        yield context
        context.close()


def inspect(browser: Any, html: Path) -> PageReport:
    """Load ``html`` from disk and report console errors, requests, images and tables."""
    page = browser.new_page()
    errors: list[str] = []
    requests: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(html.resolve().as_uri(), wait_until="load")
    found = page.evaluate(INSPECT)
    page.close()
    return PageReport(
        errors,
        [u for u in requests if not u.startswith("data:")],
        found["svgs"],
        found["tables"],
        found["headers"],
        found["units"],
        found["figures"],
        found["text"],
    )


def assert_self_contained(report: PageReport, html: Path) -> None:
    """No console error, nothing fetched but the page, every figure an inline SVG that is
    shown and has text (its axes' labels)."""
    assert report.console_errors == []
    assert report.requests == [html.resolve().as_uri()]
    source = html.read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", source)
    assert "<script" not in source and "<img" not in source
    # only an SVG's own clip paths and the fonts inline
    assert not re.search(r"url\((?!#|data:font/ttf;base64,)", source)
    ids = re.findall(r'\sid="([^"]+)"', source)
    assert len(ids) == len(set(ids)), "ids repeat: figures share one page"
    assert report.svgs, "no figures"
    for svg in report.svgs:
        assert svg["figure"], svg
        assert svg["width"] > 100 and svg["height"] > 100, svg
        assert svg["shown"] > 100 and svg["texts"] > 0, svg


@dataclass
class PdfPage:
    pixels: np.ndarray
    """RGB, uint8, rendered at PDF_DPI"""
    words: list[tuple[str, float, float, float, float]]
    """(word, x0, y0, x1, y1) in points from the top-left corner"""

    def region(self, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
        s = PDF_DPI / 72.0
        return self.pixels[int(y0 * s) : int(y1 * s), int(x0 * s) : int(x1 * s)]


def pdf_pages(pdf: Path, tmp: Path) -> list[PdfPage]:
    """Every page of ``pdf`` rasterised with pdftoppm, with its words from pdftotext."""
    for tool in ("pdftoppm", "pdftotext"):
        if shutil.which(tool) is None:
            pytest.skip(f"{tool} not found: apt-get install poppler-utils")
    prefix = tmp / "page"
    subprocess.run(["pdftoppm", "-r", str(PDF_DPI), "-png", str(pdf), str(prefix)], check=True)
    bbox = subprocess.run(
        ["pdftotext", "-bbox", str(pdf), "-"], check=True, capture_output=True, text=True
    ).stdout
    word = re.compile(
        r'<word xMin="([\d.]+)" yMin="([\d.]+)" xMax="([\d.]+)" yMax="([\d.]+)">([^<]*)</word>'
    )
    pages_words = [
        [(m[4], float(m[0]), float(m[1]), float(m[2]), float(m[3])) for m in word.findall(page)]
        for page in bbox.split("<page ")[1:]
    ]
    images = sorted(tmp.glob("page-*.png"), key=lambda p: int(p.stem.rsplit("-", 1)[1]))
    assert len(images) == len(pages_words)
    return [
        PdfPage(np.asarray(Image.open(p).convert("RGB")), w)
        for p, w in zip(images, pages_words, strict=True)
    ]


def pdf_images(pdf: Path) -> list[tuple[int, int]]:
    """(width, height) in pixels of every image ``pdf`` embeds, in order (pdfimages)."""
    if shutil.which("pdfimages") is None:
        pytest.skip("pdfimages not found: apt-get install poppler-utils")
    listing = subprocess.run(
        ["pdfimages", "-list", str(pdf)], check=True, capture_output=True, text=True
    ).stdout
    rows = [line.split() for line in listing.splitlines()[2:] if line.strip()]
    return [(int(r[3]), int(r[4])) for r in rows if r[2] == "image"]


def html_figure_sizes(html: Path) -> list[tuple[float, float]]:
    """(width, height) in points of every figure of a report's HTML, in order."""
    return [
        (float(w), float(h))
        for w, h in re.findall(
            r'<figure[^>]*><svg[^>]* width="([\d.]+)pt" height="([\d.]+)pt"', html.read_text()
        )
    ]


def ink(pixels: np.ndarray) -> float:
    """Share of pixels that are not (near) white."""
    return float((pixels.min(axis=2) < 235).mean())


def colour(pixels: np.ndarray) -> float:
    """Share of clearly coloured pixels (plot lines and markers; text is grey or black)."""
    spread = pixels.max(axis=2).astype(int) - pixels.min(axis=2).astype(int)
    return float((spread > 60).mean())


def figure_regions(pages: list[PdfPage]) -> dict[int, np.ndarray]:
    """Figure number → the page area just above its caption (where the figure is drawn)."""
    found = {}
    for page in pages:
        for k, (text, x0, y0, _, _) in enumerate(page.words[:-1]):
            number = page.words[k + 1][0]
            if text == "Figure" and re.fullmatch(r"\d+\.", number) and x0 < 60:
                found[int(number[:-1])] = page.region(60, max(y0 - 150, 40), 535, y0 - 6)
    return found


MARKS = """() => {
  const out = {};
  document.querySelectorAll('table').forEach((t, k) => {
    const key = t.classList[0] + (out[t.classList[0]] ? '-' + k : '');
    out[key] = Array.from(t.tBodies[0].rows).map(r => ({
      row: r.classList.contains('marked'),
      cells: Array.from(r.cells).map(c => c.classList.contains('flag')),
      colours: Array.from(r.cells).map(c => getComputedStyle(c).backgroundColor),
    }));
  });
  return out;
}"""


@dataclass
class RowMarks:
    row: bool
    """the whole row is highlighted (the station failed a QC check)"""
    cells: list[bool]
    """per cell: highlighted on its own (a value a processing flag applies to)"""
    colours: list[str]
    """per cell: the background colour Chromium computed"""


def marks(browser: Any, html: Path) -> dict[str, list[RowMarks]]:
    """Per table (keyed as in :class:`PageReport`), what is highlighted in each row."""
    page = browser.new_page()
    page.goto(html.resolve().as_uri(), wait_until="load")
    found = page.evaluate(MARKS)
    page.close()
    return {k: [RowMarks(r["row"], r["cells"], r["colours"]) for r in v] for k, v in found.items()}


def figure_svg(html: Path, key: str) -> str:
    """The SVG source of figure ``key`` of a report (inline in its HTML)."""
    source = html.read_text(encoding="utf-8")
    found = re.search(rf'<figure id="fig-{re.escape(key)}"[^>]*>(<svg.*?</svg>)', source, re.S)
    assert found, f"figure {key} is not an SVG"
    return found[1]


BOXES = """selectors => selectors.map(s => Array.from(document.querySelectorAll(s))
  .map(e => { const b = e.getBoundingClientRect();
              return {x0: b.left, y0: b.top, x1: b.right, y1: b.bottom}; }))"""


def svg_boxes(browser: Any, svg: str, selectors: list[str]) -> list[list[dict[str, float]]]:
    """Per CSS selector, the screen boxes of the SVG elements it matches, as Chromium lays
    the SVG out."""
    page = browser.new_page()
    page.set_content(svg)
    found: list[list[dict[str, float]]] = page.evaluate(BOXES, selectors)
    page.close()
    return found


def overlap(a: dict[str, float], b: dict[str, float]) -> bool:
    """True if two boxes share area."""
    return a["x0"] < b["x1"] and b["x0"] < a["x1"] and a["y0"] < b["y1"] and b["y0"] < a["y1"]


def svg_texts(browser: Any, svg: str, selector: str) -> list[str]:
    """Text content of the SVG elements matching ``selector``."""
    page = browser.new_page()
    page.set_content(svg)
    found: list[str] = page.evaluate(
        "s => Array.from(document.querySelectorAll(s)).map(e => e.textContent)", selector
    )
    page.close()
    return found


FLAGGED_RGB = (252, 235, 192)
"""Background of a highlighted cell (the CSS and the PDF use the same colour)."""


def flagged_share(pixels: np.ndarray) -> float:
    """Share of pixels of a highlighted cell's background colour."""
    distance = np.abs(pixels.astype(int) - np.array(FLAGGED_RGB)).max(axis=2)
    return float((distance <= 10).mean())


def line_words(page: PdfPage, first: str) -> list[tuple[str, float, float, float, float]]:
    """The words on the PDF line that starts with the word ``first`` (a table row that
    starts with it in its first column, left of 80 pt)."""
    start = next(w for w in page.words if w[0] == first and w[1] < 80)
    return sorted(
        (w for w in page.words if abs(w[2] - start[2]) < 1.0 and w[1] >= start[1] - 1),
        key=lambda w: w[1],
    )


def pdf_text(pdf: Path) -> list[str]:
    """The text of each page of ``pdf`` (pdftotext, layout kept)."""
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext not found: apt-get install poppler-utils")
    text = subprocess.run(
        ["pdftotext", "-layout", str(pdf), "-"], check=True, capture_output=True, text=True
    ).stdout
    return text.split("\f")


SIGNERS = ("Prepared by", "Checked by", "Approved by")


def assert_signoff_before_appendix(browser: Any, out: Path) -> None:
    """The report in ``out`` ends with a sign-off block (a row per signer, blank name,
    signature and date to write on), then the provenance appendix — in the HTML (Chromium)
    and in the PDF's text (issue 28 item 9)."""
    html = inspect(browser, out / "report.html")
    assert html.headers["signoff"] == ["Role", "Name", "Signature", "Date"]
    assert [row[0] for row in html.tables["signoff"]] == list(SIGNERS)
    assert all(set(cell) == {"_"} for row in html.tables["signoff"] for cell in row[1:])
    text = html.text
    assert text.rindex("Sign-off") < text.rindex("Appendix: provenance")
    assert text.rindex("Approved by") < text.index("Input files")

    whole = "\f".join(pdf_text(out / "report.pdf"))
    signoff = whole.rindex("Sign-off")
    assert whole.index("Appendix: provenance") > signoff
    lines = whole[signoff:].splitlines()
    assert any(line.split()[:4] == ["Role", "Name", "Signature", "Date"] for line in lines)
    for role in SIGNERS:
        assert any(re.fullmatch(rf"{role}(\s+_{{8,}}){{3}}", line.strip()) for line in lines), role


_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
_WHITE = np.array([0.95047, 1.0, 1.08883])
DICHROMACY = {
    "normal": np.eye(3),
    "deuteranopia": np.array(
        [
            [0.367322, 0.860646, -0.227968],
            [0.280085, 0.672501, 0.047413],
            [-0.01182, 0.04294, 0.968881],
        ]
    ),
    "protanopia": np.array(
        [
            [0.152286, 1.052583, -0.204868],
            [0.114503, 0.786281, 0.099216],
            [-0.003882, -0.048116, 1.051998],
        ]
    ),
    "tritanopia": np.array(
        [
            [1.255528, -0.076749, -0.178779],
            [-0.078411, 0.930809, 0.147602],
            [0.004733, 0.691367, 0.3039],
        ]
    ),
}
"""Colour vision → its matrix on linear sRGB (Machado, Oliveira & Fernandes 2009, severity 1)."""


def lab(hex_colour: str, vision: str = "normal") -> np.ndarray:
    """CIELAB (D65) of an sRGB ``#rrggbb`` as seen with ``vision`` (:data:`DICHROMACY`)."""
    srgb = np.array([int(hex_colour[i : i + 2], 16) for i in (1, 3, 5)]) / 255
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    xyz = _TO_XYZ @ np.clip(DICHROMACY[vision] @ linear, 0, 1) / _WHITE
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def closest_colours(colours: list[str], vision: str) -> float:
    """The smallest CIE76 colour difference ΔE between two of ``colours`` seen with
    ``vision`` (ΔE ≈ 2.3: just noticeable; above ~10: told apart at a glance)."""
    seen = [lab(c, vision) for c in colours]
    return min(float(np.linalg.norm(a - b)) for i, a in enumerate(seen) for b in seen[i + 1 :])
