"""The compiled RATTLE loop where W depends on q and M_1 is curved (rattle.c's
rattle_step_general): the same states as the Python stepper to round-off, the orders 2
and 4 against a closed form and a high-precision reference, the constraints at
round-off, the statuses, and the backend the result names."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.numerics import integrators
from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.numerics.integrate import simulate
from nhham.numerics.status import Status

from test_exact_solutions import sleigh_exact

needs_cc = pytest.mark.skipif(not c_compiler(), reason="no C compiler")


def blade_sleigh(m=1.0, I=0.3, a=0.5):
    """The Chaplygin sleigh in the coordinates of its blade B = (x, y) (heading theta):
    the centre of mass is G = B + a e1, so L = m/2 |B' + a theta' e2|^2 + I/2 theta'^2
    has W(theta); the blade does not slide sideways: e2 . B' = 0. The same motion as
    the centre-of-mass sleigh of test_exact_solutions (u = e1 . G' = e1 . B')."""
    x, y, th = sp.symbols("x y theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    mm, ii, aa = sp.symbols("m I a")
    gx, gy = xd - aa * sp.sin(th) * thd, yd + aa * sp.cos(th) * thd
    L = mm * (gx**2 + gy**2) / 2 + ii * thd**2 / 2
    return nhham.System(["x", "y", "theta"], L, [-sp.sin(th) * xd + sp.cos(th) * yd],
                        parameters={"m": m, "I": I, "a": a}, name="blade sleigh")


def blade_state(th0=0.3, u0=0.4, w0=1.5):
    """The state of blade_sleigh with body velocities (u0, w0) (B' = u0 e1)."""
    return np.array([0.0, 0.0, th0, u0 * math.cos(th0), u0 * math.sin(th0), w0])


def hoop_sleigh(m=1.0, I=0.3, a=0.5, mb=0.4, rho=0.3):
    """The blade sleigh carrying a bead on a hoop of radius rho about its centre of
    mass: bead at G + s e1 + r e2 in the body coordinates (s, r), on the circle
    s^2 + r^2 = rho^2 (holonomic, curved: no coordinate enters it linearly). W depends
    on theta, s and r; one nonholonomic and one holonomic constraint."""
    x, y, th, s, r = sp.symbols("x y theta s r")
    xd, yd, thd, sd, rd = sp.symbols("x_dot y_dot theta_dot s_dot r_dot")
    mm, ii, aa, mb_, rh = sp.symbols("m I a mb rho")
    c, n = sp.cos(th), sp.sin(th)
    gx, gy = xd - aa * n * thd, yd + aa * c * thd
    # bead velocity: G' + s' e1 + r' e2 + theta' (s e2 - r e1)
    bx = gx + sd * c - rd * n - thd * (s * n + r * c)
    by = gy + sd * n + rd * c + thd * (s * c - r * n)
    L = mm * (gx**2 + gy**2) / 2 + ii * thd**2 / 2 + mb_ * (bx**2 + by**2) / 2
    return nhham.System(["x", "y", "theta", "s", "r"], L, [-n * xd + c * yd],
                        holonomic=[s**2 + r**2 - rh**2],
                        parameters={"m": m, "I": I, "a": a, "mb": mb, "rho": rho},
                        name="sleigh with a bead on a hoop")


def hoop_state(rho=0.3, angle=0.4, spin=2.0, th0=0.3, u0=0.5, w0=1.2):
    """A state on M_1 of hoop_sleigh: the bead at the given angle on the hoop, moving
    along it at the given rate; the blade moving along e1."""
    s, r = rho * math.cos(angle), rho * math.sin(angle)
    return np.array([0.0, 0.0, th0, s, r, u0 * math.cos(th0), u0 * math.sin(th0), w0,
                     -r * spin, s * spin])


@pytest.fixture(scope="module")
def hoop():
    return numeric_model(hoop_sleigh())


def _python_stepper(monkeypatch):
    monkeypatch.setattr(integrators, "_compiled_ok", lambda model: False)


@needs_cc
@pytest.mark.parametrize("method", ["rattle", "rattle4"])
def test_compiled_loop_gives_the_python_steppers_states(monkeypatch, hoop, method):
    """W(q), a nonholonomic and a curved holonomic row: 300 steps of the compiled loop
    and of the Python stepper (the same equations, Newton to 4 eps) agree to 1e-10 at
    every step, with the same number of steps and the same status."""
    assert hoop.backend == "c" and not hoop.constant_W and hoop.k == 1
    y0 = hoop_state()
    run = getattr(integrators, method)
    fast = run(hoop, y0, 0.0, 1.5, 0.005)
    _python_stepper(monkeypatch)
    slow = run(hoop, y0, 0.0, 1.5, 0.005)
    assert fast.status == slow.status == Status.SUCCESS
    assert fast.nsteps == slow.nsteps == 300 and np.array_equal(fast.t, slow.t)
    assert np.max(np.abs(fast.y - slow.y)) <= 1e-10
    assert np.max(np.abs(fast.y[:, -1] - y0)) > 0.1  # it moved


@needs_cc
def test_constraints_and_energy_on_a_curved_M1(hoop):
    """Along the compiled run |phi| and |g| stay at round-off (1e-12), and the energy of
    this conservative system has the small bounded error of a symmetric method."""
    res = simulate(hoop, (0, 5.0), hoop_state(), method="rattle", step=0.01, warn=False)
    assert res.success and res.settings["backend"] == "c"
    assert res.constraint_residual_max <= 1e-12
    E = hoop.energy(res.y.T)
    assert np.max(np.abs(E - E[0])) < 1e-3 * abs(E[0])


def _order(steps, errors):
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


@needs_cc
@pytest.mark.parametrize("method,order", [("rattle", 2), ("rattle4", 4)])
def test_orders_with_W_of_q_against_the_closed_form(method, order):
    """The blade sleigh (W depends on theta): error at t = 2 of the body velocities and
    the heading against the tanh/sech closed form of the sleigh."""
    model = numeric_model(blade_sleigh())
    assert model.backend == "c" and not model.constant_W
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    u, w, th = sleigh_exact(np.array(2.0))
    errors = []
    for h in steps:
        res = simulate(model, (0, 2.0), blade_state(), method=method, step=h, warn=False)
        assert res.success and res.constraint_residual_max <= 1e-13
        th1, xd, yd, w1 = res["theta"][-1], res["x_dot"][-1], res["y_dot"][-1], \
            res["theta_dot"][-1]
        errors.append(max(abs(math.cos(th1) * xd + math.sin(th1) * yd - u), abs(w1 - w),
                          abs(th1 - th)))
    assert abs(_order(steps, errors) - order) < 0.25, errors


@needs_cc
@pytest.mark.parametrize("method,order,steps", [
    ("rattle", 2, [0.02, 0.01, 0.005]), ("rattle4", 4, [0.08, 0.04, 0.02])])
def test_orders_on_a_curved_M1_against_the_reference(hoop, method, order, steps):
    """The hoop sleigh against nhham's mpmath reference (30 digits, Taylor)."""
    y0 = hoop_state()
    ref = simulate(hoop, (0, 0.4), y0, method="reference", warn=False)
    assert ref.success
    errors = [np.max(np.abs(simulate(hoop, (0, 0.4), y0, method=method, step=h,
                                     warn=False).y[:, -1] - ref.y[:, -1])) for h in steps]
    assert abs(_order(np.array(steps), errors) - order) < 0.3, errors


@needs_cc
def test_backend_named_is_the_one_that_ran(monkeypatch):
    """With a compiled library the loop runs in C (the Python stepper is never built
    into a step); without one the Python stepper runs and the result says numpy."""
    system = blade_sleigh()
    c_model, np_model = numeric_model(system), numeric_model(system, backend="numpy")

    def refuse(*args, **kwargs):
        raise AssertionError("the Python stepper ran")

    with monkeypatch.context() as patch:
        patch.setattr(integrators._RattleStepper, "step", refuse)
        res = simulate(c_model, (0, 1), blade_state(), method="rattle4", step=0.01,
                       warn=False)
    assert res.success and res.settings["backend"] == "c"
    slow = simulate(np_model, (0, 1), blade_state(), method="rattle4", step=0.01, warn=False)
    assert slow.success and slow.settings["backend"] == "numpy"
    assert np.max(np.abs(res.y - slow.y)) <= 1e-12


@needs_cc
def test_statuses_of_a_failed_step_are_the_python_steppers(monkeypatch, hoop):
    """A step far too large for Newton: both loops stop with the same status, keep the
    same states, and say where (the compiled message names the step)."""
    y0 = hoop_state(spin=40.0)
    fast = simulate(hoop, (0, 5.0), y0, method="rattle", step=0.5, warn=False)
    _python_stepper(monkeypatch)
    slow = simulate(hoop, (0, 5.0), y0, method="rattle", step=0.5, warn=False)
    assert not fast.success and fast.status == slow.status
    assert fast.status in (Status.NOT_CONVERGED, Status.SINGULAR, Status.NONFINITE)
    assert len(fast.t) == len(slow.t) and np.max(np.abs(fast.y - slow.y)) <= 1e-9
    assert "RATTLE step" in fast.message


@needs_cc
@pytest.mark.parametrize("method", ["rattle", "rattle4"])
def test_pauses_and_the_recorder_leave_the_run_unchanged(monkeypatch, capsys, hoop, method):
    """The W(q) loop hands control back every PAUSE_SECONDS (signals, --budget): with a
    pause after every step, progress on, and a recorder thinning to 16 points the kept
    states are the whole run's to the last bit."""
    y0 = hoop_state()
    whole = simulate(hoop, (0, 1), y0, method=method, step=0.01, warn=False)
    monkeypatch.setattr(integrators, "PAUSE_SECONDS", 0.0)
    capsys.readouterr()
    paused = simulate(hoop, (0, 1), y0, method=method, step=0.01, warn=False, progress=True)
    assert np.array_equal(whole.y, paused.y) and whole.nsteps == paused.nsteps == 100
    assert "(50%)" in capsys.readouterr().err
    thin = simulate(hoop, (0, 1), y0, method=method, step=0.01, warn=False, max_points=16)
    kept = np.searchsorted(whole.t, thin.t)
    assert len(thin.t) <= 16 and np.array_equal(whole.t[kept], thin.t)
    assert np.array_equal(whole.y[:, kept], thin.y)


@needs_cc
def test_whipple_bicycle_compiled_as_the_python_stepper(monkeypatch):
    """The issue's case: examples/whipple_bicycle.toml (n = 8, W(q), 4 rolling rows and
    the front contact's holonomic row on a curved M_1), 50 steps of 1 ms."""
    from pathlib import Path

    scene = nhham.load_scene(Path(__file__).resolve().parents[2] / "examples"
                             / "whipple_bicycle.toml")
    model = numeric_model(scene.system)
    y0 = model.state(scene.checked_initial())
    fast = integrators.rattle(model, y0, 0.0, 0.05, 0.001)
    _python_stepper(monkeypatch)
    slow = integrators.rattle(model, y0, 0.0, 0.05, 0.001)
    assert fast.status == slow.status == Status.SUCCESS and fast.nsteps == 50
    assert np.max(np.abs(fast.y - slow.y)) <= 1e-10
    assert np.max(np.abs(model.residuals(fast.y.T))) <= 1e-12
