"""``simulate``: the result object, initial data, failure statuses, options,
warnings, the reference method and the work-precision driver."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.errors import InconsistentInitialDataError, InputError
from nhham.numerics.integrate import METHODS, simulate
from nhham.numerics.model import NumericsWarning
from nhham.numerics.status import NumericalFailure
from nhham.numerics.workprecision import work_precision

from test_codegen import pendulum, pendulum_state
from test_exact_solutions import (ball_on_turntable, ball_state, chaplygin_sleigh, sleigh_exact,
                                  sleigh_state)


@pytest.fixture(scope="module")
def sleigh():
    return numeric_model(chaplygin_sleigh())


def test_result_object_in_the_style_of_oderesult(sleigh):
    res = simulate(sleigh, (0, 3), sleigh_state(), t_eval=np.linspace(0, 3, 7), warn=False)
    assert res.success and res.status == 0 and "end" in res.message
    assert res.y.shape == (6, 7) and res.t.shape == (7,)
    assert res.states.shape == (7, 6)
    assert np.allclose(res["theta_dot"], res.y[5])
    assert res.nfev > 0 and res.nsteps > 0 and res.wall_time_s > 0
    assert res.multipliers.shape == (1, 7)
    assert res.energy.shape == (7,) and res.work.shape == (7,)
    for key in ("constraint_residual_max", "energy_drift", "energy_balance_residual",
                "cond_C_max", "cond_W_max"):
        assert np.isfinite(getattr(res, key))
    json.dumps(res.summary())  # plain numbers only
    with pytest.raises(Exception):
        res.status = 1  # frozen


def test_repr_is_one_short_line(sleigh):
    """The repr printed every array (14 KB for a longer run); now one line, the arrays
    being in .t and .y."""
    res = simulate(sleigh, (0, 30), sleigh_state(), t_eval=np.linspace(0, 30, 2000),
                   warn=False)
    text = repr(res)
    assert "\n" not in text and len(text) < 200
    assert text.startswith("<SimulationResult DOP853:") and "2000 states of 6 variables" in text


def test_system_is_accepted_directly():
    res = simulate(chaplygin_sleigh(), (0, 1), sleigh_state(), warn=False)
    assert res.success and res.model.backend in ("c", "numpy")


def test_initial_data_violating_constraints_are_refused_with_the_residual(sleigh):
    y = sleigh_state()
    y[3] += 0.01
    with pytest.raises(InconsistentInitialDataError, match=r"constraints\[0\] = "):
        simulate(sleigh, (0, 1), y, warn=False)


def test_initial_data_projected_when_asked():
    model = numeric_model(pendulum())
    y = pendulum_state() + np.array([0.01, 0.02, -0.05, 0.0])
    res = simulate(model, (0, 1), y, project_initial=True, projection=True, warn=False)
    p = res.initial_projection
    assert p.residual_before > 1e-3 and p.residual_after <= 1e-14
    assert p.displacement_q > 0 and p.displacement_v > 0
    assert res.constraint_residual_max <= 1e-12
    assert res.summary()["initial_projection"]["residual_before"] == p.residual_before


def test_initial_data_by_name_and_missing_names(sleigh):
    names = dict(zip(sleigh.names, sleigh_state()))
    assert simulate(sleigh, (0, 0.5), names, warn=False).success
    del names["theta_dot"]
    with pytest.raises(InconsistentInitialDataError, match="missing theta_dot"):
        simulate(sleigh, (0, 0.5), names, warn=False)


def test_options_are_checked(sleigh):
    y = sleigh_state()
    with pytest.raises(InputError, match="unknown method"):
        simulate(sleigh, (0, 1), y, method="Euler")
    with pytest.raises(InputError, match="needs step"):
        simulate(sleigh, (0, 1), y, method="rattle")
    with pytest.raises(InputError, match="not applicable"):
        simulate(sleigh, (0, 1), y, method="rattle", step=0.1, projection=True)
    with pytest.raises(InputError, match="alpha, beta"):
        simulate(sleigh, (0, 1), y, baumgarte=(1.0, -1.0))
    with pytest.raises(InputError, match="t_span"):
        simulate(sleigh, (1, 1), y)
    assert set(METHODS) >= {"RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA", "rattle",
                            "rattle4", "rk4", "reference"}


def blowup_system():
    """x'' = x^2 (V = -x^3/3) blows up in finite time; one trivial constraint."""
    return nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + x**3/3", ["y_dot"],
                        name="blow-up")


@pytest.mark.parametrize("method,kw", [("rk4", {"step": 0.05}), ("DOP853", {}),
                                       ("rattle", {"step": 0.05}), ("LSODA", {})])
def test_nan_or_overflow_stops_with_a_clear_status(method, kw):
    """From x = 1, x' = 1: x'^2 = 2 x^3/3 + 1/3, so x reaches infinity at
    t* = int_1^inf dx / sqrt(2x^3/3 + 1/3) = 2.3759. The run stops with status
    -2 (non-finite) or -1 (step failure) soon after (fixed steps overshoot by a
    few steps), keeps the finite part, and is never reported as a success."""
    model = numeric_model(blowup_system())
    with pytest.warns(NumericsWarning, match="run stopped"):
        res = simulate(model, (0, 10), [1.0, 0.0, 1.0, 0.0], method=method, **kw)
    assert not res.success
    assert res.status in (-1, -2, -4)
    assert np.all(np.isfinite(res.y))
    assert 2.0 < res.t[-1] < 3.0
    if res.status == -2:
        assert "non-finite" in res.message


def test_baumgarte_reduces_drift_of_the_position_constraint():
    """Pendulum, loose tolerance, no projection: g drifts; Baumgarte damps it."""
    model = numeric_model(pendulum())
    y0 = pendulum_state()
    plain = simulate(model, (0, 20), y0, method="RK45", rtol=1e-5, atol=1e-7, warn=False)
    stab = simulate(model, (0, 20), y0, method="RK45", rtol=1e-5, atol=1e-7,
                    baumgarte=(5.0, 5.0), warn=False)
    g_plain = np.max(np.abs(model.residuals(plain.states)[:, 1]))
    g_stab = np.max(np.abs(model.residuals(stab.states)[:, 1]))
    assert g_stab < 0.1 * g_plain
    assert stab.settings["baumgarte"] == (5.0, 5.0)


def test_residual_past_tolerance_warns(sleigh):
    with pytest.warns(NumericsWarning, match="constraint residual"):
        res = simulate(sleigh, (0, 20), sleigh_state(), method="RK23", rtol=1e-3, atol=1e-6,
                       residual_tol=1e-9)
    assert any("constraint residual" in w for w in res.warnings)


def test_energy_balance_for_affine_constraints():
    """Ball on turntable: E changes by O(1) but E - E0 - work stays at the
    integration error (dE/dt = lambda . h)."""
    model = numeric_model(ball_on_turntable())
    res = simulate(model, (0, 10), ball_state(model), rtol=1e-11, atol=1e-13, warn=False)
    assert res.energy_drift > 0.1
    assert res.energy_balance_residual < 1e-8


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau", "BDF", "LSODA"])
def test_projection_keeps_solver_history(sleigh, method):
    """Projecting after each step must not restart the solver: the number of
    steps stays close to the unprojected run."""
    plain = simulate(sleigh, (0, 10), sleigh_state(), method=method, warn=False)
    proj = simulate(sleigh, (0, 10), sleigh_state(), method=method, projection=True, warn=False)
    assert proj.nsteps <= 1.3 * plain.nsteps + 5
    assert proj.constraint_residual_max <= 1e-14


def test_reference_method_through_simulate(sleigh):
    res = simulate(sleigh, (0, 1.0), sleigh_state(), method="reference", reference_digits=25,
                   t_eval=[0.5, 1.0], warn=False)
    assert res.success and np.allclose(res.t, [0.5, 1.0])
    u, w, th = sleigh_exact(np.array(1.0))
    assert abs(res["theta_dot"][-1] - w) < 1e-15
    assert res.settings["digits"] == 25 and res.settings["error_estimate"] < 1e-18


def test_backward_integration(sleigh):
    fwd = simulate(sleigh, (0, 2), sleigh_state(), rtol=1e-12, atol=1e-14, warn=False)
    back = simulate(sleigh, (2, 0), fwd.y[:, -1], rtol=1e-12, atol=1e-14, warn=False)
    assert np.max(np.abs(back.y[:, -1] - sleigh_state())) < 1e-9


def test_work_precision_rows_and_time_to_solution(sleigh):
    wp = work_precision(sleigh, sleigh_state(), (0, 2.0), methods=["DOP853", "rattle"],
                        tolerances=(1e-6, 1e-10), steps=(0.05, 0.01), reference_digits=25)
    labels = [(r.method, r.setting) for r in wp.rows]
    assert ("DOP853", "rtol=1e-06") in labels and ("DOP853+projection", "rtol=1e-10") in labels
    assert ("rattle", "h=0.01") in labels
    errs = {(r.method, r.setting): r.error for r in wp.rows}
    assert errs[("DOP853", "rtol=1e-10")] < errs[("DOP853", "rtol=1e-06")] < 1e-4
    assert errs[("rattle", "h=0.01")] < errs[("rattle", "h=0.05")]
    for r in wp.rows:
        if r.method in ("rattle", "DOP853+projection"):
            assert r.constraint_residual <= 1e-12
    tts = wp.time_to_solution(1e-6)
    assert tts["DOP853"] is not None
    assert "| method |" in wp.table()
    assert wp.reference_error_estimate < 1e-18


def test_work_precision_quick_timing_and_skipped_settings(sleigh):
    """--quick: the float64 reference agrees with the sleigh's closed form; each setting
    runs `repeats` times at least (min_time 0: exactly); slow = 0 keeps only the loosest
    setting of every method and lists the others as skipped."""
    with pytest.warns(NumericsWarning, match="not 100 times below"):  # rk4 at h = 0.0025
        wp = work_precision(sleigh, sleigh_state(), (0, 2.0), quick=True,
                            methods=["DOP853", "rk4"], repeats=3, min_time=0.0)
    assert "float64 DOP853" in wp.reference and wp.reference_digits == 16
    assert wp.reference_error_estimate < 1e-11 and not wp.skipped
    assert all(r.runs == 3 for r in wp.rows)
    best = min(r.error for r in wp.rows if r.method == "DOP853")
    assert best < 1e-9  # rtol 1e-8 against the reference
    u, w, th = sleigh_exact(np.array(2.0))
    ref = simulate(sleigh, (0, 2.0), sleigh_state(), rtol=1e-13, atol=1e-16, projection=True,
                   warn=False)  # the quick reference's run
    assert abs(ref["theta"][-1] - th) < 1e-11 and abs(ref["theta_dot"][-1] - w) < 1e-11
    lean = work_precision(sleigh, sleigh_state(), (0, 2.0), quick=True,
                          methods=["DOP853", "rk4"], min_time=0.0, slow=0.0)
    assert [(r.method, r.setting) for r in lean.rows] == [
        ("DOP853", "rtol=1e-05"), ("DOP853+projection", "rtol=1e-05"), ("rk4", "h=0.04"),
        ("rk4+projection", "h=0.04")]
    assert [(m, s) for m, s, _ in lean.skipped] == [
        ("DOP853", "rtol=1e-08"), ("DOP853+projection", "rtol=1e-08"), ("rk4", "h=0.01"),
        ("rk4", "h=0.0025"), ("rk4+projection", "h=0.01"), ("rk4+projection", "h=0.0025")]
    assert "skipped: DOP853 rtol=1e-08 (DOP853 rtol=1e-05 took" in lean.describe()


def test_reference_failure_is_a_numerical_failure_saying_what():
    """C = 0 identically (a free multiplier): nothing to measure against."""
    model = numeric_model(nhham.System(["x", "y", "z"], "(x_dot**2 + y_dot**2 - z_dot**2)/2",
                                       ["y_dot + z_dot"]))
    with pytest.raises(NumericalFailure, match=r"reference solution stopped at t = 0 .*C = "
                                               r"-mu W\^-1 mu\^T is singular"):
        work_precision(model, [0.0, 0.0, 0.0, 1.0, 1.0, -1.0], (0, 1.0), quick=True)


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


def test_plots_need_matplotlib_or_say_so(tmp_path, sleigh):
    from nhham.cli.plotting import OptionalDependencyError, plot_trajectory, save_figure

    res = simulate(sleigh, (0, 1), sleigh_state(), warn=False)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        with pytest.raises(OptionalDependencyError, match="pip install"):
            plot_trajectory(res)
    else:
        path = save_figure(plot_trajectory(res), tmp_path / "t.png")
        assert (tmp_path / "t.png").exists() and path.endswith("t.png")


# ------------------------------------------------------------ compiled loop
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


def test_loop_option_is_checked(sleigh):
    numpy_model = numeric_model(chaplygin_sleigh(), backend="numpy")
    with pytest.raises(InputError, match="loop"):
        simulate(sleigh, (0, 1), sleigh_state(), loop="fortran")
    with pytest.raises(InputError, match="no compiled C backend"):
        simulate(numpy_model, (0, 1), sleigh_state(), loop="compiled")
    with pytest.raises(InputError, match="for RK23, RK45, DOP853, not 'Radau'"):
        simulate(sleigh, (0, 1), sleigh_state(), method="Radau", loop="compiled")
    res = simulate(sleigh, (0, 1), sleigh_state(), loop="scipy", warn=False)
    assert res.settings["loop"] == "scipy"
    auto = simulate(sleigh, (0, 1), sleigh_state(), warn=False)
    assert auto.settings["loop"] == ("compiled" if sleigh.backend == "c" else "scipy")


def test_dense_output_against_the_exact_solution():
    """The rolling disk: theta = theta0 + w t, x and y on a circle (closed form)."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))
    for method in ("DOP853", "Radau"):
        res = simulate(model, (0, 4), y0, method=method, rtol=1e-10, atol=1e-12,
                       dense_output=True, warn=False)
        assert res.settings["loop"] == "scipy" and res.sol is not None
        t = np.linspace(0, 4, 41)
        exact, _ = rolling_disk_exact(t)
        assert res.sol(t).shape == (8, 41) and res.sol(1.3).shape == (8,)
        assert np.max(np.abs(res.sol(t) - exact)) < 1e-6, method
        assert (res.sol.t_min, res.sol.t_max) == (0.0, 4.0)
    assert simulate(model, (0, 1), y0, warn=False).sol is None


def test_events_located_and_terminal():
    """theta = 0.3 + 1.1 t crosses 1 at t = 0.7/1.1 and 2 at t = 1.7/1.1 (closed form);
    cos(theta) changes sign downwards at theta = pi/2."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))

    def theta_is_1(t, y):
        return y[2] - 1.0

    def cos_theta(t, y):
        return np.cos(y[2])

    def theta_is_2(t, y):
        return y[2] - 2.0

    cos_theta.direction = -1
    theta_is_2.terminal = True
    res = simulate(model, (0, 5), y0, rtol=1e-11, atol=1e-12,
                   events=[theta_is_1, cos_theta, theta_is_2], warn=False)
    assert res.status == 1 and res.success and "termination event" in res.message
    assert res.t_events[0] == pytest.approx([0.7 / 1.1], abs=1e-9)
    assert res.t_events[1] == pytest.approx([(np.pi / 2 - 0.3) / 1.1], abs=1e-9)
    assert res.t[-1] == pytest.approx(1.7 / 1.1, abs=1e-9)
    exact, _ = rolling_disk_exact(np.array(res.t_events[0]))
    assert res.y_events[0].shape == (1, 8)
    assert np.allclose(res.y_events[0][0], exact[:, 0], atol=1e-8)
    with pytest.raises(InputError, match="dense_output/events"):
        simulate(model, (0, 1), y0, method="rattle", step=0.1, events=theta_is_1)
    with pytest.raises(InputError, match="dense_output and events"):
        simulate(model, (0, 1), y0, loop="compiled", dense_output=True)
