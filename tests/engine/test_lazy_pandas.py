"""pyarrow without pandas until something imports pandas (pipeline.lazy_pandas): a process
that deferred pandas converts pandas objects exactly as a plain process does, once pandas is
imported by anyone; before that, pyarrow's conversions leave pandas unimported. Each case is
its own Python process (the deferral is process state); the plain process is the peer."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests_support import ROOT, pythonpath

pytestmark = pytest.mark.process("the pandas deferral is the state of a fresh interpreter")

CONVERSIONS = """
import json, sys
import numpy as np, pyarrow as pa, pyarrow.compute as pc

def arrow_facts():
    import pandas as pd
    frame = pd.DataFrame({
        "x": [1.0, np.nan, 3.0],
        "when": pd.date_range("2026-01-01", periods=3, tz="UTC"),
        "kind": pd.Categorical(["a", "b", "a"]),
        "n": pd.array([1, None, 3], dtype="Int64"),
    })
    facts = {
        "series": [str(pa.array(frame["x"]).type), pa.array(frame["x"]).null_count],
        "categorical": str(pa.array(frame["kind"]).type),
        "datetimetz": str(pa.array(frame["when"]).type),
        "nullable int": [str(pa.array(frame["n"]).type), pa.array(frame["n"]).null_count],
        "index": str(pa.array(pd.Index([1.5, 2.5])).type),
        "chunked series": pa.chunked_array([frame["x"]]).null_count,
        "from_pandas ndarray": pa.array(np.array([1.0, np.nan]), from_pandas=True).null_count,
    }
    table = pa.Table.from_pandas(frame)  # (pyarrow's explicit pandas use: after the checks)
    facts |= {
        "schema": table.schema.remove_metadata().to_string(),
        "pandas metadata": sorted(json.loads(table.schema.metadata[b"pandas"])),
        "round trip": {k: str(v) for k, v in table.to_pandas().dtypes.items()},
    }
    return facts

def survey_conversions():
    values = np.linspace(0.0, 1.0, 5)
    array = pa.array(values)
    array.to_numpy()
    pa.scalar(1.0)
    pa.table({"md": values, "flag": np.array([True, False, True, False, True])})
    pc.multiply(array, 0.3048).to_numpy()
    pa.chunked_array([array]).to_numpy()
"""


def probe(code: str) -> dict[str, object]:
    """Run ``code`` after :data:`CONVERSIONS` in a fresh interpreter; its JSON output."""
    done = subprocess.run(
        [sys.executable, "-c", CONVERSIONS + code],
        env=pythonpath(ROOT / "src"),
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    result: dict[str, object] = json.loads(done.stdout)
    return result


@pytest.fixture(scope="module")
def plain() -> dict[str, object]:
    """A process that never deferred pandas."""
    return probe("survey_conversions(); print(json.dumps(arrow_facts()))")


def test_deferred_then_imported_converts_as_a_plain_process(plain: dict[str, object]):
    got = probe(
        "from pipeline.lazy_pandas import defer_pandas\n"
        "defer_pandas()\n"
        "survey_conversions()\n"
        "before = 'pandas' in sys.modules\n"
        "facts = arrow_facts()\n"
        "finders = [type(f).__name__ for f in sys.meta_path]\n"
        "print(json.dumps({'before': before, 'facts': facts, 'finders': finders}))"
    )
    assert got["before"] is False
    assert got["facts"] == plain
    assert "_Announce" not in got["finders"] and "_HeldBack" not in got["finders"]
    assert plain["series"] == ["double", 1]  # NaN of a Series is null, as pandas means it
    assert plain["categorical"].startswith("dictionary<")  # type: ignore[union-attr]


def test_pandas_imported_by_pyarrow_itself_after_deferring(plain: dict[str, object]):
    """``to_pandas`` imports pandas through pyarrow, not through ``import pandas``."""
    got = probe(
        "from pipeline.lazy_pandas import defer_pandas\n"
        "defer_pandas()\n"
        "survey_conversions()\n"
        "frame = pa.table({'x': [1.0, 2.0]}).to_pandas()\n"
        "print(json.dumps({'sum': float(frame['x'].sum()), 'facts': arrow_facts()}))"
    )
    assert got == {"sum": 3.0, "facts": plain}


def test_deferring_after_pandas_was_imported_changes_nothing(plain: dict[str, object]):
    got = probe(
        "import pandas\n"
        "from pipeline.lazy_pandas import defer_pandas\n"
        "defer_pandas()\n"
        "finders = [type(f).__name__ for f in sys.meta_path]\n"
        "survey_conversions()\n"
        "print(json.dumps({'facts': arrow_facts(), 'finders': finders}))"
    )
    assert got["facts"] == plain
    assert "_Announce" not in got["finders"]  # type: ignore[operator]


def test_a_batch_worker_defers_pandas(tmp_path):
    """The process-pool initialiser defers pandas before the worker's first well."""
    pipeline = ROOT / "pipelines" / "survey.yaml"
    got = probe(
        "import os\n"
        "from pipeline.batch.worker import worker_init\n"
        "from pipeline.executing import PipelineRef\n"
        "from pipeline.spec import load_spec\n"
        f"worker_init(PipelineRef({str(pipeline)!r}, load_spec({str(pipeline)!r}).spec), "
        "os.getpid())\n"
        "survey_conversions()\n"
        "print(json.dumps({'pandas': 'pandas' in sys.modules}))"
    )
    assert got == {"pandas": False}
