"""The energy-exact discrete gradient (nhham.numerics.discrete_gradient): energy and
constraints to rounding, order 2 against closed forms, symmetry, the balance with the
reactions' work for affine constraints, g = 0 for holonomic ones, and its refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import nhham
from nhham import models, numeric_model
from nhham.errors import InputError
from nhham.numerics.discrete_gradient import EnergyExactStepper, energy_exact, energy_exact_step

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
EPS = np.finfo(float).eps


def _model(name):
    return numeric_model(nhham.load_scene(str(EXAMPLES / f"{name}.toml")).system,
                         backend="numpy")


@pytest.fixture(scope="module")
def oscillator():
    return _model("contact_oscillator")


@pytest.fixture(scope="module")
def magnetic():
    return _model("contact_oscillator_magnetic")


def _oscillator_state(model):
    # x' = -y z' solved by hand: q = (0, 1, 0.5), v = (-0.5, 0.2, 0.5)
    return model.state(dict(x=0.0, y=1.0, z=0.5, x_dot=-0.5, y_dot=0.2, z_dot=0.5))


@pytest.mark.parametrize("scene", ["oscillator", "magnetic"])
def test_energy_and_constraint_to_rounding_over_1000_steps(scene, request):
    """E = 0.895 by hand (the magnetic term does no work), kept to rounding at h = 0.1;
    x' + y z' = 0 at every grid point."""
    model = request.getfixturevalue(scene)
    y0 = _oscillator_state(model)
    assert model.energy(y0) == pytest.approx(0.895, abs=1e-15)
    run = energy_exact(model, y0, 0.0, 100.0, 0.1)
    assert run.status == 0 and run.y.shape == (6, 1001)
    E = model.energy(run.y.T)
    assert np.max(np.abs(E - 0.895)) < 200 * EPS
    x_dot, y, z_dot = run.y[3], run.y[1], run.y[5]
    assert np.max(np.abs(x_dot + y * z_dot)) < 8 * EPS
    assert np.max(np.abs(run.work)) == 0.0      # linear constraints: the reactions do no work


def test_the_step_is_symmetric(oscillator, magnetic):
    """The step with -h from y1 returns to y0 (so the order is even)."""
    for model in (oscillator, magnetic):
        y0 = _oscillator_state(model)
        y1 = energy_exact_step(model, y0, 0.1)
        assert np.max(np.abs(y1 - y0)) > 1e-3
        assert np.max(np.abs(energy_exact_step(model, y1, -0.1) - y0)) < 1e-14


def _sleigh_speed(run):
    """u = x' cos(theta) + y' sin(theta), the forward speed of the centre of mass."""
    return run.y[3] * np.cos(run.y[2]) + run.y[4] * np.sin(run.y[2])


def test_order_two_against_the_sleighs_closed_form():
    """m = I = a = 1, u0 = 0, w0 = 1: u' = w^2, w' = -u w/2 keep u^2 + 2 w^2 = 2, so
    u = sqrt(2) tanh(t/sqrt(2)) (by hand); the error at t = 2 falls four-fold per halving."""
    model = numeric_model(models.chaplygin_sleigh(m=1.0, I=1.0, a=1.0), backend="numpy")
    y0 = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=0.0, y_dot=1.0, theta_dot=1.0))
    exact = math.sqrt(2.0) * math.tanh(2.0 / math.sqrt(2.0))
    errors = [abs(_sleigh_speed(energy_exact(model, y0, 0.0, 2.0, h))[-1] - exact)
              for h in (0.04, 0.02, 0.01)]
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(3.7 < r < 4.3 for r in ratios), (errors, ratios)
    assert errors[-1] < 1e-4


def test_order_two_with_the_gyroscopic_term(magnetic):
    """Against DOP853 at rtol 1e-13 (another integrator of the same equations): ratios 4."""
    y0 = _oscillator_state(magnetic)
    ref = nhham.simulate(magnetic, (0.0, 5.0), y0, method="DOP853", rtol=1e-13, atol=1e-14)
    end = np.asarray(ref.y)[:, -1] if np.shape(ref.y)[0] == 6 else np.asarray(ref.y)[-1]
    errors = [np.max(np.abs(energy_exact(magnetic, y0, 0.0, 5.0, h).y[:, -1] - end))
              for h in (0.1, 0.05, 0.025)]
    assert all(3.7 < errors[i] / errors[i + 1] < 4.3 for i in range(2)), errors


def test_affine_constraints_keep_the_balance_with_the_reactions_work():
    """The ball on a turntable: the reactions do work (E changes); E - E0 - work stays at
    rounding, and the work is the energy's change."""
    model = _model("ball_on_turntable")
    scene = nhham.load_scene(str(EXAMPLES / "ball_on_turntable.toml"))
    y0 = model.state(scene.initial)
    run = energy_exact(model, y0, 0.0, 20.0, 0.05)
    assert run.status == 0
    E = model.energy(run.y.T)
    assert np.max(np.abs(E - E[0])) > 1e-3 * abs(E[0])      # the energy does change
    assert np.max(np.abs(E - E[0] - run.work)) < 1e3 * EPS * np.max(np.abs(E))
    assert np.max(np.abs(model.residuals(run.y.T))) < 1e-13


def test_holonomic_rows_keep_g_and_the_energy():
    """The Cartesian pendulum from the bottom at 1 m/s: x^2 + y^2 = l^2 at every point,
    E = 1/2 - 9.81 (by hand) to rounding, order 2 against DOP853."""
    model = _model("pendulum_cartesian")
    y0 = model.state(dict(x=0.0, y=-1.0, x_dot=1.0, y_dot=0.0))
    run = energy_exact(model, y0, 0.0, 10.0, 0.05)
    q = run.y[:2]
    assert np.max(np.abs(q[0] ** 2 + q[1] ** 2 - 1.0)) < 16 * EPS
    assert np.max(np.abs(model.energy(run.y.T) - (0.5 - 9.81))) < 1e3 * EPS
    ref = nhham.simulate(model, (0.0, 2.0), y0, method="DOP853", rtol=1e-13, atol=1e-14)
    end = np.asarray(ref.y)[:, -1] if np.shape(ref.y)[0] == 4 else np.asarray(ref.y)[-1]
    errors = [np.max(np.abs(energy_exact(model, y0, 0.0, 2.0, h).y[:, -1] - end))
              for h in (0.02, 0.01)]
    assert 3.7 < errors[0] / errors[1] < 4.3, errors


def test_the_command_runs_it_and_reports_the_balance(tmp_path):
    """``nhham simulate --method discrete_gradient`` on the contact oscillator: the energy
    drift at rounding in the JSON report."""
    import json
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "nhham", "simulate",
                          str(EXAMPLES / "contact_oscillator.toml"), "--t-end", "20",
                          "--json"], capture_output=True, text=True, check=True)
    report = json.loads(out.stdout)["result"]
    assert report["method"] == "discrete_gradient" and report["steps"] == 200
    assert report["energy_drift_rel"] < 1e-13 and report["constraint_residual_max"] < 1e-14


@pytest.mark.parametrize("scene, why", [
    ("isokinetic_particle", "no constraint nonlinear in the velocities"),
    ("bead_on_turning_wire", "time-dependent L or constraints"),
])
def test_refusals_name_the_reason(scene, why):
    system = nhham.load_scene(str(EXAMPLES / f"{scene}.toml")).system
    model = numeric_model(system, backend="numpy")
    y0 = np.zeros(2 * model.n)
    with pytest.raises(InputError, match=why):
        nhham.simulate(model, (0.0, 1.0), y0, method="discrete_gradient", step=0.1)


def test_stepper_counts_and_newton_to_rounding(oscillator):
    st = EnergyExactStepper(oscillator)
    y = _oscillator_state(oscillator)
    for _ in range(50):
        y, work = st.step(y, 0.1)
        assert work == 0.0
    # a Jacobian kept from step to step: about eight iterations a step to rounding
    assert st.newton <= 50 * 9 and st.nfev > 0
