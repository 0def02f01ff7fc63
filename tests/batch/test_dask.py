"""The Dask executor gives the same outputs, statuses and errors as the local process pool:
on a scheduler given by address (a LocalCluster on 127.0.0.1 in this process), where the
batch keeps as many wells in flight as the cluster has worker threads, and on the
LocalCluster the batch starts itself, whose worker processes alone read the inputs."""

from __future__ import annotations

from pathlib import Path

import pytest
from batch_support import (
    Opens,
    assert_complete,
    corrupt,
    log_events,
    make_wells,
    output_hashes,
    summary,
)

from tests_support import gyropipe_cli

distributed = pytest.importorskip("distributed")


def statuses(out: Path) -> dict[str, tuple[str, str]]:
    return {w: (r["status"], r["detail"]) for w, r in summary(out).items()}


def test_dask_executor_outputs_equal_the_local_ones(tmp_path: Path, survey: Path):
    names = ["D1", "D2", "D3", "D4"]
    paths = make_wells(tmp_path / "in", names)
    corrupt(paths[2])
    pattern = tmp_path / "in" / "*.csv"
    local = gyropipe_cli(
        "batch", survey, "--inputs", pattern, "--out", tmp_path / "local", "--workers", "2"
    )
    assert local.returncode == 1, local.output

    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        on_cluster = gyropipe_cli(
            "batch", survey, "--inputs", pattern, "--out", tmp_path / "dask", "--executor", "dask",
            "--scheduler", cluster.scheduler_address, "--workers", "1",
        )  # fmt: skip
    assert on_cluster.returncode == 1, on_cluster.output
    start = log_events(on_cluster.stderr)[0]
    assert (start["executor"], start["workers"]) == ("dask", 2)  # the cluster's, not --workers
    good = ["D1", "D2", "D4"]
    assert output_hashes(tmp_path / "dask", good) == output_hashes(tmp_path / "local", good)
    assert statuses(tmp_path / "dask") == statuses(tmp_path / "local")
    for well in good:
        assert_complete(tmp_path / "dask" / well)

    # no --scheduler: the batch starts a LocalCluster of worker processes on 127.0.0.1
    with Opens() as opens:
        own = gyropipe_cli(
            "batch", survey, "--inputs", tmp_path / "in" / "D[12].csv", "--out",
            tmp_path / "own", "--executor", "dask", "--workers", "1",
        )  # fmt: skip
    assert own.returncode == 0, own.output
    assert any(Path(p).name == survey.name for p in opens.driver)  # the hook saw the batch
    assert not {str(p.resolve()) for p in paths} & set(opens.driver)  # only workers read them
    assert output_hashes(tmp_path / "own", ["D1", "D2"]) == output_hashes(
        tmp_path / "local", ["D1", "D2"]
    )
