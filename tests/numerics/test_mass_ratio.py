"""Extreme mass ratios: the null-space solve of the constrained accelerations
(nhham.numerics.nullspace, and ``ksolve`` in C) against closed forms.

The model problem (examples/mass_ratio.toml): L = (a x'^2 + b y'^2)/2 + x with x' + y' = 1.
By hand: a x'' = 1 - lambda, b y'' = -lambda, x'' + y'' = 0 give x'' = -y'' = 1/(a + b) and
lambda = b/(a + b); x'' is constant, so x_dot(1) - x_dot(0) = 1/(a + b).

The tolerance on x_dot(1) - 1/2 (derived): an explicit Runge-Kutta step adds h sum_i b_i k_i
to x_dot. With every stage value k_i = x'' to a few eps the increment is right to a few eps
relative, and the addition to x_dot in [1/2, 1) rounds by at most half an ulp, 2^-54. After
N steps |x_dot(1) - 1/2 - 1/(a + b)| <= c eps / (a + b) + N 2^-54, a relative error of at
most 16 eps + N 2^-54 (a + b). The saddle-point solve's error in x'' is about eps (1 + b/a):
before the null-space solve DOP853 gave relative errors 2e-12 (b/a = 1e4) .. 1 (1e16).
"""

from __future__ import annotations

import contextlib
import io
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import nhham
from nhham.numerics.linearization import linearize as linearize_state
from nhham.numerics.codegen import c_compiler
from nhham.numerics.nullspace import (diagonal_ratio, householder_rows, solve_null_space,
                                      solve_null_space_one)

EPS = np.finfo(float).eps
HALF_ULP = 2.0 ** -54          # half an ulp of a number in [1/2, 1)
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "mass_ratio.toml"
BACKENDS = ["numpy"] + (["c"] if c_compiler() is not None else [])
RATIOS = [4, 6, 8, 10, 12, 14, 16]   # b/a = 10^e, with a b = 1 (the example: e = 16)


def _masses(e):
    return 10.0 ** (-e / 2), 10.0 ** (e / 2)


def _bound(a, b, steps):
    """The relative tolerance on x_dot(1) - 1/2 of the module docstring."""
    return 16 * EPS + steps * HALF_ULP * (a + b)


@pytest.fixture(scope="module")
def models():
    system = nhham.load_scene(str(EXAMPLE)).system
    return {backend: nhham.numeric_model(system, backend=backend) for backend in BACKENDS}


def test_the_model_problem_solved_by_hand():
    """On W = diag(1, b), mu = (1, 1), top = (1, 0), bottom = 0 the null-space solves (a
    batch and one state) give x = (1, -1)/(1 + b), y = b/(1 + b) to rounding at every
    ratio; a batch gives each state its own."""
    assert diagonal_ratio(np.diag([2.0, -8.0])) == 4.0 and diagonal_ratio(np.zeros((0, 0))) == 1
    mu, top, bottom = np.array([[1.0, 1.0]]), np.array([1.0, 0.0]), np.zeros(1)
    for e in range(0, 33, 2):
        b = 10.0 ** e
        for solve in (solve_null_space, solve_null_space_one):
            x, y = solve(np.diag([1.0, b]), mu, top, bottom)
            assert abs(x[0] * (1 + b) - 1) <= 4 * EPS and abs(x[1] * (1 + b) + 1) <= 4 * EPS
            assert abs(y[0] - b / (1 + b)) <= 4 * EPS
    W = np.stack([np.diag([2.0, 3.0]), np.diag([1.0, 1e12])])
    x, y = solve_null_space(W, np.stack([mu, mu]), np.stack([top, top]), np.zeros((2, 1)))
    # 2 x1 + y = 1, 3 x2 + y = 0, x1 + x2 = 0: x = (1/5, -1/5), y = 3/5
    assert np.allclose(x[0], [0.2, -0.2], rtol=4 * EPS) and np.isclose(y[0, 0], 0.6)
    assert abs(x[1, 0] * (1 + 1e12) - 1) <= 4 * EPS


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_change_of_units_changes_no_acceleration(models, backend):
    """The model problem with x in metres, millimetres and kilometres (x = X u: a, and the
    constraint's coefficient of X', scaled by u^2 and u) at b/a = 1e0 .. 1e12: X'' =
    1/((a + b) u) to a few eps in every unit, one state and a batch, both backends. (The
    diagonal ratio, which chose the solve before, is b/a in metres and 1e6 b/a in
    millimetres: a ratio of 1e2 was solved in metres by the saddle solve, in millimetres
    by the null-space solve.)"""
    system = nhham.System(["X", "y"], "(a*u**2*X_dot**2 + b*y_dot**2)/2 + u*X",
                          ["u*X_dot + y_dot - 1"], parameters={"a": 1.0, "b": 1.0, "u": 1.0})
    base = nhham.numeric_model(system, backend=backend)
    for e in range(0, 13, 2):
        b = 10.0 ** e
        for u in (1.0, 1e-3, 1e3):
            model = base.with_parameters(b=b, u=u)
            y = np.array([0.0, 0.0, 0.5 / u, 0.5])
            want = 1.0 / ((1.0 + b) * u)
            for got in (model.evaluate(y)[0][2], model.evaluate(np.array([y, y]))[0][1, 2]):
                assert abs(got - want) <= 4 * EPS * want, (e, u, got)


def test_householder_with_row_pivoting_keeps_small_components():
    """A = Q [R; 0] with Q orthogonal; for A = (1e-6, 0, -1/2)^T the kernel vector in the
    plane of A, (1/2, 0, 1e-6)/|.|, comes out with its small component to rounding
    (LAPACK's unpivoted QR, numpy.linalg.qr: relative error 2.5e-11)."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(4, 5, 2)) * rng.choice([1e-8, 1.0, 1e8], size=(4, 5, 1))
    Q, R = householder_rows(A)
    assert np.allclose(Q[:, :, :2] @ R, A, rtol=0, atol=1e-15 * np.abs(A).max())
    assert np.allclose(np.swapaxes(Q, 1, 2) @ Q, np.eye(5), atol=1e-15)
    Q, _ = householder_rows(np.array([[1e-6], [0.0], [-0.5]]))
    kernel = Q[:, 1:]
    v = kernel @ (kernel.T @ np.array([0.5, 0.0, 1e-6]))  # the plane's kernel direction
    assert abs(v[2] / v[0] - 2e-6) <= 4 * EPS * 2e-6


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("method", ["DOP853", "RK45", "RK23", "rk4"])
def test_mass_ratios_1e4_to_1e16_through_the_library(models, backend, method):
    """x_dot(1) - 1/2 = 1/(a + b) and y_dot(1) - 1/2 = -1/(a + b) within the derived
    tolerance, for b/a = 1e4 .. 1e16, every explicit method, both backends; the result
    says the null-space solve gave the accelerations."""
    for e in RATIOS:
        a, b = _masses(e)
        model = models[backend].with_parameters(a=a, b=b)
        options = {"step": 0.01} if method == "rk4" else {"rtol": 1e-13}
        res = nhham.simulate(model, (0.0, 1.0), [0.0, 0.0, 0.5, 0.5], method=method,
                             warn=False, **options)
        assert res.success and res.kkt_solve == "null-space", (e, res.message)
        exact = 1.0 / (a + b)
        for name, sign in (("x_dot", 1.0), ("y_dot", -1.0)):
            got = sign * (res[name][-1] - 0.5)
            assert abs(got - exact) <= _bound(a, b, res.nsteps) * exact, (e, name, got)


def _run(*argv):
    from nhham.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(list(argv))
    return rc, json.loads(out.getvalue()), err.getvalue()


@pytest.mark.parametrize("e", [4, 8, 12, 16])
def test_mass_ratios_through_the_command(tmp_path, e):
    """``nhham simulate SCENE --json`` (the example at 1e16, its text at other ratios):
    x_dot(1) - 1/2 = 1/(a + b) within the derived tolerance, ``kkt_solve`` "null-space",
    no warning (cond(W) = b/a is a spread of W's diagonal, not a near-singular W)."""
    a, b = _masses(e)
    scene = EXAMPLE
    if e != 16:
        scene = tmp_path / "ratio.toml"
        scene.write_text(EXAMPLE.read_text().replace("{ a = 1e-8, b = 1e8 }",
                                                     f"{{ a = {a!r}, b = {b!r} }}"))
    rc, env, err = _run("simulate", str(scene), "--json")
    assert rc == 0 and env["warnings"] == [], err
    result = env["result"]
    assert result["kkt_solve"] == "null-space" and result["kkt_ratio_max"] == pytest.approx(b / a)
    x_dot = result["y_final"][result["state"].index("x_dot")]
    exact = 1.0 / (a + b)
    assert abs(x_dot - 0.5 - exact) <= _bound(a, b, result["steps"]) * exact


def test_a_well_scaled_system_reports_its_solve_and_ratio():
    """The Chaplygin sleigh: W = diag(m, m, I) = diag(1, 1, 1/4), ratio 4 by hand: the
    null-space solve, as everywhere, said in the result's JSON (not in its text)."""
    scene = nhham.load_scene(str(EXAMPLE.parent / "chaplygin_sleigh.toml"))
    res = nhham.simulate(scene.system, (0.0, 0.5), scene.initial, warn=False)
    assert res.kkt_solve == "null-space" and res.diagnostics.kkt_ratio_max == 4.0
    assert "null-space" not in res.describe()
    assert res.summary()["kkt_solve"] == "null-space"


_SPRING = """name = "mass ratio with a spring and damping"
coordinates = ["x", "y"]
parameters = { a = 1.0, b = %r, k = 1.0, c = 1.0 }
lagrangian = "(a*x_dot**2 + b*y_dot**2)/2 - k*x**2/2"
dissipation = "c*x_dot**2/2"
constraints = ["x_dot + y_dot - 1"]
"""


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_linearisation_of_a_steady_motion_at_extreme_ratios(backend):
    """L = (a x'^2 + b y'^2)/2 - k x^2/2, R = c x'^2/2, x' + y' = 1: by hand
    (a + b) x'' = -k x - c x', so about x = 0, x' = 0, y' = 1 (steady; y cyclic) the
    state matrix in (x, x_dot) is [[0, 1], [-k/(a + b), -c/(a + b)]]. With a = 1 and
    b = 1e4 .. 1e16 the complex step and the batched linearisation give it to rounding
    (the saddle solve: relative errors 1.7e-13 at 1e4, 1.0 at 1e16)."""
    system = nhham.loads_scene(_SPRING % 1e4).system
    base = nhham.numeric_model(system, backend=backend)
    y0 = np.array([0.0, 0.0, 0.0, 1.0])
    for e in (4, 8, 12, 16):
        b = 10.0 ** e
        model = base.with_parameters(b=b)
        lin = linearize_state(model, y0, independent=["x", "y", "x_dot"], neutral=["y"])
        assert lin.coordinates == ("x", "x_dot")
        s = 1.0 + b
        expected = np.array([[0.0, 1.0], [-1.0 / s, -1.0 / s]])
        assert np.allclose(lin.matrix, expected, rtol=8 * EPS, atol=0), (e, lin.matrix)
        batch = nhham.linearize_batch(model, np.array([y0, y0]), reference=lin)
        assert np.allclose(batch.matrices, expected, rtol=8 * EPS, atol=0), e
        assert list(batch.status) == [0, 0]


_CHAIN = """name = "cart on a wheel with a bead"
coordinates = ["x", "s", "phi"]
parameters = { M = 1e12, m = 1.0, J = 1.0, R = 0.5, k = 3.0, f = 2.0, tau = 1.0 }
lagrangian = "M*x_dot**2/2 + m*(x_dot + s_dot)**2/2 + J*phi_dot**2/2 - k*s**2/2 + f*(x + s) + tau*phi"
constraints = ["x_dot - R*phi_dot"]
"""


def _chain_by_hand(M, s, m=1, J=1, R=Fraction(1, 2), k=3, f=2, tau=1):
    """A heavy cart (mass M, position x) rolling on a light wheel (inertia J, radius R,
    angle phi, driven by a torque tau; rolling: x' = R phi'), a light bead (mass m) at
    x + s on a spring k, pushed by f. W = [[M + m, m, 0], [m, m, 0], [0, 0, J]] is not
    diagonal. By hand, the x, s and phi rows
        (M + m) x'' + m s'' = f - lambda,  m (x'' + s'') = f - k s,  J phi'' = tau + R lambda
    and x'' = R phi'' give x'' = (k s + tau/R) / (M + J/R^2), s'' = (f - k s)/m - x'',
    phi'' = x''/R, lambda = J x''/R^2 - tau/R (exact rationals): the wheel's phi'' is
    (tau + R lambda)/J with R lambda = -tau (1 - O(1/M)), the model problem's cancellation."""
    xdd = (k * s + tau / R) / (M + J / R ** 2)
    return xdd, Fraction(f - k * s, m) - xdd, xdd / R, J * xdd / R ** 2 - tau / R


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_stiff_chain_with_a_non_diagonal_W(backend):
    """The cart, wheel and bead of :func:`_chain_by_hand` at M/m = 1e4 .. 1e16: the
    accelerations and the multiplier to rounding against the exact rationals, one state
    and a batch (the saddle solve: phi'' wrong by 1.2e-5 at 1e12 and 9.3e-3 at 1e16; the
    null-space solve without row pivoting, at tau = 0: by 5e-9 at 1e16)."""
    base = nhham.numeric_model(nhham.loads_scene(_CHAIN).system, backend=backend)
    rng = np.random.default_rng(5)
    states = np.column_stack([rng.uniform(-1, 1, 3), rng.uniform(0.1, 1, 3),
                              rng.uniform(-3, 3, 3), rng.normal(size=3),
                              rng.normal(size=3), np.zeros(3)])
    states[:, 5] = states[:, 3] / 0.5  # on the constraint: x' = R phi'
    for tau in (1.0, 0.0):
        for e in (4, 8, 12, 16):
            model = base.with_parameters(M=10.0 ** e, tau=tau)
            dY, LAM, _, status = model.evaluate(states)
            assert status == 0
            for y, dy_batch, lam_batch in zip(states, dY, LAM):
                exact = _chain_by_hand(Fraction(10 ** e), Fraction(y[1]), tau=int(tau))
                dy, lam, _, _ = model.evaluate(y)
                for got in (np.concatenate([dy[3:], lam]),
                            np.concatenate([dy_batch[3:], lam_batch])):
                    for value, want in zip(got, exact):
                        assert abs(value - float(want)) <= 8 * EPS * abs(float(want)), (e, got)


def test_a_ratio_that_grows_along_the_run():
    """L = (x'^2 + exp(x) y'^2)/2 with x' = 1, from x = 8 and y' = 0: x = 8 + t, W =
    diag(1, e^x), so W's diagonal ratio grows as e^(8 + t) (it passed the old threshold
    4096 at t = 0.318, and the run was reported "mixed"): one solve throughout, the
    largest ratio e^9 at t = 1."""
    system = nhham.System(["x", "y"], "(x_dot**2 + exp(x)*y_dot**2)/2", ["x_dot - 1"])
    res = nhham.simulate(system, (0.0, 1.0), [8.0, 0.0, 1.0, 0.0], warn=False,
                         t_eval=np.linspace(0.0, 1.0, 11))
    assert res.kkt_solve == "null-space"
    assert res.diagnostics.kkt_ratio_max == pytest.approx(np.exp(9.0), rel=1e-12)
    assert np.allclose(res["x"], 8.0 + res.t, rtol=1e-13)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_loss_the_diagonal_ratio_does_not_see(backend):
    """The isokinetic particle (W = I: a diagonal ratio of 1): along its run the saddle
    solve's constraint rows had a backward error up to 1.4e7 eps, and the accelerations of
    its single-state and compiled solves lost 3e-9 and 1.2e-8 of their size against a
    50-digit solve of the same system (mpmath); 5.6e-13 after a refinement step. The
    null-space solve keeps them to a few eps (measured 4.4e-16)."""
    import mpmath

    from nhham.journeys import simulate as run_scene
    from nhham.numerics.kernels import columns

    scene = nhham.load_scene(str(EXAMPLE.parent / "isokinetic_particle.toml"))
    answer = run_scene(scene, t_end=10.0)
    Y = np.asarray(answer.payload["result"].y).T   # (states, 2n)
    model = nhham.numeric_model(answer.system, backend=backend)
    n, m, k = model.n, model.m, model.k
    out = model.kernels.batch("saddle", Y, model.parameter_values)
    W, F, mu, drift, _, _ = columns(out, (n * n, n, m * n, m, m, k))
    worst = 0.0
    with mpmath.workdps(40):
        for i, y in enumerate(Y):
            K = mpmath.zeros(n + m, n + m)
            for a in range(n):
                for b in range(n):
                    K[a, b] = W[i, a * n + b]
                for c in range(m):
                    K[a, n + c] = K[n + c, a] = mu[i, c * n + a]
            z = mpmath.lu_solve(K, mpmath.matrix([*map(float, F[i]), *map(float, -drift[i])]))
            exact = np.array([float(z[a]) for a in range(n)])
            got = model.evaluate(y)[0][n:]
            worst = max(worst, np.abs(got - exact).max() / np.abs(exact).max())
    assert worst <= 16 * EPS, worst
