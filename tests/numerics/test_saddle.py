"""The solves of the constrained field (nhham.numerics.saddle and nullspace, and the
compiled one in C) against systems solved by hand and against the symbolic field solved
in 40-digit mpmath."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.numerics.saddle import cond_each, solve_saddle

HAVE_CC = c_compiler() is not None


def _lorentzian():
    """Indefinite W (a Lorentzian metric, as in the paper's examples) with a
    non-null constraint: the saddle matrix is regular, W has no Cholesky factor
    (the compiled solve falls back to LU)."""
    return nhham.System(["q1", "q2", "q3"],
                        "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2 - q1**2/2 + q1*q3",
                        ["q1_dot + 2*q3_dot + q2*q2_dot"], name="Lorentzian")


def _nearly_singular_W(c=1 - 1e-12):
    """W = [[1, c, 0], [c, 1, 0], [0, 0, 1]] (cond ~ 2/(1 - c)) but positive
    definite on ker mu: the saddle matrix is well conditioned, the range-space
    method would not be (the compiled solve falls back to LU)."""
    return nhham.System(["x", "y", "z"],
                        f"(x_dot**2 + 2*{c!r}*x_dot*y_dot + y_dot**2 + z_dot**2)/2 - x**2/2 "
                        f"+ cos(y)", ["y_dot - z_dot + x*z_dot/3"], name="nearly singular W")


def _saddle_reference(system, ing, y):
    """(v, a) and lambda from the symbolic W, F, mu, drift at y, the saddle
    system solved in 40-digit mpmath (independent of the generated code)."""
    import mpmath

    sub = dict(zip(system.state, [sp.Float(float(v), 40) for v in y]))
    sub.update({p: sp.Float(float(v), 40) for p, v in system.parameter_values.items()})
    n, m = system.n, system.m
    ev = lambda M: [[mpmath.mpf(str(sp.N(e.xreplace(sub), 40))) for e in row]  # noqa: E731
                    for row in M.tolist()]
    with mpmath.workdps(40):
        W, mu = ev(ing.W), ev(ing.mu)
        F, drift = ev(sp.Matrix(ing.forcing)), ev(sp.Matrix(ing.drift))
        K = mpmath.zeros(n + m, n + m)
        b = mpmath.zeros(n + m, 1)
        for i in range(n):
            b[i] = F[i][0]
            for j in range(n):
                K[i, j] = W[i][j]
            for c in range(m):
                K[i, n + c] = K[n + c, i] = mu[c][i]
        for c in range(m):
            b[n + c] = -drift[c][0]
        z = mpmath.lu_solve(K, b)
        return (np.array([float(v) for v in y[n:]] + [float(z[i]) for i in range(n)]),
                np.array([float(z[n + c]) for c in range(m)]))


@pytest.mark.parametrize("builder", [lambda: nhham.models.snake(4), _lorentzian,
                                     _nearly_singular_W], ids=["snake4", "Lorentzian",
                                                                "nearly-singular-W"])
def test_compiled_solver_every_branch_matches_symbolic_and_numpy(builder):
    """The compiled solve of the accelerations (the null-space solve, with an indefinite
    or a nearly singular W too) and the numpy paths (one state, a batch) give the
    symbolic field P(xi_L) and multipliers at points of M_1; batches give the
    single-state values."""
    system = builder()
    ing = lagrangian_geometry(system).ingredients
    models = [numeric_model(system, backend="numpy")]
    if HAVE_CC:
        models.append(numeric_model(system, backend="c"))
    rng = np.random.default_rng(11)
    n = system.n
    states = []
    for _ in range(3):
        y = np.concatenate([rng.uniform(-0.6, 0.6, n), rng.normal(size=n)])
        states.append(models[0].project(y).y)
    Y = np.array(states)
    for y in states:
        field, lam = _saddle_reference(system, ing, y)
        scale = 1.0 + np.max(np.abs(field))
        for model in models:
            assert np.allclose(model.rhs(0.0, y), field, rtol=1e-11, atol=1e-11 * scale), (
                model.backend)
            assert np.allclose(model.multipliers(y), lam, rtol=1e-10, atol=1e-10 * scale)
    for model in models:
        assert np.allclose(model.rhs(0.0, Y), [model.rhs(0.0, y) for y in states],
                           rtol=1e-13, atol=1e-13)


def test_a_saddle_system_solved_by_hand():
    """W = diag(2, 3), mu = (1, 1), top = (1, 0), bottom = 0: 2 x1 + y = 1, 3 x2 + y = 0,
    x1 + x2 = 0 give x = (1/5, -1/5), y = 3/5. A batch of two states gives each one's."""
    W = np.diag([2.0, 3.0])
    mu = np.array([[1.0, 1.0]])
    x, y = solve_saddle(W, mu, np.array([1.0, 0.0]), np.array([0.0]))
    assert np.allclose(x, [0.2, -0.2], rtol=1e-15, atol=1e-16) and np.allclose(y, [0.6])
    Wb = np.stack([W, np.diag([1.0, 1.0])])
    mub = np.stack([mu, mu])
    xb, yb = solve_saddle(Wb, mub, np.array([[1.0, 0.0], [1.0, 0.0]]), np.zeros((2, 1)))
    # second state: x1 + y = 1, x2 + y = 0, x1 + x2 = 0 -> x = (1/2, -1/2), y = 1/2
    assert np.allclose(xb, [[0.2, -0.2], [0.5, -0.5]]) and np.allclose(yb, [[0.6], [0.5]])
    xw, yw = solve_saddle(W, np.zeros((0, 2)), np.array([1.0, 3.0]), np.zeros(0))
    assert np.allclose(xw, [0.5, 1.0]) and yw.shape == (0,)


def test_the_condition_of_C():
    """C = -mu W^-1 mu^T = -diag(1, 4) for W = Id, mu = diag(1, 2): cond 4; a singular W: inf."""
    W = np.stack([np.eye(2), np.zeros((2, 2))])
    mu = np.stack([np.diag([1.0, 2.0])] * 2)
    assert np.allclose(cond_each(W, mu), [4.0, np.inf])


def test_a_mass_ratio_of_1e16_keeps_the_constraint_to_rounding():
    """W = diag(a, b), mu = (1, 1), [[W, mu^T], [mu, 0]] [x; y] = [(1, 0); 1] by hand:
    x1 = (1 + b)/(a + b), x2 = 1 - x1, y = 1 - a x1. With a = 1e-8, b = 1e8 the
    multiplier is 1e8 times the second acceleration: without refinement the
    constraint row was met only to 1.7e-8."""
    from nhham.numerics.saddle import solve_saddle

    a, b = 1e-8, 1e8
    x, y = solve_saddle(np.diag([a, b]), np.array([[1.0, 1.0]]), np.array([1.0, 0.0]),
                        np.array([1.0]))
    x1 = (1 + b) / (a + b)
    assert abs(x[0] - x1) <= 4e-16 * x1
    assert abs(x[0] + x[1] - 1.0) <= 4e-16
    assert abs(y[0] - (1 - a * x1)) <= 4e-16
