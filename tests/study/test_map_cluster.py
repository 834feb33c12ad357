"""``drill_sim map --scheduler``: the same map on a local Dask cluster (two worker processes,
started and closed here) equals the map computed in this process, byte for byte."""

from __future__ import annotations

import pytest

from drill_sim.cli.main import main

distributed = pytest.importorskip("distributed")

MAP = ["map", "--rpm", "40:200:3", "--wob-kn", "80,100,140", "--duration", "12"]


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as local:
        yield local


@pytest.mark.process          # two worker processes (multiprocessing, not a subprocess call)
def test_a_local_dask_cluster_computes_the_same_map(tmp_path, cluster, capsys):
    here, there = tmp_path / "here.csv", tmp_path / "there.csv"
    assert main([*MAP, "--workers", "1", "--out", str(here)]) == 0
    assert main([*MAP, "--scheduler", cluster.scheduler_address, "--out", str(there)]) == 0
    assert f"on the Dask cluster at {cluster.scheduler_address}" in capsys.readouterr().out
    assert there.read_bytes() == here.read_bytes()


def test_a_cluster_without_workers_is_refused(tmp_path, capsys):
    with distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=":0") as empty:
        assert main([*MAP, "--scheduler", empty.scheduler_address, "--out",
                     str(tmp_path / "m.csv")]) == 2
    err = capsys.readouterr().err
    assert "has no workers" in err and "dask worker" in err and err.count("\n") == 1
