"""The continuous stage's column store in memory, on disk and spilled midway: the store
holds its columns in memory up to its threshold and moves them to files one byte past it,
and the bits read back — through the store's own API and through a pipeline run — are the
same whichever way it held them."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pipeline.continuous import store as store_module
from pipeline.continuous.store import ColumnStore
from tests_support import gyropipe_cli


def test_the_store_moves_to_files_one_byte_past_its_threshold() -> None:
    store = ColumnStore(spool_bytes=100)
    store.write("x", 0, np.arange(10.0))  # 80 bytes
    store.write("flag", 0, np.ones(20, dtype=np.int8))  # 100: at the threshold
    store.write("x", 2, np.full(8, -1.5))  # rows already held: nothing grows
    assert not store.on_disk
    store.append("flag", np.array([7], dtype=np.int8))  # 101 bytes
    assert store.on_disk
    np.testing.assert_array_equal(store.read("x", 0, 10), [0.0, 1.0, *[-1.5] * 8])
    np.testing.assert_array_equal(store.read("flag", 0, 21), [1] * 20 + [7])
    assert store.read("flag", 0, 21).dtype == np.int8


def test_floats_are_read_only_views_that_keep_their_rows_when_a_column_grows() -> None:
    """In memory a float64 column's rows come without a copy, read-only; the column still
    grows while such a view lives (the view keeps the rows it had, and shows a write to
    them made before it grew), and on disk or of another type they are copies, read-only
    too."""
    store = ColumnStore()
    store.write("x", 0, np.arange(4.0))
    store.write("flag", 0, np.arange(4, dtype=np.int8))
    view = store.floats("x", 1, 3)
    np.testing.assert_array_equal(view, [1.0, 2.0])
    with pytest.raises(ValueError, match="read-only"):
        view[0] = 9.0
    store.write("x", 1, np.array([-1.0]))  # within the column: the view shows it
    store.append("x", np.arange(3.0))  # past its end while the view lives
    np.testing.assert_array_equal(view, [-1.0, 2.0])
    np.testing.assert_array_equal(store.floats("x", 0, 7), [0.0, -1.0, 2.0, 3.0, 0.0, 1.0, 2.0])
    assert store.floats("x", 5, 5).size == 0
    flags = store.floats("flag", 0, 4)
    assert flags.dtype == np.float64 and not flags.flags.writeable
    spilled = ColumnStore(spool_bytes=8)
    spilled.write("x", 0, np.arange(4.0))
    assert spilled.on_disk and not spilled.floats("x", 0, 4).flags.writeable


def written(store: ColumnStore) -> list[bool]:
    """A backward run's writes (chunks from the end, a gap read as zeros before it is
    filled), overwrites, appends, an int8 column and payloads a value comparison would not
    tell apart (−0.0, NaN, ±inf) into ``store``; whether it was on disk after each."""
    rng = np.random.default_rng(7)
    special = np.array([-0.0, np.nan, np.inf, -np.inf, 5e-324])
    steps: list[bool] = []
    for a in (120_000, 80_000, 40_000, 0):  # longer than a chunk, written from the end
        store.write("long", a, rng.normal(size=40_000))
        steps.append(store.on_disk)
    for a in (900, 600, 300, 0):  # reversed chunks of 300 rows
        store.write("azi", a, rng.normal(size=300))
        steps.append(store.on_disk)
    store.write("azi", 150, special)
    for _ in range(6):
        store.append("time", rng.uniform(size=250))
        store.append("held", rng.integers(-128, 128, size=250).astype(np.int8))
        steps.append(store.on_disk)
    store.write("late", 40, np.arange(3.0))  # rows 0…39 never written: zeros
    steps.append(store.on_disk)
    return steps


def expected() -> dict[str, np.ndarray]:
    """The columns :func:`written` leaves, made by slicing NumPy arrays."""
    rng = np.random.default_rng(7)
    special = np.array([-0.0, np.nan, np.inf, -np.inf, 5e-324])
    long = np.zeros(160_000)
    for a in (120_000, 80_000, 40_000, 0):
        long[a : a + 40_000] = rng.normal(size=40_000)
    azi = np.zeros(1200)
    for a in (900, 600, 300, 0):
        azi[a : a + 300] = rng.normal(size=300)
    azi[150:155] = special
    time, held = [], []
    for _ in range(6):
        time.append(rng.uniform(size=250))
        held.append(rng.integers(-128, 128, size=250).astype(np.int8))
    late = np.concatenate([np.zeros(40), np.arange(3.0)])
    columns = {"time": np.concatenate(time), "held": np.concatenate(held), "late": late}
    return {"azi": azi, **columns, "long": long}


def test_the_same_bits_in_memory_on_disk_and_spilled_midway() -> None:
    total = 8 * 1200 + 8 * 1500 + 1500 + 8 * 43 + 8 * 160_000  # bytes of the columns written
    stores = {
        "memory": ColumnStore(spool_bytes=total),
        "disk": ColumnStore(spool_bytes=0),
        "midway": ColumnStore(spool_bytes=8 * 160_000 + 100),  # spilled with "long" held
    }
    steps = {name: written(store) for name, store in stores.items()}
    assert not any(steps["memory"]) and all(steps["disk"])
    assert steps["midway"][:4] == [False] * 4 and steps["midway"][-1] is True
    for name, want in expected().items():
        for how, store in stores.items():
            got = store.read(name, 0, store.rows(name))
            assert got.dtype == want.dtype and got.tobytes() == want.tobytes(), (how, name)
            for lo, hi in ((97, 1013), (65_000, 140_000)):  # across writes and the end
                part = store.read(name, lo, hi)
                assert part.tobytes() == want[lo:hi].tobytes(), (how, name, lo)


PLAN = """
name: spool
seed: 3
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 100}
    - {kind: build, dls: 4.5, inc: 30, azi: 40}
    - {kind: hold, to_md: 400}
tool: {preset: mems-vrg}
survey: {mode: continuous, start_md: 135, end_md: 300, speed: 1.5}
"""
PIPELINE = """
name: spool
version: "1"
inputs: {samples: {description: raw samples}}
stages:
  - {id: read, uses: read_samples}
  - id: readings
    uses: position_readings
    inputs: {samples: read.samples}
    with: {trim_start: 1.0}
  - id: stops
    uses: compass
    inputs: {readings: readings.readings}
    with: {noise_floor: 0.01}
  - id: continuous
    uses: integrate_continuous
    inputs: {samples: read.samples, stops: stops.stations}
    persist: [stations, series]
"""


def test_a_continuous_run_gives_the_same_bits_whichever_way_its_store_holds_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "plan.yaml").write_text(textwrap.dedent(PLAN))
    (tmp_path / "pipeline.yaml").write_text(textwrap.dedent(PIPELINE))
    gyropipe_cli("simulate", tmp_path / "plan.yaml", "--out", tmp_path / "sim", check=True)
    samples = tmp_path / "sim" / "samples.parquet"
    raw = 8 * pq.ParquetFile(samples).metadata.num_rows  # bytes of one raw column
    files: list[int] = []
    make_file = store_module._column_file

    def counted() -> object:
        files.append(1)
        return make_file()

    monkeypatch.setattr(store_module, "_column_file", counted)
    made: dict[str, int] = {}
    # in memory throughout; on disk from the first byte; spilled while the raw columns
    # (seven of them) are being written
    for how, spool in (("memory", 64 * raw), ("disk", 0), ("midway", 3 * raw)):
        monkeypatch.setattr(store_module, "SPOOL_BYTES", spool)
        files.clear()
        out = tmp_path / how
        gyropipe_cli(
            "run", tmp_path / "pipeline.yaml", "--input", samples, "--out", out, check=True
        )
        made[how] = len(files)
    assert made["memory"] == 0 and made["disk"] > 10 and made["midway"] == made["disk"]
    for table in ("continuous.stations.parquet", "continuous.series.parquet"):
        want = pq.read_table(tmp_path / "memory" / table)
        assert want.num_rows > 10
        for how in ("disk", "midway"):
            got = pq.read_table(tmp_path / how / table)
            assert got.column_names == want.column_names
            for name in want.column_names:
                x, y = got.column(name).to_numpy(), want.column(name).to_numpy()
                assert x.tobytes() == y.tobytes(), (how, table, name)
