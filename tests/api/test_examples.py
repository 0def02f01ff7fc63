"""The Python walk-through (examples/notebook.ipynb) and the README's Python example run as
written: every code cell in order in one namespace, from a copy of the examples directory."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from pipeline.reports.charts.drawing import Drawing
from tests_support import ROOT


def cells(notebook: Path) -> list[str]:
    document = json.loads(notebook.read_text())
    return ["".join(c["source"]) for c in document["cells"] if c["cell_type"] == "code"]


def readme_python() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("```python\nimport pipeline as gp")
    return text[start + len("```python\n") : text.index("```", start + 10)]


@pytest.fixture
def examples(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of examples/ (plans, samples) as the working directory."""
    root = tmp_path / "examples"
    shutil.copytree(ROOT / "examples", root, ignore=shutil.ignore_patterns("report"))
    shutil.copytree(ROOT / "pipelines", tmp_path / "pipelines")
    monkeypatch.chdir(root)
    return root


def test_notebook_runs(examples: Path) -> None:
    namespace: dict[str, object] = {}
    last = None
    for number, source in enumerate(cells(examples / "notebook.ipynb"), 1):
        code = compile(source, f"notebook cell {number}", "exec")
        exec(code, namespace)
        *_, last = source.strip().splitlines()
        if last.startswith("gp.plot_"):
            drawing = eval(last, namespace)
            assert isinstance(drawing, Drawing)
            assert drawing._repr_svg_().startswith("<svg")  # what Jupyter shows
    assert sorted(p.name for p in (examples / "out").iterdir()) == [
        "samples.parquet",
        "short-j-well.html",
        "short-j-well.pdf",
    ]
    trajectory = namespace["trajectory"]
    assert len(trajectory) == 10  # type: ignore[arg-type]  # stations 0, 100, …, 900 m
    assert "Short J well" in (examples / "out" / "short-j-well.html").read_text()


def test_readme_python_example_runs(examples: Path) -> None:
    namespace: dict[str, object] = {}
    exec(compile(readme_python(), "README.md", "exec"), namespace)
    assert (examples / "out" / "short-j-well.html").is_file()
    result = namespace["result"]
    assert "trajectory.trajectory" in result.tables  # type: ignore[attr-defined]
