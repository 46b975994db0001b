"""What a run keeps: every j-th step, thinning within max_points, t_eval refused beyond it,
the memory stated (``nhham.numerics.storage``)."""

from __future__ import annotations

import numpy as np
import pytest

from nhham.errors import InputError
from nhham.numerics.integrate import simulate
from nhham.numerics.storage import STORE_BYTES, Recorder, default_max_points, storage_bytes

from test_exact_solutions import sleigh_state


def _feed(recorder, nsteps):
    """Offer steps 0..nsteps (the state is the step number) as a loop does."""
    recorder.add(0.0, [0.0, 0.0])
    for i in range(1, nsteps + 1):
        if recorder.keep(i):
            recorder.add(float(i), [float(i), -float(i)])
    recorder.close(float(nsteps), [float(nsteps), -float(nsteps)])
    return recorder.result(1)


@pytest.mark.parametrize("nsteps, max_points, stride, kept_stride",
                         [(10, 100, 1, 1), (10, 100, 3, 3), (1000, 100, 1, 16),
                          (1000, 64, 5, 20), (4097, 4096, 1, 2)])
def test_recorder_keeps_every_stride_th_step_within_the_bound(nsteps, max_points, stride,
                                                               kept_stride):
    """The kept steps are 0, s, 2s, ... and the last, with s the requested stride doubled
    until they fit (s by hand: 1000 steps in 100 states -> 16: 1000/8 = 125 > 100 and
    1000/16 = 62.5)."""
    rec = Recorder(2, max_points, stride)
    t, y, extra = _feed(rec, nsteps)
    expected = list(range(0, nsteps + 1, kept_stride))
    if expected[-1] != nsteps:
        expected.append(nsteps)
    assert t.tolist() == [float(s) for s in expected]
    assert y.shape == (1, len(expected)) and extra.tolist() == [-float(s) for s in expected]
    storage = rec.storage()
    assert storage.stride == kept_stride and storage.points == len(expected) <= max_points + 1
    assert storage.thinned == (kept_stride > stride)
    assert storage.bytes == 3 * 8 * len(expected)
    assert ("thinned" in storage.describe(nsteps)) == storage.thinned


def test_default_bound_is_the_store_bytes():
    assert default_max_points(9) == STORE_BYTES // 80 == 838860  # the rolling disk's rows
    assert storage_bytes(default_max_points(201), 201) <= STORE_BYTES
    assert default_max_points(10**9) == 1024  # never fewer


@pytest.mark.parametrize("method, options", [
    ("DOP853", {"rtol": 1e-12}), ("DOP853", {"rtol": 1e-12, "loop": "scipy"}),
    ("RK45", {"rtol": 1e-10, "projection": True}), ("rattle", {"step": 0.002}),
    ("rattle4", {"step": 0.01}), ("rk4", {"step": 0.002})])
def test_thinned_and_strided_runs_keep_steps_of_the_full_run(sleigh, method, options):
    """Every loop: with a small max_points the kept states are the full run's states at
    steps 0, s, 2s, ... (s a power of two) and its last one; save_every=3 keeps every
    third. The trajectory itself is the same."""
    full = simulate(sleigh, (0, 3), sleigh_state(), method=method, warn=False, **options)
    assert full.storage.stride == 1 and len(full.t) == full.nsteps + 1
    bound = full.nsteps // 4
    small = simulate(sleigh, (0, 3), sleigh_state(), method=method, warn=False,
                     max_points=bound, **options)
    s = small.storage.stride
    assert s >= 4 and s & (s - 1) == 0 and small.storage.thinned
    assert bound // 2 <= len(small.t) <= bound + 1 and small.storage.max_points == bound
    idx = list(range(0, full.nsteps + 1, s))
    idx += [] if idx[-1] == full.nsteps else [full.nsteps]
    assert np.array_equal(small.t, full.t[idx]) and np.array_equal(small.y, full.y[:, idx])
    third = simulate(sleigh, (0, 3), sleigh_state(), method=method, warn=False, save_every=3,
                     **options)
    idx = list(range(0, full.nsteps + 1, 3))
    idx += [] if idx[-1] == full.nsteps else [full.nsteps]
    assert np.array_equal(third.t, full.t[idx]) and np.array_equal(third.y, full.y[:, idx])
    assert third.storage.stride == 3 and not third.storage.thinned
    assert "one every 3 steps" in third.describe()


def test_t_eval_beyond_max_points_is_refused_with_the_memory(sleigh):
    """101 states of 2n + 1 = 7 numbers and their times: 101 * 8 * 8 B = 6464 B."""
    t = np.linspace(0, 1, 101)
    with pytest.raises(InputError, match=r"t_eval: 101 output states would take 6.46 kB, "
                                         r"above max_points = 100"):
        simulate(sleigh, (0, 1), sleigh_state(), t_eval=t, max_points=100)
    res = simulate(sleigh, (0, 1), sleigh_state(), t_eval=t, max_points=101, warn=False)
    assert np.array_equal(res.t, t) and res.storage.stride == 0
    assert res.storage.bytes == storage_bytes(101, 7)
    with pytest.raises(InputError, match="t_eval: the fixed-step method 'rattle'"):
        simulate(sleigh, (0, 1), sleigh_state(), method="rattle", step=0.1, t_eval=t)
    for bad in ({"max_points": 1}, {"save_every": 0}, {"save_every": 1.5}):
        with pytest.raises(InputError, match="max_points|save_every"):
            simulate(sleigh, (0, 1), sleigh_state(), **bad)
