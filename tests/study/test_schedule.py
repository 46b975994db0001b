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


def _closed_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_budget_bounds_the_connection_to_a_scheduler():
    """An address where nothing listens: the connection is tried for what is left of the
    budget, not dask's 30 s, and the study ends as a budget that ran out."""
    import nhham

    with pytest.raises(nhham.BudgetExceeded, match="while connecting to the scheduler"):
        sweep(SCENE, "linearize", OVER, scheduler=f"tcp://127.0.0.1:{_closed_port()}",
              budget=1.0)


def test_the_budget_stops_a_chunk_inside_its_runs(tmp_path):
    """Runs to t = 1e9 (days of integration): the compiled loop stops at the study's
    deadline; the chunk is not kept and --resume is what is left."""
    out = tmp_path / "runs.zarr"
    drive = "examples/differential_drive_motors.toml"
    # the model built first, so that the preparation fits the budget
    assert sweep(drive, "simulate", ["c=0.01:0.05:2"], workers=1).complete
    for scheduler in ("synchronous", "threads"):
        stopped = sweep(drive, "simulate", ["c=0.01:0.05:2"], workers=2, chunk_points=1,
                        scheduler=scheduler, budget=3.0, run_options={"t_end": 1e9},
                        out=out, overwrite=True)
        assert not stopped.complete and stopped.stopped == "budget" and stopped.computed == 0


@pytest.mark.parametrize("scheduler, fragment", [
    ("ucx://127.0.0.1:8786", "the address scheme ucx:// is not supported"),
    ("inproc://x", "the address scheme inproc:// is not supported"),
    ("proceses", "'proceses' is neither processes, threads, synchronous nor the address")])
def test_unsupported_schedulers_are_refused_naming_the_option(scheduler, fragment):
    from nhham.errors import InputError
    from nhham.study.schedule import check_scheduler

    with pytest.raises(InputError, match=fragment) as info:
        check_scheduler(scheduler, None)
    assert info.value.key == "--scheduler"


def test_plain_tcp_off_this_machine_is_warned_about_once_and_loopback_is_not():
    import warnings

    from nhham.errors import NhhamWarning
    from nhham.study.schedule import check_scheduler

    with pytest.warns(NhhamWarning, match="clear text .* unpickled here") as caught:
        assert check_scheduler("tcp://10.1.2.3:8786", None) == "tcp"
    assert len(caught) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for quiet in ("tcp://127.0.0.1:8786", "tcp://localhost:8786", "tcp://[::1]:8786",
                      "tls://cluster.example.org:8786"):
            check_scheduler(quiet, None)


def test_tls_takes_the_certificates_of_the_dask_configuration(tmp_path):
    """Without certificates in the configuration a tls:// address is refused (naming the
    keys to set); with them, distributed.Security carries them."""
    import dask

    from nhham.errors import InputError
    from nhham.study.schedule import _security

    with dask.config.set({"distributed.comm.tls.ca-file": None,
                          "distributed.comm.tls.client.cert": None}):
        with pytest.raises(InputError, match="no TLS certificates .*ca-file") as info:
            _security("tls://127.0.0.1:8786")
    assert info.value.key == "--scheduler"
    ca, cert = tmp_path / "ca.pem", tmp_path / "client.pem"
    with dask.config.set({"distributed.comm.tls.ca-file": str(ca),
                          "distributed.comm.tls.client.cert": str(cert)}):
        security = _security("tls://127.0.0.1:8786")
    assert (security.tls_ca_file, security.tls_client_cert) == (str(ca), str(cert))


def test_workers_have_an_upper_bound():
    from nhham.errors import InputError
    from nhham.study.schedule import check_scheduler, default_workers, max_workers

    assert max_workers() == max(8, 4 * default_workers())
    check_scheduler(None, max_workers())
    with pytest.raises(InputError, match=f"--workers: at most {max_workers()} local "
                                         f"workers") as info:
        check_scheduler(None, 100000)
    assert info.value.key == "--workers"


def test_a_study_on_a_tls_cluster_with_the_configuration_s_certificates(here):
    """A cluster that speaks only TLS (self-signed certificates made for the test, given
    to the study through the dask configuration, as a user's would be)."""
    import dask

    security = distributed.Security.temporary()
    config = {"distributed.comm.tls.ca-file": security.tls_ca_file,
              "distributed.comm.tls.client.cert": security.tls_client_cert,
              "distributed.comm.tls.client.key": security.tls_client_key}
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tls", security=security,
                                  dashboard_address=None) as cluster, \
            dask.config.set(config):
        assert cluster.scheduler_address.startswith("tls://")
        result = sweep(SCENE, "linearize", OVER, scheduler=cluster.scheduler_address,
                       chunk_points=9)
    assert result.complete and result.scheduler.startswith("tls://")
    _same(here, result.dataset)


def test_the_resource_tracker_of_a_local_cluster_does_not_report_killed_workers():
    """Workers killed on Ctrl-C leave semaphores that multiprocessing's resource tracker
    reports on stderr at exit, after `nhham: interrupted`; the tracker a study starts has
    that warning off (a leak planted by hand: silent with it, reported without)."""
    import subprocess
    import sys

    plant = ("from multiprocessing import resource_tracker\n"
             "resource_tracker.register('/nhham-planted', 'semaphore')\n")
    quiet = "from nhham.study.schedule import _quiet_resource_tracker\n_quiet_resource_tracker()\n"
    loud = subprocess.run([sys.executable, "-c", plant], capture_output=True, text=True,
                          timeout=60)
    assert "leaked semaphore" in loud.stderr
    calm = subprocess.run([sys.executable, "-c", quiet + plant], capture_output=True,
                          text=True, timeout=60)
    assert calm.stderr == ""
