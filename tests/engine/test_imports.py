"""What a gyropipe process imports (#19 target 2): ``gyropipe --help`` only click and the
standard library; a run only what its stages use. Each case is a real ``gyropipe`` process
that writes ``sys.modules`` at exit; no timings."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tests_support import ROOT, pythonpath, without_report

pytestmark = pytest.mark.process("what a fresh interpreter imports")

SCRIPT = """
import atexit, sys
out = sys.argv.pop(1)
atexit.register(lambda: open(out, "w").write("\\n".join(sorted(sys.modules))))
sys.argv[0] = "gyropipe"
from pipeline.cli import main
main()
"""

HEAVY = ("numpy", "pyarrow", "pydantic", "pandas", "scipy", "matplotlib", "dask", "pint")


def modules_of(tmp_path: Path, *args: str) -> set[str]:
    """The modules loaded by the end of ``gyropipe ARGS`` (this tree's sources)."""
    listing = tmp_path / "modules.txt"
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(listing), *args],
        env=pythonpath(ROOT / "src"),
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    return set(listing.read_text().split())


def loaded(modules: set[str], package: str) -> bool:
    return package in modules or any(m.startswith(f"{package}.") for m in modules)


def test_help_imports_click_and_the_standard_library_only(tmp_path: Path):
    modules = modules_of(tmp_path, "--help")
    assert [p for p in HEAVY if loaded(modules, p)] == []
    assert "importlib.metadata" not in modules
    assert sorted(m for m in modules if loaded({m}, "pipeline")) == [
        "pipeline",
        "pipeline.cli",
        "pipeline.cli_args",
        "pipeline.cli_models",
        "pipeline.errors",
        "pipeline.lazy",
        "pipeline.version",
    ]
    assert "click" in modules


@pytest.fixture(scope="module")
def survey_modules(tmp_path_factory: pytest.TempPathFactory) -> set[str]:
    """A survey-only run (pipelines/survey.yaml without its report stage) of the bundled
    stations, given as Parquet."""
    tmp = tmp_path_factory.mktemp("survey-imports")
    stations = tmp / "stations.parquet"
    subprocess.run(
        [
            sys.executable,
            "-c",
            SCRIPT,
            str(tmp / "unused.txt"),
            "convert",
            str(ROOT / "examples" / "stations-j-well.csv"),
            str(stations),
        ],
        env=pythonpath(ROOT / "src"),
        check=True,
        capture_output=True,
    )
    pipeline = without_report("survey", tmp)
    return modules_of(tmp, "run", str(pipeline), "--input", str(stations), "--out", "out")


def test_survey_run_imports_no_plotting_and_no_cluster(survey_modules: set[str]):
    """No matplotlib, no dask (pint would load it), no report modules, and no pandas
    (pyarrow would import it on its first array conversion: pipeline.lazy_pandas)."""
    for package in ("matplotlib", "dask", "pipeline.reports", "allantools", "pandas"):
        assert not loaded(survey_modules, package), package
    assert "pipeline.survey.mincurve" in survey_modules  # the run did run


def test_survey_run_imports_no_scipy_stats(survey_modules: set[str]):
    assert not loaded(survey_modules, "scipy.stats")


def test_continuous_run_without_report_imports_no_plotting(tmp_path: Path):
    """The continuous pipeline without its report stage (issue #20's floor: interpreter and
    the libraries of its stages) loads no matplotlib, no report modules, no dask, and no
    SciPy (its filters are NumPy's: pipeline.continuous.filters), no pandas."""
    sim = tmp_path / "sim"
    plan = yaml.safe_load((ROOT / "examples" / "plans" / "j-well-continuous.yaml").read_text())
    plan["survey"].update(start_md=600, end_md=640)
    (tmp_path / "plan.yaml").write_text(yaml.safe_dump(plan))
    simulated = modules_of(tmp_path, "simulate", str(tmp_path / "plan.yaml"), "--out", str(sim))
    assert not loaded(simulated, "pandas") and "pipeline.sim.sensors" in simulated
    pipeline = without_report("continuous-gyro", tmp_path)
    samples = str(sim / "samples.parquet")
    modules = modules_of(tmp_path, "run", str(pipeline), "--input", samples, "--out", "out")
    for package in ("matplotlib", "dask", "pipeline.reports", "allantools", "scipy", "pandas"):
        assert not loaded(modules, package), package
    assert "pipeline.continuous.integrate" in modules  # the run did integrate


def test_run_with_its_report_imports_no_matplotlib(tmp_path: Path):
    """The survey pipeline with its report stage: the report's figures are drawn by the
    report package's own vector renderer, so neither matplotlib nor Pillow is loaded (and
    the fonts are read from the package, fontTools' subsetter not even imported); the
    report's tables need no pandas either."""
    modules = modules_of(
        tmp_path,
        "run",
        str(ROOT / "pipelines" / "survey.yaml"),
        "--input",
        str(ROOT / "examples" / "stations-j-well.csv"),
        "--out",
        "out",
    )
    assert (tmp_path / "out" / "report.html").is_file() and (
        tmp_path / "out" / "report.pdf"
    ).is_file()
    assert "pipeline.reports.charts.svg" in modules and "pipeline.reports.charts.pdf" in modules
    for package in ("matplotlib", "PIL", "fontTools.subset", "pandas"):
        assert not loaded(modules, package), package


def test_python_m_pipeline_cli_is_the_command(tmp_path: Path):
    """``python -m pipeline.cli`` runs the command (it printed nothing and exited 0)."""
    done = subprocess.run(
        [sys.executable, "-m", "pipeline.cli", "validate", str(tmp_path / "none.yaml")],
        env=pythonpath(ROOT / "src"),
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert done.returncode == 2
    assert "none.yaml" in done.stderr
