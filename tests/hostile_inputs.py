"""Hostile input files (issue 32): small files that claim, nest or repeat their way to huge
costs. Shared by the regression tests and the fuzz suite (``fuzz_support``: :data:`HOSTILE`, the
generators of each input kind); each generator returns the file's bytes."""

from __future__ import annotations

import io
import json
import random
import struct
from collections.abc import Callable

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pipeline.tables import Stations

MCAP_MAGIC = b"\x89MCAP0\r\n"


def _record(op: int, body: bytes) -> bytes:
    return struct.pack("<BQ", op, len(body)) + body


def _text(value: str) -> bytes:
    raw = value.encode()
    return struct.pack("<I", len(raw)) + raw


def _mapping(entries: dict[str, str]) -> bytes:
    body = b"".join(_text(k) + _text(v) for k, v in entries.items())
    return struct.pack("<I", len(body)) + body


def mcap_file(records: bytes) -> bytes:
    """An MCAP file of ``records`` (after the Header), with a DataEnd and a Footer but no
    summary and no CRCs."""
    header = _record(0x01, _text("") + _text("hostile"))
    end = _record(0x0F, struct.pack("<I", 0))
    footer = _record(0x02, struct.pack("<QQI", 0, 0, 0))
    return MCAP_MAGIC + header + records + end + footer + MCAP_MAGIC


def mcap_chunk(declared: int, actual: int, compression: str = "zstd") -> bytes:
    """An MCAP file of one compressed chunk that declares ``declared`` bytes of records and
    decompresses to ``actual`` zero bytes (a zstd frame of 64 MiB of zeros is ~2 kB)."""
    zeros = bytes(actual)
    if compression == "zstd":
        import zstandard

        stored = zstandard.ZstdCompressor(write_content_size=False).compress(zeros)
    else:
        import lz4.frame

        stored = lz4.frame.compress(zeros)
    body = (
        struct.pack("<QQQI", 0, 0, declared, 0)
        + _text(compression)
        + struct.pack("<Q", len(stored))
        + stored
    )
    return mcap_file(_record(0x06, body))


def nested_json(depth: int) -> str:
    """A JSON object nested ``depth`` levels deep: ``{"a": {"a": … {} …}}``."""
    return '{"a": ' * depth + "{}" + "}" * depth


def mcap_channel_metadata(key: str, value: str) -> bytes:
    """An MCAP file with a per-sample JSON channel whose metadata ``key`` is ``value``."""
    channel = _record(
        0x04,
        struct.pack("<HH", 1, 0) + _text("/imu") + _text("json") + _mapping({key: value}),
    )
    message = _record(
        0x05, struct.pack("<HIQQ", 1, 0, 1, 1) + json.dumps({"t": 0.0, "gx": 1.0}).encode()
    )
    return mcap_file(channel + message)


def parquet_bytes(table: pa.Table, **options: object) -> bytes:
    sink = io.BytesIO()
    pq.write_table(table, sink, **options)  # type: ignore[arg-type]
    return sink.getvalue()


def _stations(rows: int, extra: int = 0) -> pa.Table:
    """A valid stations table of ``rows`` rows (MD 0, 1, …) and ``extra`` zero columns."""
    data = {"md": np.arange(rows, dtype=float), "inc": np.zeros(rows), "azi": np.zeros(rows)}
    table = Stations.compiled().make_table(data, north_reference="true")
    for i in range(extra):
        table = table.append_column(f"c{i}", pa.array(np.zeros(rows)))
    return table


def parquet_with_metadata(key: bytes, value: bytes) -> bytes:
    """A valid stations Parquet file whose schema metadata ``key`` is ``value``."""
    table = _stations(3)
    meta = {**(table.schema.metadata or {}), key: value}
    return parquet_bytes(table.replace_schema_metadata(meta))


def parquet_wide(columns: int, rows: int = 2) -> bytes:
    """A stations Parquet file with ``columns`` extra float64 columns."""
    return parquet_bytes(_stations(rows, columns))


def parquet_long(rows: int) -> bytes:
    """A stations Parquet file of ``rows`` zero rows in one row group: run-length encoding
    packs 3 × 8 bytes per row into a few kB."""
    schema = _stations(1).schema
    table = pa.table([pa.array(np.zeros(rows)) for _ in schema], schema=schema)
    return parquet_bytes(table, row_group_size=rows, compression="zstd")


def witsml_text(chars: int) -> bytes:
    """A WITSML 1.4.1 trajectory whose well name is ``chars`` characters long."""
    return _witsml(name="x" * chars)


def witsml_attribute(chars: int) -> bytes:
    """A WITSML 1.4.1 trajectory with an attribute ``chars`` characters long."""
    return _witsml(attribute="x" * chars)


def _witsml(name: str = "w", attribute: str = "") -> bytes:
    extra = f' note="{attribute}"' if attribute else ""
    return (
        '<?xml version="1.0"?>\n<trajectorys xmlns="http://www.witsml.org/schemas/1series" '
        f'version="1.4.1.1"><trajectory uidWell="w" uidWellbore="b" uid="t"{extra}>'
        f"<nameWell>{name}</nameWell><nameWellbore>b</nameWellbore><name>t</name>"
        "<aziRef>true north</aziRef>"
        '<trajectoryStation uid="s1"><md uom="m">0</md><incl uom="dega">0</incl>'
        '<azi uom="dega">0</azi></trajectoryStation>'
        '<trajectoryStation uid="s2"><md uom="m">100</md><incl uom="dega">1</incl>'
        '<azi uom="dega">10</azi></trajectoryStation></trajectory></trajectorys>\n'
    ).encode()


def csv_wide(columns: int) -> bytes:
    """A stations CSV with ``columns`` extra columns (two rows)."""
    names = ",".join(f"c{i}" for i in range(columns))
    zeros = ",".join("0" for _ in range(columns))
    return f"md [m],inc [deg],azi true [deg],{names}\n0,0,0,{zeros}\n100,1,10,{zeros}\n".encode()


def csv_named(chars: int, key: str = "Well: ") -> bytes:
    """A stations CSV whose title line ``key`` gives a well name ``chars`` characters long."""
    return (
        f"{key}{'x' * chars}\nNorth Reference: true\nMD (m),Inc (deg),Azimuth (deg)\n"
        "0,0,0\n100,1,10\n"
    ).encode()


def las_named(chars: int) -> bytes:
    """A LAS 2.0 stations file whose ~Well WELL item is ``chars`` characters long."""
    return (
        "~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.M 0 :\n STOP.M 100 :\n"
        f" NULL. -999.25 :\n WELL. {'x' * chars} : well\n~Curve\n DEPT.M : depth\n"
        " INCL.DEG : inclination\n AZIM.DEG : azimuth (true north)\n~A\n0 0 0\n100 1 10\n"
    ).encode()


def las_wide(curves: int) -> bytes:
    """A LAS 2.0 stations file with ``curves`` extra curves (two rows)."""
    names = "".join(f" C{i}.M : curve {i}\n" for i in range(curves))
    zeros = " 0" * curves
    return (
        "~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.M 0 :\n STOP.M 100 :\n"
        " NULL. -999.25 :\n~Curve\n DEPT.M : depth\n INCL.DEG : inclination\n"
        f" AZIM.DEG : azimuth (true north)\n{names}~A\n0 0 0{zeros}\n100 1 10{zeros}\n"
    ).encode()


def yaml_binary_aliases(anchor_chars: int, aliases: int) -> bytes:
    """A pipeline whose ``!!binary`` anchor of ``anchor_chars`` base64 characters is
    aliased ``aliases`` times."""
    many = ", ".join(["*b"] * aliases)
    return f"name: p\nversion: 1\nblob: &b !!binary {'A' * anchor_chars}\nmany: [{many}]\n".encode()


Generator = Callable[[random.Random], tuple[bytes, str]]


def _pick(rng: random.Random, *sizes: int) -> int:
    return rng.choice(sizes)


HOSTILE: dict[str, tuple[Generator, ...]] = {
    "mcap": (
        lambda r: (mcap_chunk(_pick(r, 6 << 30, 1 << 40), 8 << 20), "zstd chunk claims GiB"),
        lambda r: (mcap_chunk(1000, 4 << 20, r.choice(["zstd", "lz4"])), "chunk holds more"),
        lambda r: (
            mcap_channel_metadata("units", nested_json(_pick(r, 65, 5_000, 100_000))),
            "channel metadata nested deep",
        ),
    ),
    "parquet": (
        lambda r: (parquet_wide(_pick(r, 1_001, 5_003)), "too many columns"),
        lambda r: (parquet_long(_pick(r, 3_000_000, 5_000_000)), "RLE rows claim GB"),
        lambda r: (
            parquet_with_metadata(b"gyropipe.well", nested_json(100_000).encode()),
            "well metadata nested deep",
        ),
    ),
    "witsml": (
        lambda r: (witsml_text(_pick(r, 1_000_000, 5_000_000)), "huge text"),
        lambda r: (witsml_attribute(_pick(r, 1_000_000, 5_000_000)), "huge attribute"),
    ),
    "csv-stations": (
        lambda r: (csv_wide(_pick(r, 1_001, 100_000)), "too many columns"),
        lambda r: (csv_named(_pick(r, 1_000_000, 5_000_000)), "huge well name"),
    ),
    "las-stations": (
        lambda r: (las_wide(_pick(r, 998, 100_000)), "too many curves"),
        lambda r: (las_named(_pick(r, 1_000_000, 5_000_000)), "huge well name"),
    ),
    "pipeline": (
        lambda r: (yaml_binary_aliases(100_000, _pick(r, 200, 20_000)), "binary aliases"),
        lambda r: (b"name: p\nversion: 1\nwhen: !!timestamp abc\n", "bad timestamp"),
    ),
}
"""The hostile generators of each fuzzed input kind (the fuzz suite's ``hostile`` op)."""
