"""``simulate``: the result object, initial data, failure statuses, options and
warnings (its loops: test_scipy_loop.py, test_compiled_loop.py, test_integrators.py,
test_reference.py; the work-precision driver: test_workprecision.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nhham.numerics.codegen import numeric_model
from nhham.errors import InconsistentInitialDataError, InputError
from nhham.numerics.integrate import METHODS, simulate
from nhham.numerics.model import NumericsWarning

from handmade import blowup_system
from test_codegen import pendulum, pendulum_state
from test_exact_solutions import (ball_on_turntable, ball_state, chaplygin_sleigh, sleigh_state)


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


def test_backward_integration(sleigh):
    fwd = simulate(sleigh, (0, 2), sleigh_state(), rtol=1e-12, atol=1e-14, warn=False)
    back = simulate(sleigh, (2, 0), fwd.y[:, -1], rtol=1e-12, atol=1e-14, warn=False)
    assert np.max(np.abs(back.y[:, -1] - sleigh_state())) < 1e-9


def test_plots_need_matplotlib_or_say_so(tmp_path, sleigh):
    from nhham.render.plotting import OptionalDependencyError, plot_trajectory, save_figure

    res = simulate(sleigh, (0, 1), sleigh_state(), warn=False)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        with pytest.raises(OptionalDependencyError, match="pip install"):
            plot_trajectory(res)
    else:
        path = save_figure(plot_trajectory(res), tmp_path / "t.png")
        assert (tmp_path / "t.png").exists() and path.endswith("t.png")


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


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_a_lagrangian_not_quadratic_in_v_with_a_constraint(backend):
    """L = x'^4/12 + (x'^2 + y'^2)/2 with y' = x x': W = diag(1 + x'^2, 1) depends on v,
    and the geometry kernel (W, mu, h) read q alone (an internal error, "name 'v0' is
    not defined"). By hand: p_x = x'^3/3 + x', p_y = y' = x x', d p_x/dt = lambda x,
    d p_y/dt = -lambda, so x'' (1 + x'^2 + x^2) = -x x'^2 and y' = x x'; against that
    ODE integrated by scipy."""
    import sympy as sp
    from scipy.integrate import solve_ivp

    from nhham import System

    x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    system = System([x, y], xd ** 4 / 12 + (xd ** 2 + yd ** 2) / 2, [yd - x * xd])
    model = numeric_model(system, backend=backend)
    if backend == "c" and model.backend != "c":
        pytest.skip("no C compiler")
    y0 = np.array([0.3, 0.0, 0.8, 0.24])
    res = simulate(model, (0, 2), y0, rtol=1e-11, atol=1e-12, warn=False)
    assert res.success

    def hand(t, s):
        q, p, v = s
        return [v, q * v, -q * v ** 2 / (1 + v ** 2 + q ** 2)]

    ref = solve_ivp(hand, (0, 2), [0.3, 0.0, 0.8], method="DOP853", rtol=1e-12, atol=1e-13)
    end = res.y[:, -1]
    assert np.allclose([end[0], end[1], end[2]], ref.y[:, -1], rtol=1e-8, atol=1e-9)
    assert abs(end[3] - end[0] * end[2]) < 1e-9   # on the constraint


def test_an_overflow_in_the_numpy_kernels_stops_the_run_as_non_finite():
    """x'' = e^x from x = 0, x' = sqrt(2): x'^2/2 - e^x = 0, so e^(-x/2) = 1 - t/sqrt(2)
    and x reaches infinity at t* = sqrt(2). Python's math.exp raised OverflowError in the
    numpy backend's single-state kernel (an internal error of the command); now the run
    stops there as the compiled one does, keeping the finite part."""
    from nhham import System

    model = numeric_model(System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + exp(x)", ["y_dot"]),
                          backend="numpy")
    with pytest.warns(NumericsWarning, match="run stopped"):
        res = simulate(model, (0, 3), [0.0, 0.0, np.sqrt(2), 0.0], method="rk4", step=0.01)
    assert not res.success and res.status == -2 and "non-finite" in res.message
    assert np.all(np.isfinite(res.y)) and 1.3 < res.t[-1] < 1.6


def test_a_run_from_a_state_where_W_is_infinite_stops_there():
    """W = diag(1/(2t), 1) is infinite at t = 0: the run stops at its start (non-finite),
    and the diagnostics of the state kept report cond(W) = inf (numpy's SVD of inf did
    not converge: an internal error of the command)."""
    from nhham import System

    model = numeric_model(System(["x", "y"], "x_dot**2/(4*t) + y_dot**2/2"), backend="numpy")
    with pytest.warns(NumericsWarning):
        res = simulate(model, (0, 1), [0.0, 0.0, 1.0, 1.0])
    assert not res.success and res.status == -2 and res.t.tolist() == [0.0]
    assert res.cond_W_max == np.inf
