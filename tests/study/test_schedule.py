"""Studies on Dask: a local cluster of two worker processes, and a Client given by the user,
give what the chunks give in this process."""

import numpy as np
import pytest

from nhham.study.sweep import sweep

distributed = pytest.importorskip("dask.distributed")

SCENE = "examples/differential_drive.toml"
OVER = ["w=-4.5:5.5:9", "d=0.02:0.06:3"]


@pytest.fixture(scope="module")
def here():
    return sweep(SCENE, "linearize", OVER, workers=1).dataset


def _same(a, b):
    for name in a.data_vars:
        x, y = np.asarray(a[name].values), np.asarray(b[name].values)
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name


def test_two_worker_processes_of_a_local_cluster(here):
    result = sweep(SCENE, "linearize", OVER, scheduler="processes", workers=2, chunk_points=9)
    assert (result.scheduler, result.workers, result.chunks) == ("processes", 2, 3)
    _same(here, result.dataset)


def test_a_client_of_the_user_s_cluster(here):
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        result = sweep(SCENE, "linearize", OVER, client=client, chunk_points=9)
        assert result.scheduler == cluster.scheduler_address and result.workers == 2
        assert len(client.scheduler_info()["workers"]) == 2   # the cluster is still there
    _same(here, result.dataset)


def test_threads_share_this_process_s_model(here):
    result = sweep(SCENE, "linearize", OVER, scheduler="threads", workers=2, chunk_points=9)
    assert result.scheduler == "threads"
    _same(here, result.dataset)


def test_threads_stop_at_the_budget_and_resume(tmp_path, here):
    """Threads (dask's threaded scheduler): the first chunk's report outlasts the budget,
    so only it is written (3 points: a piece of a line along w, which --chunk cuts);
    --resume computes the other eight, to the arrays of one process (the boundaries of
    the pieces merged into those of the whole lines)."""
    import time

    out = tmp_path / "drive.zarr"
    stopped = sweep(SCENE, "linearize", OVER, scheduler="threads", workers=2, chunk_points=3,
                    out=out, budget=2.0, progress=lambda done, total, elapsed: time.sleep(2.0))
    assert not stopped.complete and stopped.computed == 3 and stopped.scheduler == "threads"
    resumed = sweep(SCENE, "linearize", OVER, scheduler="threads", workers=2, chunk_points=3,
                    out=out, resume=True)
    assert resumed.complete and resumed.computed == 24
    _same(here, resumed.dataset)
