"""A survey report an operator can sign (issue 28 item 9): the job's header fields (service
company, tool, run and job number, survey type, CRS and map position, depth datum) shown when
given and only then, a sign-off block, and provenance (local paths, plugins) in an appendix
after it — in the HTML (Chromium) and in the PDF text."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from report_support import assert_signoff_before_appendix, inspect, pdf_text

from tests_support import ROOT, gyropipe_cli

SAMPLE = "examples/stations-j-well.csv"
GIVEN = {
    "service_company": "Acme Gyro Services",
    "tool_name": "NorthStar 48",
    "tool_serial": "NS-4471",
    "run_number": "3",
    "job_number": "JOB-2026-118",
    "survey_type": "definitive",
    "crs": "EPSG:23031",
    "easting": "431250.5",
    "northing": "6478512.25",
    "depth_reference": "RKB",
}
SHOWN = {
    "Service company": "Acme Gyro Services",
    "Tool": "NorthStar 48",
    "Tool serial": "NS-4471",
    "Run number": "3",
    "Job number": "JOB-2026-118",
    "Survey type": "definitive",
    "Coordinate system": "EPSG:23031",
    "Wellhead map position": "E 431250.50 m, N 6478512.25 m",
    "Depth datum": "RKB",
}


def _run(out: Path, *well: str) -> Path:
    args = [a for item in well for a in ("--well", item)]
    gyropipe_cli("run", "pipelines/survey.yaml", "--input", SAMPLE, "--out", out, *args, check=True)
    return out


class Runs(dict[str, Path]):
    """Output directories of survey.yaml on the sample, each run when first asked for:
    ``given`` with every header field, ``absent`` with none."""

    def __init__(self, work: Path) -> None:
        super().__init__()
        self.work = work

    def __missing__(self, name: str) -> Path:
        well = [f"{k}={v}" for k, v in GIVEN.items()] if name == "given" else []
        self[name] = _run(self.work / name, *well)
        return self[name]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Runs:
    return Runs(tmp_path_factory.mktemp("signable"))


def _pairs(text: str) -> dict[str, str]:
    """Label → value of the shown labels in a page laid out as text (a label, then two or
    more spaces, then its value, in either column of the header)."""
    found = {}
    for line in text.splitlines():
        for label in SHOWN:
            match = re.search(rf"(?:^|\s{{2}}){re.escape(label)}\s{{2,}}(\S.*?)(?:\s{{3}}|$)", line)
            if match:
                found.setdefault(label, match[1])
    return found


def test_header_fields_in_the_html_when_given(runs: Runs, browser: Any):
    given = inspect(browser, runs["given"] / "report.html").text
    well = given[given.index("Well and site") : given.index("Results")]
    for label, value in SHOWN.items():
        assert f"{label}\t{value}" in well or f"{label}\n{value}" in well, (label, well)
    absent = inspect(browser, runs["absent"] / "report.html").text
    absent = absent[absent.index("Well and site") : absent.index("Results")]
    for label in SHOWN:
        if label != "Tool":  # "Tool type" and "Tool and run" remain
            assert label not in absent, label
    assert "\nTool\n" not in absent and "\nTool\t" not in absent
    assert "Pipeline\t" not in well and "Pipeline\n" not in well  # in the appendix only


def test_header_fields_in_the_pdf_when_given(runs: Runs):
    first = pdf_text(runs["given"] / "report.pdf")[0]
    assert _pairs(first) == SHOWN
    absent = pdf_text(runs["absent"] / "report.pdf")[0]
    assert _pairs(absent) == {}


def test_signoff_block_then_provenance_appendix(runs: Runs, browser: Any):
    assert_signoff_before_appendix(browser, runs["absent"])


def test_first_pages_have_no_local_path_and_no_plugin_list(runs: Runs):
    pages = pdf_text(runs["absent"] / "report.pdf")
    assert len(pages) > 2
    appendix = next((i for i, p in enumerate(pages) if "Appendix: provenance" in p), 0)
    assert appendix >= 2
    assert SAMPLE in "".join(pages[appendix:]) and "Plugins loaded" in "".join(pages[appendix:])
    for page in pages[:2]:
        assert SAMPLE not in page and "stations-j-well.csv" not in page
        assert "survey.yaml" not in page and "Plugins loaded" not in page
        assert str(runs["absent"]) not in page


def test_header_fields_from_the_file_header(tmp_path: Path):
    """The same fields, given in a CSV title block (``Run number: 3``), reach the report."""
    title = {
        "Service company": "Acme Gyro Services",
        "Tool name": "NorthStar 48",
        "Tool serial": "NS-4471",
        "Run number": "3",
        "Job number": "JOB-2026-118",
        "Survey type": "definitive",
        "CRS": "EPSG:23031",
        "Easting": "431250.5",
        "Northing": "6478512.25",
        "Depth reference": "RKB",
    }
    sample = (ROOT / SAMPLE).read_text()
    stations = tmp_path / "stations.csv"
    stations.write_text("".join(f"{k}: {v}\n" for k, v in title.items()) + sample)
    gyropipe_cli(
        "run", "pipelines/survey.yaml", "--input", stations, "--out", tmp_path / "out", check=True
    )
    assert _pairs(pdf_text(tmp_path / "out" / "report.pdf")[0]) == SHOWN
