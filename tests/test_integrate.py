"""``simulate``: the result object, initial data, failure statuses, options,
warnings, the reference method and the work-precision driver."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import nhham
from nhham.codegen import numeric_model
from nhham.errors import InconsistentInitialDataError, InputError
from nhham.integrate import METHODS, simulate
from nhham.numeric import NumericsWarning
from nhham.workprecision import work_precision

from test_codegen import pendulum, pendulum_state
from test_exact_solutions import (ball_on_turntable, ball_state, chaplygin_sleigh, sleigh_exact,
                                  sleigh_state)


@pytest.fixture(scope="module")
def sleigh():
    return numeric_model(chaplygin_sleigh())


def test_result_object_in_the_style_of_oderesult(sleigh):
    res = simulate(sleigh, sleigh_state(), (0, 3), t_eval=np.linspace(0, 3, 7), warn=False)
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


def test_system_is_accepted_directly():
    res = simulate(chaplygin_sleigh(), sleigh_state(), (0, 1), warn=False)
    assert res.success and res.model.backend in ("c", "numpy")


def test_initial_data_violating_constraints_are_refused_with_the_residual(sleigh):
    y = sleigh_state()
    y[3] += 0.01
    with pytest.raises(InconsistentInitialDataError, match=r"constraints\[0\] = "):
        simulate(sleigh, y, (0, 1), warn=False)


def test_initial_data_projected_when_asked():
    model = numeric_model(pendulum())
    y = pendulum_state() + np.array([0.01, 0.02, -0.05, 0.0])
    res = simulate(model, y, (0, 1), project_initial=True, projection=True, warn=False)
    p = res.initial_projection
    assert p.residual_before > 1e-3 and p.residual_after <= 1e-14
    assert p.displacement_q > 0 and p.displacement_v > 0
    assert res.constraint_residual_max <= 1e-12
    assert res.summary()["initial_projection"]["residual_before"] == p.residual_before


def test_initial_data_by_name_and_missing_names(sleigh):
    names = dict(zip(sleigh.names, sleigh_state()))
    assert simulate(sleigh, names, (0, 0.5), warn=False).success
    del names["theta_dot"]
    with pytest.raises(InconsistentInitialDataError, match="missing theta_dot"):
        simulate(sleigh, names, (0, 0.5), warn=False)


def test_options_are_checked(sleigh):
    y = sleigh_state()
    with pytest.raises(InputError, match="unknown method"):
        simulate(sleigh, y, (0, 1), method="Euler")
    with pytest.raises(InputError, match="needs step"):
        simulate(sleigh, y, (0, 1), method="rattle")
    with pytest.raises(InputError, match="not applicable"):
        simulate(sleigh, y, (0, 1), method="rattle", step=0.1, projection=True)
    with pytest.raises(InputError, match="alpha, beta"):
        simulate(sleigh, y, (0, 1), baumgarte=(1.0, -1.0))
    with pytest.raises(InputError, match="t_span"):
        simulate(sleigh, y, (1, 1))
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
        res = simulate(model, [1.0, 0.0, 1.0, 0.0], (0, 10), method=method, **kw)
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
    plain = simulate(model, y0, (0, 20), method="RK45", rtol=1e-5, atol=1e-7, warn=False)
    stab = simulate(model, y0, (0, 20), method="RK45", rtol=1e-5, atol=1e-7,
                    baumgarte=(5.0, 5.0), warn=False)
    g_plain = np.max(np.abs(model.residuals(plain.states)[:, 1]))
    g_stab = np.max(np.abs(model.residuals(stab.states)[:, 1]))
    assert g_stab < 0.1 * g_plain
    assert stab.settings["baumgarte"] == (5.0, 5.0)


def test_residual_past_tolerance_warns(sleigh):
    with pytest.warns(NumericsWarning, match="constraint residual"):
        res = simulate(sleigh, sleigh_state(), (0, 20), method="RK23", rtol=1e-3, atol=1e-6,
                       residual_tol=1e-9)
    assert any("constraint residual" in w for w in res.warnings)


def test_energy_balance_for_affine_constraints():
    """Ball on turntable: E changes by O(1) but E - E0 - work stays at the
    integration error (dE/dt = lambda . h)."""
    model = numeric_model(ball_on_turntable())
    res = simulate(model, ball_state(model), (0, 10), rtol=1e-11, atol=1e-13, warn=False)
    assert res.energy_drift > 0.1
    assert res.energy_balance_residual < 1e-8


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau", "BDF", "LSODA"])
def test_projection_keeps_solver_history(sleigh, method):
    """Projecting after each step must not restart the solver: the number of
    steps stays close to the unprojected run."""
    plain = simulate(sleigh, sleigh_state(), (0, 10), method=method, warn=False)
    proj = simulate(sleigh, sleigh_state(), (0, 10), method=method, projection=True, warn=False)
    assert proj.nsteps <= 1.3 * plain.nsteps + 5
    assert proj.constraint_residual_max <= 1e-14


def test_reference_method_through_simulate(sleigh):
    res = simulate(sleigh, sleigh_state(), (0, 1.0), method="reference", reference_digits=25,
                   t_eval=[0.5, 1.0], warn=False)
    assert res.success and np.allclose(res.t, [0.5, 1.0])
    u, w, th = sleigh_exact(np.array(1.0))
    assert abs(res["theta_dot"][-1] - w) < 1e-15
    assert res.settings["digits"] == 25 and res.settings["error_estimate"] < 1e-18


def test_backward_integration(sleigh):
    fwd = simulate(sleigh, sleigh_state(), (0, 2), rtol=1e-12, atol=1e-14, warn=False)
    back = simulate(sleigh, fwd.y[:, -1], (2, 0), rtol=1e-12, atol=1e-14, warn=False)
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


def test_plots_need_matplotlib_or_say_so(tmp_path, sleigh):
    from nhham.plotting import OptionalDependencyError, plot_trajectory

    res = simulate(sleigh, sleigh_state(), (0, 1), warn=False)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        with pytest.raises(OptionalDependencyError, match="pip install"):
            plot_trajectory(res, tmp_path / "t.png")
    else:
        path = plot_trajectory(res, tmp_path / "t.png")
        assert (tmp_path / "t.png").exists() and path.endswith("t.png")
