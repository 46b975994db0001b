"""What every integration loop hands back (nhham.numerics.run): a run stopped at its
wall-time limit or by a Ctrl-C keeps its trajectory; progress is reported by tenths of the
interval."""

from __future__ import annotations

import numpy as np
import pytest

from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate
from nhham.numerics.run import Deadline, report_progress


@pytest.mark.parametrize("method, options", [("DOP853", {}), ("Radau", {}),
                                             ("rattle", {"step": 0.01}), ("rk4", {"step": 0.01})])
def test_time_limit_stops_a_run_and_keeps_it(method, options):
    """time_limit=0: the run stops at the first look at the clock (after a step, or the
    first return of a compiled loop) with Status.TIME_LIMIT, a failure that keeps the
    trajectory so far."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))
    res = simulate(model, (0, 1e5), y0, method=method, time_limit=0.0, warn=False, **options)
    assert res.status == -5 and not res.success and res.status.name == "TIME_LIMIT"
    assert "time limit of 0 s" in res.message and 0 < res.t[-1] < 1e5
    assert len(res.t) == res.y.shape[1] >= 2


@pytest.mark.parametrize("method, options", [("DOP853", {}), ("Radau", {}),
                                             ("rattle", {"step": 0.01})])
def test_a_ctrl_c_stops_a_run_and_keeps_it(method, options):
    """SIGINT during the run (a timer thread sends it to this process): the loop stops at
    its next look (Status.INTERRUPTED), the states so far kept and on the disk's exact
    motion (theta' and phi' constant); SIGINT is handled as before afterwards."""
    import os
    import signal
    import threading

    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))
    before = signal.getsignal(signal.SIGINT)
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        res = simulate(model, (0, 1e7), y0, method=method, warn=False, save_every=1000,
                       **options)
    finally:
        timer.cancel()
    assert res.status.name == "INTERRUPTED" and not res.success
    assert "interrupted (Ctrl-C) at t = " in res.message and 0 < res.t[-1] < 1e7
    assert np.allclose(res.y[6], y0[6]) and np.allclose(res.y[7], y0[7])
    assert signal.getsignal(signal.SIGINT) is before


def test_progress_is_reported_once_a_tenth(capsys):
    """Over [2, 4]: t = 2.5 is 25% done (the 20% mark, once), 3.1 passes 50%, and an
    earlier time reports nothing again."""
    done = report_progress(2.5, 2.0, 4.0, 0)
    assert done == 2 and capsys.readouterr().err == "  t = 2.5 (20%)\n"
    assert report_progress(2.55, 2.0, 4.0, done) == 2 and capsys.readouterr().err == ""
    assert report_progress(3.1, 2.0, 4.0, done) == 5
    assert capsys.readouterr().err == "  t = 3.1 (50%)\n"
    assert report_progress(2.1, 2.0, 4.0, 5) == 5 and capsys.readouterr().err == ""
    assert report_progress(0.5, 0.0, -1.0, 0) == 0  # backwards: t moves from t0 towards t1
    assert report_progress(-0.5, 0.0, -1.0, 0) == 5


def test_a_deadline():
    never = Deadline.after(None)
    assert not never.passed() and never.seconds == float("inf")
    later = Deadline.after(1e6)
    assert not later.passed() and later.seconds == 1e6
    assert later.message(2.5) == ("stopped at the time limit of 1e+06 s (wall time) at t = 2.5, "
                                  "before the end of the interval")
