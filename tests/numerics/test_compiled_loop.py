"""scipy's explicit Runge-Kutta methods as one compiled loop (nhham.numerics.compiled_loop):
against scipy's own loop, against closed-form solutions, its failures and options, and
its pauses (every few milliseconds) that change nothing."""

from __future__ import annotations

import numpy as np
import pytest

import nhham
from handmade import blowup_system
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

from test_codegen import pendulum, pendulum_state
from test_exact_solutions import chaplygin_sleigh, sleigh_exact, sleigh_state


HAVE_CC = numeric_model(chaplygin_sleigh()).backend == "c"
needs_cc = pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")


@needs_cc
@pytest.mark.parametrize("method", ["RK23", "RK45", "DOP853"])
@pytest.mark.parametrize("options", [{}, {"projection": True}, {"t_eval": True},
                                     {"t_eval": True, "projection": True},
                                     {"baumgarte": (1.0, 2.0)}],
                         ids=["plain", "projection", "t_eval", "t_eval+projection", "baumgarte"])
def test_compiled_loop_matches_scipy_loop_on_the_numpy_path(method, options):
    """RK23/RK45/DOP853 as one compiled loop against scipy's own loop on the
    numpy backend (the pre-existing path), on the Cartesian pendulum (holonomic:
    the projection runs Newton in C): same number of steps, the same states at
    the t_eval points and at t_end up to round-off, the same work integral;
    projected runs keep the residual at round-off."""
    system = pendulum()
    compiled, numpy_model = numeric_model(system), numeric_model(system, backend="numpy")
    kw = dict(options)
    if kw.pop("t_eval", False):
        kw["t_eval"] = np.linspace(0.0, 3.0, 13)[1:]  # t0 not requested
    runs = [simulate(m, (0, 3.0), pendulum_state(), method=method, rtol=1e-8, atol=1e-10,
                     warn=False, loop=loop, **kw)
            for m, loop in ((compiled, "compiled"), (numpy_model, "auto"))]
    fast, ref = runs
    assert fast.settings["loop"] == "compiled" and ref.settings["loop"] == "scipy"
    assert fast.success and ref.success
    assert abs(fast.nsteps - ref.nsteps) <= 2
    assert fast.t[-1] == ref.t[-1] == 3.0
    assert np.allclose(fast.y[:, -1], ref.y[:, -1], rtol=1e-11, atol=1e-11)
    assert fast.work[-1] == pytest.approx(ref.work[-1], abs=1e-10)
    if "t_eval" in kw:
        assert np.array_equal(fast.t, kw["t_eval"]) and np.array_equal(ref.t, kw["t_eval"])
        assert np.allclose(fast.y, ref.y, rtol=1e-11, atol=1e-11)
        assert fast.nfev == ref.nfev
    else:
        assert fast.t[0] == 0.0 and np.all(np.diff(fast.t) > 0)
        assert len(fast.t) == fast.nsteps + 1
    if kw.get("projection"):
        assert fast.constraint_residual_max <= 1e-14


@needs_cc
def test_compiled_loop_against_exact_solutions():
    """Chaplygin sleigh (closed form) and the rolling disk (exact state) with the
    compiled DOP853 / RK45, also with projection and across several chunks of
    stored steps (RK23 at a tight tolerance: thousands of steps)."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    sleigh = numeric_model(chaplygin_sleigh())
    t = np.linspace(0.5, 6.0, 12)
    for method, rtol, tol in (("DOP853", 1e-11, 1e-9), ("RK45", 1e-10, 1e-8)):
        for projection in (False, True):
            res = simulate(sleigh, (0, 6.0), sleigh_state(), method=method, rtol=rtol,
                           atol=1e-13, t_eval=t, projection=projection, loop="compiled",
                           warn=False)
            u_ex, w_ex, th_ex = sleigh_exact(res.t)
            u = np.cos(res["theta"]) * res["x_dot"] + np.sin(res["theta"]) * res["y_dot"]
            err = max(np.max(np.abs(u - u_ex)), np.max(np.abs(res["theta_dot"] - w_ex)),
                      np.max(np.abs(res["theta"] - th_ex)))
            assert err < tol, (method, projection, err)
    disk = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))
    res = simulate(disk, (0, 5.0), y0, method="RK23", rtol=1e-9, atol=1e-12, projection=True,
                   loop="compiled", warn=False)
    assert res.nsteps > 1000 and len(res.t) == res.nsteps + 1  # several C calls
    assert np.max(np.abs(res.y - rolling_disk_exact(res.t)[0])) < 1e-6
    assert res.constraint_residual_max <= 1e-14


@needs_cc
def test_compiled_loop_failures_progress_and_options(capsys):
    """Failure statuses and messages as in scipy's loop (the finite part kept),
    scipy's option checks, max_step honoured, progress reported."""
    blowup = numeric_model(blowup_system())
    for loop in ("compiled", "scipy"):
        res = simulate(blowup, (0, 10), [1.0, 0.0, 1.0, 0.0], method="DOP853", loop=loop,
                       warn=False)
        assert res.status in (-1, -2) and 2.0 < res.t[-1] < 3.0 and np.all(np.isfinite(res.y))
    singular = numeric_model(nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 - x",
                                          ["x*x_dot + y*y_dot"]))
    msgs = []
    for loop in ("compiled", "scipy"):
        res = simulate(singular, (0, 1), np.zeros(4), method="RK45", loop=loop, warn=False)
        assert res.status == -3 and len(res.t) == 1
        msgs.append(res.message)
    assert msgs[0] == msgs[1] and "singular saddle-point system at t = 0" in msgs[0]
    sleigh = numeric_model(chaplygin_sleigh())
    for bad in ({"max_step": 0.0}, {"first_step": -1.0}, {"first_step": 5.0}):
        with pytest.raises(ValueError, match="step"):
            simulate(sleigh, (0, 1), sleigh_state(), loop="compiled", **bad)
    with pytest.warns(UserWarning, match="rtol"):
        simulate(sleigh, (0, 1), sleigh_state(), rtol=1e-20, loop="compiled", warn=False)
    res = simulate(sleigh, (0, 1), sleigh_state(), max_step=0.01, first_step=1e-3,
                   loop="compiled", warn=False)
    assert np.max(np.diff(res.t)) <= 0.01 + 1e-15 and res.t[1] == pytest.approx(1e-3)


@needs_cc
@pytest.mark.parametrize("method, options", [("DOP853", {"rtol": 1e-12}),
                                             ("RK23", {"projection": True}),
                                             ("rattle", {"step": 0.01}),
                                             ("rattle4", {"step": 0.05})])
def test_compiled_loops_resume_after_every_pause(monkeypatch, capsys, method, options):
    """The compiled loops hand control back every PAUSE_SECONDS (so that Ctrl-C and the
    command's --budget are handled at once): with a pause after every step the run is
    the same to the last bit, and progress is reported at every tenth."""
    import nhham.numerics.compiled_loop as compiled_loop
    import nhham.numerics.integrators as integrators

    sleigh = numeric_model(chaplygin_sleigh())
    whole = simulate(sleigh, (0, 2), sleigh_state(), method=method, warn=False, **options)
    monkeypatch.setattr(compiled_loop, "PAUSE_SECONDS", 0.0)
    monkeypatch.setattr(integrators, "PAUSE_SECONDS", 0.0)
    capsys.readouterr()
    paused = simulate(sleigh, (0, 2), sleigh_state(), method=method, warn=False,
                      progress=True, **options)
    assert np.array_equal(whole.t, paused.t) and np.array_equal(whole.y, paused.y)
    assert whole.nsteps == paused.nsteps > 15 and whole.nfev == paused.nfev
    err = capsys.readouterr().err
    assert "(50%)" in err and "(100%)" in err


@pytest.mark.parametrize("method", ["RK23", "RK45", "DOP853"])
def test_the_kept_tableau_is_scipy_s_and_a_damaged_one_is_read_again(method, tmp_path,
                                                                     monkeypatch):
    """The coefficients the compiled loop reads from the cache are scipy's own, bit for
    bit; a cache file changed after it was written is not trusted (its hash record)."""
    import scipy.integrate

    from nhham.numerics import compiled_loop

    monkeypatch.setenv("NHHAM_CACHE", str(tmp_path))
    compiled_loop._coefficients.cache_clear()
    first = compiled_loop._coefficients(method)
    kept = list(tmp_path.glob(f"tableau_{method}_*.json"))
    assert len(kept) == 1
    compiled_loop._coefficients.cache_clear()
    again = compiled_loop._coefficients(method)   # read from the file
    cls = getattr(scipy.integrate, method)
    for info, tab in (first, again):
        assert info[0] == cls.n_stages and info[3] == cls.error_estimator_order
        assert np.array_equal(tab, compiled_loop._scipy_tableau(method)[1])
    s = cls.n_stages
    assert np.array_equal(again[1][s * s:s * s + s], np.asarray(cls.B, dtype=float))
    kept[0].write_text(kept[0].read_text().replace("[", "[1.0, ", 2))
    compiled_loop._coefficients.cache_clear()
    assert np.array_equal(compiled_loop._coefficients(method)[1], first[1])
    compiled_loop._coefficients.cache_clear()
