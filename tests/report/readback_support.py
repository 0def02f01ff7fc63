"""Every deliverable of a run read back without gyropipe's readers: the csv module for a CSV
export, a plain line parser for LAS 2.0, ``xml.etree`` for WITSML 1.4.1.1, pyarrow for
Parquet, the mcap library for ``processed.mcap``, regular expressions over report.html and
``pdftotext -layout`` for report.pdf. Each listing comes back as columns in the units the
file states, with those units, and each value's printed text where the file is text (its
decimals are the precision it states)."""

from __future__ import annotations

import csv
import html
import math
import re
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
from mcap.reader import make_reader

WITSML_NS = {"w": "http://www.witsml.org/schemas/1series"}
TO_CANONICAL = {
    "m": 1.0,
    "ft": 0.3048,
    "m2": 1.0,
    "ft2": 0.3048**2,
    "deg": 1.0,
    "dega": 1.0,
    "deg/30m": 1.0,
    "dega/30m": 1.0,
    "deg/100ft": 30.0 / 30.48,
    "dega/100ft": 30.0 / 30.48,
}
"""a unit a file states → the factor to the canonical m, m², deg, deg/30m (independent
of gyropipe's unit table: 1 ft = 0.3048 m exactly, 100 ft = 30.48 m)"""


@dataclass
class Column:
    """One column of a listing: its unit as the file states it, values in that unit (NaN:
    empty, null or left out) and, for text files, each value's text."""

    unit: str
    values: list[float] = field(default_factory=list)
    texts: list[str] = field(default_factory=list)

    def canonical(self) -> list[float]:
        """The values in m, m², deg or deg/30m."""
        factor = TO_CANONICAL[self.unit]
        return [v * factor for v in self.values]


@dataclass
class Listing:
    """A file's station listing and what its header states (key → text)."""

    header: dict[str, str]
    columns: dict[str, Column]


def _number(text: str) -> float:
    text = text.strip().replace("−", "-").replace(",", "")
    return math.nan if text in ("", "undefined") else float(text)


def read_csv(path: Path) -> Listing:
    """A gyropipe CSV export: ``# key=value`` comment lines, then ``name[unit]`` columns."""
    lines = path.read_text(encoding="utf-8").splitlines()
    header = dict(line[2:].split("=", 1) for line in lines if line.startswith("# ") and "=" in line)
    rows = list(csv.reader(line for line in lines if not line.startswith("#")))
    columns: dict[str, Column] = {}
    for i, name in enumerate(rows[0]):
        found = re.fullmatch(r"(.+?)(?:\[(.*)\])?", name)
        assert found, name
        texts = [row[i] for row in rows[1:]]
        column = Column(found.group(2) or "", texts=texts)
        if found.group(2) is not None:
            column.values = [_number(t) for t in texts]
        columns[found.group(1)] = column
    return Listing(header, columns)


def read_las(path: Path) -> Listing:
    """A LAS 2.0 file (unwrapped): the header lines of ``~W``/``~P`` as ``MNEM`` → value and
    ``MNEM.unit`` → unit, the curves of ``~C`` with their units, the ``~A`` data (NULL as
    NaN)."""
    header: dict[str, str] = {}
    curves: list[tuple[str, str]] = []
    data: list[list[str]] = []
    section = ""
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("~"):
            section = line[1].upper()
            continue
        if not line.strip() or line.startswith("#"):
            continue
        if section == "A":
            data.append(line.split())
            continue
        found = re.fullmatch(r"\s*([^.]+?)\s*\.(\S*)\s+(.*?)\s*:(.*)", line)
        if section in "WPC" and found:
            mnemonic, unit, value = found.group(1), found.group(2), found.group(3)
            if section == "C":
                curves.append((mnemonic, unit))
            else:
                header[mnemonic] = value
                header[f"{mnemonic}.unit"] = unit
    null = float(header["NULL"])
    columns = {}
    for i, (name, unit) in enumerate(curves):
        texts = [row[i] for row in data]
        values = [math.nan if float(t) == null else float(t) for t in texts]
        columns[name] = Column(unit, values, texts)
    return Listing(header, columns)


WITSML_STATION = {
    "md": "md",
    "tvd": "tvd",
    "incl": "inc",
    "azi": "azi",
    "dispNs": "north",
    "dispEw": "east",
    "vertSect": "vertical_section",
    "dls": "dls",
    "matrixCov/varianceNN": "cov_nn",
    "matrixCov/varianceNE": "cov_ne",
    "matrixCov/varianceNVert": "cov_nv",
    "matrixCov/varianceEE": "cov_ee",
    "matrixCov/varianceEVert": "cov_ev",
    "matrixCov/varianceVertVert": "cov_vv",
}
"""a WITSML 1.4.1.1 trajectoryStation's elements → the trajectory columns they state"""


def read_witsml(path: Path) -> Listing:
    """A WITSML 1.4.1.1 ``trajectorys`` file of one trajectory: its header elements (text),
    ``*.uom`` beside them, and its stations' elements (an element left out: NaN)."""
    (trajectory,) = ET.parse(path).getroot().findall("w:trajectory", WITSML_NS)
    header: dict[str, str] = dict(trajectory.attrib)
    for child in trajectory:
        tag = child.tag.split("}")[1]
        if tag != "trajectoryStation" and len(child) == 0:
            header[tag] = (child.text or "").strip()
            if "uom" in child.attrib:
                header[f"{tag}.uom"] = child.attrib["uom"]
    stations = trajectory.findall("w:trajectoryStation", WITSML_NS)
    columns: dict[str, Column] = {}
    for path_, name in WITSML_STATION.items():
        xpath = "/".join(f"w:{part}" for part in path_.split("/"))
        found = [s.find(xpath, WITSML_NS) for s in stations]
        units = {e.attrib["uom"] for e in found if e is not None}
        if not units:
            continue
        assert len(units) == 1, (path_, units)
        texts = ["" if e is None else (e.text or "").strip() for e in found]
        columns[name] = Column(units.pop(), [_number(t) for t in texts], texts)
    header["typeTrajStation"] = ",".join(
        (s.findtext("w:typeTrajStation", "", WITSML_NS) or "") for s in stations
    )
    return Listing(header, columns)


def arrow_listing(table: pa.Table) -> Listing:
    """An Arrow table's float columns with the unit each field's metadata states, and its
    schema metadata (text)."""
    header = {k.decode(): v.decode() for k, v in (table.schema.metadata or {}).items()}
    columns = {}
    for f in table.schema:
        if pa.types.is_floating(f.type):
            unit = (f.metadata or {}).get(b"unit", b"").decode()
            values = [math.nan if v is None else v for v in table.column(f.name).to_pylist()]
            columns[f.name] = Column(unit, values)
    return Listing(header, columns)


def read_parquet(path: Path) -> Listing:
    """A persisted Parquet table, as :func:`arrow_listing`."""
    return arrow_listing(pq.read_table(path))


def read_mcap(path: Path) -> tuple[dict[str, dict[str, str]], dict[str, pa.Table]]:
    """A processed MCAP file: its metadata records (name → key → text) and each topic's
    Arrow IPC messages concatenated (topic → table)."""
    with path.open("rb") as f:
        reader = make_reader(f)
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        parts: dict[str, list[pa.Table]] = {}
        for schema, channel, message in reader.iter_messages():
            assert schema is not None and schema.encoding == "arrow.ipc.schema", channel.topic
            assert channel.message_encoding == "arrow.ipc.record_batch", channel.topic
            table = pa.ipc.open_stream(schema.data + message.data).read_all()
            parts.setdefault(channel.topic, []).append(table)
    return metadata, {topic: pa.concat_tables(tables) for topic, tables in parts.items()}


def plain(fragment: str) -> str:
    """An HTML fragment's text, whitespace collapsed."""
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", fragment))).strip()


def html_text(report: Path) -> str:
    """report.html's visible text (no style, script or drawing), whitespace collapsed."""
    text = report.read_text(encoding="utf-8")
    return plain(re.sub(r"<(style|script|svg)\b.*?</\1>", " ", text, flags=re.S))


def html_table(report: Path, css_class: str) -> tuple[list[tuple[str, str]], list[list[str]]]:
    """The header cells (name, the unit its ``<span class="unit">`` states) and body rows
    (cell text) of report.html's first ``<table class="css_class">``."""
    text = report.read_text(encoding="utf-8")
    table = re.search(rf'<table class="{css_class}"[^>]*>(.*?)</table>', text, flags=re.S)
    assert table, f"no table {css_class!r} in {report.name}"
    head, _, body = table.group(1).partition("<tbody>")
    heads = [
        (plain(name), plain(unit))
        for name, unit in re.findall(
            r'<th[^>]*>(.*?)(?:<span class="unit">(.*?)</span>)?</th>', head, flags=re.S
        )
    ]
    rows = [
        [plain(c) for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row, flags=re.S)]
        for row in re.findall(r"<tr[^>]*>(.*?)</tr>", body, flags=re.S)
    ]
    return heads, rows


def pdf_text(pdf: Path) -> str:
    """report.pdf's text as ``pdftotext -layout`` lays it out, whitespace collapsed."""
    done = subprocess.run(["pdftotext", "-layout", pdf, "-"], capture_output=True, check=True)
    return " ".join(done.stdout.decode().split())


def pdf_lines(pdf: Path) -> list[str]:
    """report.pdf's lines as ``pdftotext -layout`` lays them out, blanks dropped."""
    done = subprocess.run(["pdftotext", "-layout", pdf, "-"], capture_output=True, check=True)
    return [line.strip() for line in done.stdout.decode().splitlines() if line.strip()]
