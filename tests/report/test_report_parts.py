"""Report parts from a plugin, end to end: a real plugin module found through its entry point
adds a stage that states its method (cited by its paper) and a whole section (a paragraph,
a table with units, a figure), and `gyropipe run` (in process) puts both in the HTML — parsed
and in Chromium — and in the PDF (pdftotext). A plugin whose section raises fails the report
with one line naming the plugin; one that registers an empty part is reported by name; the
calibration report takes plugin sections too."""

from __future__ import annotations

import re
import subprocess
from collections.abc import Iterator
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
import yaml
from report_support import assert_self_contained, inspect

from pipeline.plugins import forget_shared_registries
from tests_support import ROOT, CliResult, gyropipe_cli, plugin_site

TORTUOSITY = """
from pipeline.plugin import (
    MethodNote, ReportDef, ReportFigure, ReportLine, ReportSection, ReportTable, StageDef,
    Trajectory, hookimpl,
)
from pydantic import BaseModel

PAPER = ("Gaynor T. M., Chen D. C.-K., Stuart D., Comeaux B. Tortuosity versus "
         "micro-tortuosity: why little things mean a lot. SPE/IADC Drilling Conference, "
         "Amsterdam, 27 February – 1 March 2001 (SPE 67818).")


class Params(BaseModel):
    interval: float = 300.0


def passthrough(inputs, params, ctx):
    return {"trajectory": inputs["trajectory"]}


def method(stage, ctx):
    return MethodNote("Tortuosity", f"cumulative dogleg per {stage.params['interval']:g} m "
                      f"of hole {ctx.cite(PAPER)}")


def section(ctx):
    if ctx.document != "survey":
        return None
    table = ctx.tables["trajectory"]
    md = table.column("md").to_pylist()
    dls = table.column("dls").to_pylist()
    rows, cumulative, total = [], [], 0.0
    for top, base, rate in zip(md, md[1:], dls[1:]):
        total += rate * (base - top) / 30.0
        cumulative.append(total)
    for k in range(0, len(cumulative), 10):
        rows.append((f"{md[k + 1]:.1f}", f"{cumulative[k]:.2f}"))
    return ReportSection(
        "Tortuosity",
        paragraphs=(f"Cumulative dogleg over the well, after {ctx.cite(PAPER)}: "
                    f"{total:.2f}° at TD of {ctx.well.well}.",),
        tables=(ReportTable("Cumulative dogleg", (("MD", "m"), ("Cumulative dogleg", "°")),
                            tuple(rows), note="every tenth course"),),
        figure=ReportFigure("Cumulative dogleg against MD", "Sum of the course doglegs.",
                            "MD (m)", "Cumulative dogleg (°)",
                            (ReportLine("cumulative", md[1:], cumulative),)),
    )


@hookimpl
def gyropipe_register_stages(register):
    register(StageDef("tortuosity.mark", passthrough, "passes the trajectory on",
                      inputs={"trajectory": Trajectory}, outputs={"trajectory": Trajectory},
                      params=Params))


def series_section(ctx):
    if ctx.document != "calibration":
        return None
    return ReportSection("Series seen", paragraphs=(
        f"{ctx.tables['series'].num_rows} calibration series reached this section.",))


@hookimpl
def gyropipe_register_report_parts(register):
    register(ReportDef("tortuosity.mark", method=method))
    register(ReportDef("tortuosity.section", section=section))
    register(ReportDef("tortuosity.series", section=series_section))
"""

BROKEN = """
from pipeline.plugin import ReportDef, hookimpl


def section(ctx):
    raise RuntimeError("no tortuosity today")


@hookimpl
def gyropipe_register_report_parts(register):
    register(ReportDef("brokensection.oops", section=section))
    register(ReportDef("brokensection.empty"))
"""

PLUGINS = {"tortuosity": ("0.2.0", TORTUOSITY), "brokensection": ("0.0.1", BROKEN)}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory holding the plugin modules and their dist-info entry points."""
    return plugin_site(tmp_path_factory.mktemp("site"), PLUGINS)


@pytest.fixture
def plugged(site: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The plugins installed for this test (on ``sys.path``; the process's registries are
    loaded afresh on entry and on exit, so no other test sees them)."""
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.chdir(ROOT)
    forget_shared_registries()
    yield
    forget_shared_registries()


def gyropipe(*args: str) -> CliResult:
    return gyropipe_cli(*args, cwd=Path.cwd())


def pipeline_with_tortuosity(directory: Path) -> Path:
    """pipelines/survey.yaml with the plugin's stage between the trajectory and the report."""
    spec = yaml.safe_load((ROOT / "pipelines" / "survey.yaml").read_text())
    report = next(s for s in spec["stages"] if s["uses"] == "report")
    at = spec["stages"].index(report)
    spec["stages"].insert(
        at,
        {
            "id": "tortuosity",
            "uses": "tortuosity.mark",
            "inputs": {"trajectory": "trajectory.trajectory"},
            "with": {"interval": 100.0},
        },
    )
    report["inputs"]["trajectory"] = "tortuosity.trajectory"
    path = directory / "survey-tortuosity.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


class Sections(HTMLParser):
    """Each ``<section>``'s id → its text (tags dropped, style and SVG text left out)."""

    def __init__(self) -> None:
        super().__init__()
        self.found: dict[str, list[str]] = {}
        self.current: str | None = None
        self.skip = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "section":
            self.current = dict(attrs).get("id") or ""
            self.found[self.current] = []
        self.skip += tag in ("style", "svg")

    def handle_endtag(self, tag: str) -> None:
        self.skip -= tag in ("style", "svg")
        self.current = None if tag == "section" else self.current

    def handle_data(self, data: str) -> None:
        if self.current is not None and not self.skip:
            self.found[self.current].append(data)


def sections_of(html: Path) -> dict[str, str]:
    parser = Sections()
    parser.feed(html.read_text(encoding="utf-8"))
    return {key: " ".join(" ".join(text).split()) for key, text in parser.found.items()}


@pytest.fixture(scope="module")
def report(site: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The survey report of a run with the tortuosity plugin (the broken one disabled)."""
    out = tmp_path_factory.mktemp("parts")
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(site))
        mp.chdir(ROOT)
        done = gyropipe(
            "run",
            str(pipeline_with_tortuosity(out)),
            "--input",
            "examples/stations-j-well.csv",
            "--out",
            str(out / "run"),
            "--disable-plugin",
            "brokensection",
        )
    assert done.returncode == 0, done.output
    return out / "run"


PAPER = "Tortuosity versus micro-tortuosity: why little things mean a lot"


def test_the_plugins_section_and_method_are_in_the_html(report: Path) -> None:
    found = sections_of(report / "report.html")
    keys = list(found)
    assert keys[-3:] == ["part-tortuosity-section", "signoff", "provenance"]  # before sign-off
    section = found["part-tortuosity-section"]
    assert section.startswith("7. Tortuosity Cumulative dogleg over the well, after [1]: ")
    assert "at TD of J-12." in section
    assert "Cumulative dogleg MD m Cumulative dogleg ° " in section  # headers with units
    assert "every tenth course" in section
    assert "Figure 6. Cumulative dogleg against MD" in section
    method = found["method"]
    assert "Tortuosity cumulative dogleg per 100 m of hole [1]" in method
    assert f"[1] Gaynor T. M., Chen D. C.-K., Stuart D., Comeaux B. {PAPER}" in method
    for client_text in (method, section):  # internal names stay in Provenance
        assert "tortuosity.mark" not in client_text and "interval" not in client_text


def test_the_plugins_section_shows_in_chromium(report: Path, browser: Any) -> None:
    html = report / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    assert page.figures[-1] == "fig-part-tortuosity-section"
    assert page.headers["part"] == ["MD", "Cumulative dogleg"]
    assert page.units["part"] == ["m", "°"]
    rows = page.tables["part"]
    assert rows[0][0] == "30.0" and len(rows) >= 3
    assert all(re.fullmatch(r"\d+\.\d\d", r[1]) for r in rows)
    cumulative = [float(r[1]) for r in rows]
    assert cumulative == sorted(cumulative) and cumulative[-1] > 0


def test_the_plugins_section_is_in_the_pdf(report: Path) -> None:
    text = subprocess.run(
        ["pdftotext", str(report / "report.pdf"), "-"], capture_output=True, text=True, check=True
    ).stdout
    flat = " ".join(text.split())
    assert "7. Tortuosity" in flat
    assert "Cumulative dogleg over the well, after [1]:" in flat
    assert "every tenth course" in flat
    assert "Figure 6. Cumulative dogleg against MD" in flat
    assert "cumulative dogleg per 100 m of hole [1]" in flat
    assert PAPER in flat
    assert flat.index("7. Tortuosity") < flat.index("8. Sign-off")


def test_a_raising_section_fails_the_report_naming_its_plugin(
    plugged: None, tmp_path: Path
) -> None:
    done = gyropipe(
        "run",
        "pipelines/survey.yaml",
        "--input",
        "examples/stations-j-well.csv",
        "--out",
        str(tmp_path / "run"),
    )
    assert done.returncode != 0
    lines = [line for line in done.output.splitlines() if "no tortuosity today" in line]
    assert len(lines) == 1, done.output
    assert (
        "plugin brokensection 0.0.1: report part 'brokensection.oops': section raised "
        "RuntimeError: no tortuosity today"
    ) in lines[0]
    assert "Traceback" not in done.output
    assert not (tmp_path / "run" / "report.html").exists()


def test_an_empty_part_is_a_problem_of_its_plugin(plugged: None) -> None:
    done = gyropipe("plugins")
    assert done.returncode == 0, done.output
    assert (
        "problem: plugin brokensection 0.0.1: report part 'brokensection.empty': give a "
        "method or a section (or both)"
    ) in done.output
    assert "brokensection 0.0.1 (third-party): report:brokensection.oops" in done.output
    assert (
        "tortuosity 0.2.0 (third-party): stage:tortuosity.mark, report:tortuosity.mark, "
        "report:tortuosity.section, report:tortuosity.series"
    ) in done.output


def test_a_plugin_section_in_the_calibration_report(plugged: None, tmp_path: Path) -> None:
    """The calibration report takes plugin sections too: each part says for which document
    it has one (the survey section above is not in it)."""
    done = gyropipe(
        "run",
        "pipelines/calibration.yaml",
        "--input",
        "examples/calibration-ig50.csv",
        "--out",
        str(tmp_path / "run"),
        "--disable-plugin",
        "brokensection",
    )
    assert done.returncode == 0, done.output
    found = sections_of(tmp_path / "run" / "report.html")
    assert list(found)[-3:] == ["part-tortuosity-series", "signoff", "provenance"]
    series = pq.read_table(tmp_path / "run" / "drift.series.parquet").num_rows
    assert f"{series} calibration series reached this section." in found["part-tortuosity-series"]
    assert "part-tortuosity-section" not in found
