"""docs/batch.md against a real batch: the ledger columns it documents are the ledger's, its
SQL queries run and find rows, and its log fields are those the batch writes."""

from __future__ import annotations

import hashlib
import re
import sqlite3
from pathlib import Path

from batch_support import corrupt, log_events, make_wells

from tests_support import ROOT, gyropipe_cli

DOC = (ROOT / "docs" / "batch.md").read_text()


def section(heading: str) -> str:
    """The text under the markdown heading ``heading`` up to the next heading."""
    start = DOC.index(f"\n{heading}\n")
    following = re.search(r"\n#+ ", DOC[start + len(heading) + 2 :])
    end = start + len(heading) + 2 + following.start() if following else len(DOC)
    return DOC[start:end]


def first_cells(text: str) -> list[str]:
    """The back-quoted first cells of a markdown table's body rows."""
    return re.findall(r"^\| `(\w+)` \|", text, flags=re.MULTILINE)


def test_the_operator_guide_matches_a_real_ledger_and_log(tmp_path: Path, survey: Path):
    paths = make_wells(tmp_path / "in", ["A", "B", "C"])
    corrupt(paths[2])
    out = tmp_path / "out"
    result = gyropipe_cli(
        "batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out, "--quiet"
    )
    assert result.returncode == 1, result.output  # C fails, A and B are done
    with sqlite3.connect(out / "ledger.sqlite") as db:
        for table in ("runs", "batches", "file_hashes"):
            columns = [row[1] for row in db.execute(f"PRAGMA table_info({table})")]
            assert first_cells(section(f"### {table}")) == columns, table
        sha256 = hashlib.sha256((tmp_path / "in" / "A.csv").read_bytes()).hexdigest()
        params = {"sha256": sha256, "well": "A"}
        queries = re.findall(r"```sql\n(.*?)```", section("### Queries"), flags=re.DOTALL)
        assert len(queries) == 4
        for query in queries:
            rows = db.execute(query, params).fetchall()
            assert rows, query
    logged = {e["event"]: set(e) - {"time", "event"} for e in log_events(result.stderr)}
    documented = {
        event: set(re.findall(r"`(\w+)`", fields))
        for event, fields in re.findall(r"^\| `(\w+)` \| (.*) \|$", section("## The log"), re.M)
    }
    assert documented.keys() - logged.keys() == {"note"}  # no well waited for another batch
    for event, fields in logged.items():
        assert documented[event] == fields, event
