"""The numeric model (nhham.numerics.model): batches and single states on every backend and
path, the power of the constraint forces against the rate of the energy, parameters,
shapes, a singular saddle matrix, and the projection onto M_1."""

from __future__ import annotations

import numpy as np
import pytest

import nhham
from nhham.errors import ComputationError
from nhham.numerics.codegen import c_compiler, numeric_model

from test_codegen import pendulum, pendulum_state
from test_exact_solutions import ball_on_turntable, ball_state, chaplygin_sleigh, sleigh_state

HAVE_CC = c_compiler() is not None


def test_single_state_and_batch_agree_on_every_backend_and_path():
    """(k, 2n) batches give the single-state values, without a loop over states."""
    system = ball_on_turntable()  # W depends on q, affine constraints
    models = [numeric_model(system, backend="numpy"),
              numeric_model(system, backend="numpy", path="closed_form")]
    if HAVE_CC:
        models += [numeric_model(system, backend="c"),
                   numeric_model(system, backend="c", path="closed_form")]
    rng = np.random.default_rng(5)
    base = ball_state(models[0])
    Y = base + 0.1 * rng.normal(size=(7, base.size))
    Y = np.array([models[0].project(y).y for y in Y])
    ref = np.array([models[0].rhs(0, y) for y in Y])
    for model in models:
        batch = model.rhs(0, Y)
        assert batch.shape == Y.shape
        assert np.allclose(batch, ref, rtol=1e-11, atol=1e-12), (model.backend, model.path)
        assert np.allclose(model.multipliers(Y), [model.multipliers(y) for y in Y], atol=1e-12)
        assert np.allclose(model.energy(Y), [model.energy(y) for y in Y], rtol=1e-14)
        assert np.allclose(model.cond_C(Y), [model.cond_C(y) for y in Y], rtol=1e-10)
        assert np.allclose(model.cond_W(Y), [model.cond_W(y) for y in Y], rtol=1e-10)
        assert model.residuals(Y).shape == (7, 2)


def test_power_is_rate_of_energy():
    """-lambda . (mu v) = dE/dt: finite difference of E along the field (affine h)."""
    model = numeric_model(ball_on_turntable())
    y = ball_state(model)
    dy = model.rhs(0, y)
    eps = 1e-6
    dE = (model.energy(y + eps * dy) - model.energy(y - eps * dy)) / (2 * eps)
    assert model.power(y) == pytest.approx(dE, rel=1e-7)
    W, mu, h, g = model.geometry(y)
    assert model.power(y) == pytest.approx(float(model.multipliers(y) @ h), rel=1e-12)


def test_with_parameters_equals_regenerated_model():
    system = chaplygin_sleigh()
    model = numeric_model(system)
    other = model.with_parameters(a=0.2, I=0.7)
    fresh = numeric_model(chaplygin_sleigh(a=0.2, I=0.7))
    y = sleigh_state(a=0.2)
    assert np.allclose(other.rhs(0, y), fresh.rhs(0, y), rtol=1e-14, atol=1e-15)
    assert not np.allclose(other.rhs(0, y), model.rhs(0, y))
    with pytest.raises(KeyError):
        model.with_parameters(b=1.0)


def test_shape_errors():
    model = numeric_model(chaplygin_sleigh(), backend="numpy")
    with pytest.raises(ValueError, match="2n = 6"):
        model.rhs(0, np.zeros(5))
    with pytest.raises(ValueError):
        model.energy(np.zeros((2, 2, 6)))


def test_singular_saddle_matrix_is_reported_not_returned():
    """mu = (1, x) with W = diag(1, 0) on x's velocity... use a constraint whose
    one-form vanishes at a point: C is singular there."""
    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["x*x_dot + y*y_dot"])
    for backend in (["numpy", "c"] if HAVE_CC else ["numpy"]):
        model = numeric_model(system, backend=backend)
        dy, lam, power, status = model.evaluate(np.zeros(4))
        assert status != 0
        with pytest.raises(ComputationError, match="singular|not finite"):
            model.rhs(0, np.zeros(4))
        assert model.cond_C(np.zeros(4)) == np.inf


def test_projection_onto_M1_holonomic_and_affine():
    model = numeric_model(pendulum())
    y = pendulum_state() + np.array([0.05, -0.02, 0.1, 0.03])
    out = model.project(y)
    assert out.residual_before > 1e-2
    assert out.residual_after <= 1e-14
    assert out.newton_iterations >= 2
    assert np.max(np.abs(model.residuals(out.y))) <= 1e-14
    # Velocities are projected in the kinetic metric: the change is W-orthogonal
    # to the constraint distribution (here: parallel to the gradient of g).
    dv = out.y[2:] - y[2:]
    grad = out.y[:2]
    assert abs(dv[0] * grad[1] - dv[1] * grad[0]) < 1e-12
    ball = numeric_model(ball_on_turntable())
    yb = ball_state(ball) + 0.01
    pb = ball.project(yb)
    assert pb.newton_iterations == 0 and pb.residual_after <= 1e-14


def test_project_many_is_project_state_by_state():
    """The batched projection (studies' perturbed starts) against the one-state one, with
    a holonomic constraint (the Cartesian pendulum) and without (the sleigh)."""
    from nhham.numerics.codegen import numeric_model
    from nhham.system.models import chaplygin_sleigh, pendulum_cartesian

    rng = np.random.default_rng(5)
    for system in (chaplygin_sleigh(), pendulum_cartesian()):
        model = numeric_model(system)
        Y = rng.uniform(-1, 1, (6, 2 * model.n))
        many, moved = model.project_many(Y)
        for y, p, d in zip(Y, many, moved):
            one = model.project(y)
            assert np.allclose(p, one.y, rtol=1e-13, atol=1e-13)
            assert np.isclose(d, np.linalg.norm(one.y - y), rtol=1e-12)
        assert model.scaled_residuals(many).max() < 1e-13
