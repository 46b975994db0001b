"""Fixed-step schemes: empirical order (log-log fit against closed forms),
time reversibility, and constraint residuals of the projected and structure-
preserving methods on every test problem."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nhham.numerics.codegen import numeric_model
from nhham.errors import InputError
from nhham.numerics.integrate import simulate
from nhham.numerics.integrators import rattle_step

from test_codegen import pendulum, pendulum_state
from test_exact_solutions import (ball_exact, ball_on_turntable, ball_state, chaplygin_sleigh,
                                  knife_edge, knife_exact, nonholonomic_particle, particle_exact,
                                  rolling_disk, rolling_disk_exact, sleigh_exact, sleigh_state)


def _order(steps, errors):
    """Slope of log(error) against log(step) by least squares."""
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


def _sleigh_error(model, method, h, t_end=2.0, **kw):
    res = simulate(model, (0, t_end), sleigh_state(), method=method, step=h, warn=False, **kw)
    assert res.success
    th, xd, yd, w = res["theta"][-1], res["x_dot"][-1], res["y_dot"][-1], res["theta_dot"][-1]
    u, w_ex, th_ex = sleigh_exact(np.array(t_end))
    return max(abs(math.cos(th) * xd + math.sin(th) * yd - u), abs(w - w_ex), abs(th - th_ex))


@pytest.mark.parametrize("method,kw,order", [
    ("rattle", {}, 2), ("rattle4", {}, 4), ("rk4", {}, 4), ("rk4", {"projection": True}, 4),
    ("rk4", {"baumgarte": (2.0, 2.0)}, 4),
])
def test_empirical_order_sleigh(method, kw, order):
    """Chaplygin sleigh, error at t = 2 against the tanh/sech closed form."""
    model = numeric_model(chaplygin_sleigh())
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = [_sleigh_error(model, method, h, **kw) for h in steps]
    p = _order(steps, errors)
    assert abs(p - order) < 0.25, (method, kw, p, errors)


@pytest.mark.parametrize("method,order", [("rattle", 2), ("rattle4", 4), ("rk4", 4)])
def test_empirical_order_state_dependent_W_affine_constraints(method, order):
    """Ball on the turntable (W depends on the Euler angles; affine constraints):
    the general Newton path of RATTLE, centre position against the closed form."""
    model = numeric_model(ball_on_turntable())
    y0 = ball_state(model)
    steps = np.array([0.4, 0.2, 0.1, 0.05])
    errors = []
    for h in steps:
        res = simulate(model, (0, 2.0), y0, method=method, step=h, warn=False)
        x, y, vx, vy = ball_exact(np.array(2.0))
        errors.append(max(abs(res["x"][-1] - x), abs(res["y"][-1] - y),
                          abs(res["x_dot"][-1] - vx), abs(res["y_dot"][-1] - vy)))
    p = _order(steps, errors)
    assert abs(p - order) < 0.3, (p, errors)


def test_empirical_order_holonomic_rattle():
    """Cartesian pendulum: RATTLE (position constraint g(q1) = 0) is second
    order; the reference is a tight DOP853 run (no closed form in time)."""
    model = numeric_model(pendulum())
    y0 = pendulum_state()
    ref = simulate(model, (0, 1.0), y0, method="DOP853", rtol=1e-13, atol=1e-14,
                   projection=True, warn=False).y[:, -1]
    steps = np.array([0.02, 0.01, 0.005, 0.0025])
    errors = [np.max(np.abs(simulate(model, (0, 1.0), y0, method="rattle", step=h,
                                     warn=False).y[:, -1] - ref)) for h in steps]
    assert abs(_order(steps, errors) - 2) < 0.2


@pytest.mark.parametrize("builder,state", [
    (chaplygin_sleigh, lambda m: sleigh_state()),
    (ball_on_turntable, ball_state),
    (pendulum, lambda m: pendulum_state()),
])
def test_rattle_is_time_reversible(builder, state):
    """A step with -h from y1 returns to y0 (symmetric method), to round-off."""
    model = numeric_model(builder())
    y0 = state(model)
    for h in (0.1, 0.01):
        y1 = rattle_step(model, y0, h)
        back = rattle_step(model, y1, -h)
        assert np.max(np.abs(back - y0)) < 1e-12
        assert np.max(np.abs(y1 - y0)) > 1e-4 * h


def test_compiled_rattle_runs_backward_to_the_start():
    model = numeric_model(chaplygin_sleigh())
    fwd = simulate(model, (0, 5), sleigh_state(), method="rattle", step=0.05, warn=False)
    back = simulate(model, (5, 0), fwd.y[:, -1], method="rattle", step=0.05, warn=False)
    assert back.t[-1] == 0.0
    assert np.max(np.abs(back.y[:, -1] - sleigh_state())) < 1e-11


PROBLEMS = {
    "rolling disk": (rolling_disk, lambda m: rolling_disk_exact(np.array(0.0))[0]),
    "sleigh": (chaplygin_sleigh, lambda m: sleigh_state()),
    "particle": (nonholonomic_particle, lambda m: particle_exact(np.array(0.0))),
    "knife edge": (knife_edge, lambda m: knife_exact(np.array(0.0))),
    "turntable": (ball_on_turntable, ball_state),
    "pendulum": (pendulum, lambda m: pendulum_state()),
}

EXACT_METHODS = [
    ("rattle", {"step": 0.01}), ("rattle4", {"step": 0.02}),
    ("rk4", {"step": 0.01, "projection": True}),
    ("RK23", {"projection": True, "rtol": 1e-6}), ("RK45", {"projection": True}),
    ("DOP853", {"projection": True}), ("Radau", {"projection": True}),
    ("BDF", {"projection": True}), ("LSODA", {"projection": True}),
]


@pytest.mark.parametrize("problem", list(PROBLEMS))
def test_constraint_residual_of_projected_and_structure_preserving_methods(problem):
    """max |phi| and |g| <= 1e-12 along the run, for every projected and every
    structure-preserving method, on every test problem."""
    builder, state = PROBLEMS[problem]
    model = numeric_model(builder())
    y0 = state(model)
    for method, kw in EXACT_METHODS:
        res = simulate(model, (0, 1.5), y0, method=method, warn=False, **kw)
        assert res.success, (problem, method, res.message)
        assert res.constraint_residual_max <= 1e-12, (problem, method,
                                                      res.constraint_residual_max)


def test_rattle_refuses_non_quadratic_lagrangian():
    import nhham

    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + x*y_dot", ["y_dot - x*x_dot"])
    with pytest.raises(InputError, match="1/2 v\\^T W"):
        simulate(system, (0, 1), [0.0, 0.0, 1.0, 0.0], method="rattle", step=0.1, warn=False)
    # the scipy methods are fine with it
    assert simulate(system, (0, 1), [0.0, 0.0, 1.0, 0.0], warn=False).success


def test_fixed_step_grid_and_save_every():
    model = numeric_model(chaplygin_sleigh())
    res = simulate(model, (0, 1.0), sleigh_state(), method="rattle", step=0.03, save_every=5,
                   warn=False)
    N = math.ceil(1.0 / 0.03)
    assert res.settings["step"] == pytest.approx(1.0 / N)
    assert res.t[-1] == pytest.approx(1.0) and res.nsteps == N
    assert np.allclose(np.diff(res.t)[:-1], 5.0 / N)


@pytest.mark.parametrize("backend", ["auto", "numpy"])
@pytest.mark.parametrize("method", ["rattle", "rattle4"])
def test_rattle_converges_at_large_coordinates(backend, method):
    """Long horizons: after 1e5 turns (theta ~ 6e5, phi ~ 1e6) u = (q1 - q0)/h carries a
    round-off of eps |q| / h ~ 2e-8 that no Newton iteration removes; the test of the
    discrete constraint is relative to it. The disk started there moves as the one
    started at small angles (phi is cyclic, theta enters through cos and sin: shifted by
    2 pi k) and as the closed form."""
    model = numeric_model(rolling_disk(), backend=backend)
    turns = 2 * np.pi * 10**5
    far, _ = rolling_disk_exact(np.array(0.0), th0=0.3 + turns, ph0=1e6)
    near, _ = rolling_disk_exact(np.array(0.0))
    runs = [simulate(model, (0, 2.0), y0, method=method, step=0.01, warn=False)
            for y0 in (far, near)]
    assert all(r.success for r in runs), [r.message for r in runs]
    shift = far - near
    assert np.max(np.abs(runs[0].y[:, -1] - shift - runs[1].y[:, -1])) < 1e-7
    exact, _ = rolling_disk_exact(runs[0].t, th0=0.3 + turns, ph0=1e6)
    assert np.max(np.abs(runs[0].y - exact)) < 1e-4
    assert runs[0].constraint_residual_max < 1e-9
