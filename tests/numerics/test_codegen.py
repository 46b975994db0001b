"""Generated numeric models against the symbolic pieces they come from.

Values are compared with the symbolic objects of nhham.lagrangian evaluated
at points of M_1 built by hand (not with the numeric model itself), and the
backends and paths are compared with each other.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.errors import ComputationError, MissingParameterValueError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.model import NumericsWarning
from nhham.numerics.status import Status

from test_exact_solutions import (ball_on_turntable, ball_state, chaplygin_sleigh, rolling_disk,
                                  sleigh_state)

HAVE_CC = c_compiler() is not None


def pendulum(m=1.3, g=9.81, l=0.8):
    """Cartesian pendulum: L = m/2 (x'^2 + y'^2) - m g y, x^2 + y^2 - l^2 = 0."""
    xd, yd = sp.symbols("x_dot y_dot")
    x, y = sp.symbols("x y")
    mm, gg, ll = sp.symbols("m g l")
    return nhham.System(["x", "y"], mm * (xd**2 + yd**2) / 2 - mm * gg * y,
                        holonomic=[x**2 + y**2 - ll**2],
                        parameters={"m": m, "g": g, "l": l}, name="pendulum")


def pendulum_state(angle=0.7, omega=1.1, l=0.8):
    s, c = np.sin(angle), np.cos(angle)
    return np.array([l * s, -l * c, l * c * omega, l * s * omega])


def _disk_point(rng):
    th, phd = rng.uniform(-3, 3), rng.normal()
    return np.array([rng.normal(), rng.normal(), th, rng.normal(),
                     0.7 * np.cos(th) * phd, 0.7 * np.sin(th) * phd, rng.normal(), phd])


def _symbolic_at(system, expr_matrix, y):
    sub = dict(zip(system.state, y))
    sub.update(system.parameter_values)
    return np.array(sp.Matrix(expr_matrix).xreplace(sub).evalf(), dtype=float)


@pytest.fixture(scope="module")
def disk():
    return rolling_disk()


@pytest.fixture(scope="module")
def disk_models(disk):
    models = {"numpy": numeric_model(disk, backend="numpy")}
    if HAVE_CC:
        models["c"] = numeric_model(disk, backend="c")
    models["closed"] = numeric_model(disk, backend="numpy", path="closed_form")
    return models


def test_field_and_multipliers_match_symbolic(disk, disk_models):
    """rhs and lambda equal P(xi_L) and the multipliers of nhham.lagrangian."""
    G = lagrangian_geometry(disk)
    rng = np.random.default_rng(3)
    for _ in range(4):
        y = _disk_point(rng)
        field = _symbolic_at(disk, G.projected_field, y)[:, 0]
        lam = _symbolic_at(disk, G.multipliers, y)[:, 0]
        for name, model in disk_models.items():
            assert np.allclose(model.rhs(0.0, y), field, rtol=1e-12, atol=1e-12), name
            assert np.allclose(model.multipliers(y), lam, rtol=1e-12, atol=1e-12), name


def test_energy_condition_numbers_residuals_match_symbolic(disk, disk_models):
    G = lagrangian_geometry(disk)
    rng = np.random.default_rng(4)
    y = _disk_point(rng)
    y[4] += 1e-3  # off M_1: residuals are not zero
    model = disk_models["numpy"]
    E = float(_symbolic_at(disk, sp.Matrix([G.energy]), y)[0, 0])
    W = _symbolic_at(disk, G.hessian, y)
    C = _symbolic_at(disk, G.constraint_matrix, y)
    phi = _symbolic_at(disk, sp.Matrix(disk.phi), y)[:, 0]
    assert model.energy(y) == pytest.approx(E, rel=1e-14)
    assert model.cond_W(y) == pytest.approx(np.linalg.cond(W), rel=1e-12)
    assert model.cond_C(y) == pytest.approx(np.linalg.cond(C), rel=1e-10)
    assert np.allclose(model.residuals(y), phi, atol=1e-15)
    assert model.residual_names == ("constraints[0]", "constraints[1]")


@pytest.mark.parametrize("lagrangian", [
    # linear (magnetic) terms b . v and a potential: E = T + V
    "m*(x_dot**2 + y_dot**2)/2 + B*(x*y_dot - y*x_dot)/2 - k*(x**2 + y**2)/2 - k*cos(y)",
    # not quadratic in the velocities
    "x_dot**4/12 + m*x_dot**2/2 + m*y_dot**2/2 + B*sin(x)*y_dot - k*cos(x)",
])
def test_energy_and_derivative_kernels_against_sympy(lagrangian):
    """E_L, dL/dq and d(phi)/dq of the generated kernels against sympy's diff of the
    same expressions, computed here."""
    x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    m, B, k = sp.symbols("m B k")
    L = sp.sympify(lagrangian, locals={"B": B})
    phi = [xd * sp.cos(y) + yd * sp.sin(x) + x * y]
    values = {"m": 1.3, "B": 0.7, "k": 2.1}
    system = nhham.System(["x", "y"], L, phi, parameters=values)
    model = numeric_model(system, backend="numpy")
    sub0 = {m: 1.3, B: 0.7, k: 2.1}
    E = xd * sp.diff(L, xd) + yd * sp.diff(L, yd) - L
    rng = np.random.default_rng(11)
    for state in rng.normal(size=(4, 4)):
        sub = {**sub0, **dict(zip((x, y, xd, yd), state))}
        assert model.energy(state) == pytest.approx(float(E.subs(sub)), rel=1e-13, abs=1e-13)
        lq = [float(sp.diff(L, q).subs(sub)) for q in (x, y)]
        assert np.allclose(model.lagrangian_q(state), lq, rtol=1e-13, atol=1e-13)
        jphi = [[float(sp.diff(f, q).subs(sub)) for q in (x, y)] for f in phi]
        assert np.allclose(model.constraint_jacobian_q(state), jphi, rtol=1e-13, atol=1e-13)


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


def test_generated_code_shares_subexpressions_and_hides_user_names(disk_models):
    src = disk_models["numpy"].python_source
    assert "_t0 = " in src  # cse temporaries
    assert "theta" not in src and "phi_dot" not in src  # safe generated names only
    if HAVE_CC:
        assert "lu_solve" in disk_models["c"].c_source


def test_numeric_side_never_imports_sympy():
    """Load the numeric modules without nhham/__init__ (which needs sympy for
    System) and check that sympy was not imported."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    code = textwrap.dedent(f"""
        import sys, types
        pkg = types.ModuleType("nhham"); pkg.__path__ = [{os.path.join(root, 'nhham')!r}]
        sys.modules["nhham"] = pkg
        import nhham.numerics.model, nhham.numerics.integrators, nhham.numerics.integrate, nhham.numerics.reference
        import nhham.numerics.diagnostics, nhham.numerics.workprecision
        assert "sympy" not in sys.modules, "sympy imported by the numeric side"
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_missing_parameter_value_is_named():
    xd, = sp.symbols("x_dot"),
    system = nhham.System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - k*x**2/2",
                          ["y_dot - x*x_dot"], parameters={"m": 1.0, "k": None})
    with pytest.raises(MissingParameterValueError, match="k"):
        numeric_model(system)
    model = numeric_model(system, parameters={"k": 2.0}, backend="numpy")
    assert model.parameters == {"m": 1.0, "k": 2.0}
    with pytest.raises(MissingParameterValueError, match="spring"):
        numeric_model(system, parameters={"k": 2.0, "spring": 1.0})


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


def test_fallback_to_numpy_without_compiler(monkeypatch):
    monkeypatch.setenv("NHHAM_NO_CC", "1")
    auto = numeric_model(chaplygin_sleigh(), backend="auto")
    assert auto.backend == "numpy" and "compiler" in auto.backend_note
    with pytest.warns(NumericsWarning, match="C backend unavailable"):
        forced = numeric_model(chaplygin_sleigh(), backend="c")
    assert forced.backend == "numpy"
    y = sleigh_state()
    assert np.allclose(forced.rhs(0, y), auto.rhs(0, y))


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")
def test_compiled_library_is_cached(tmp_path):
    a = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(tmp_path))
    files = sorted(os.listdir(tmp_path))
    b = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(tmp_path))
    assert a.backend == b.backend == "c"
    library = os.path.basename(a.compiled.path)
    assert files == sorted([".lock", library, library + ".sha256"])
    assert sorted(os.listdir(tmp_path)) == files
    assert a.compiled.path == b.compiled.path


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


# ------------------------------------------------- compiled solver and entries
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
    """The compiled saddle solve (Cholesky + Schur complement for positive
    definite W; LU when W is indefinite or nearly singular) and the numpy path
    give the symbolic field P(xi_L) and multipliers at points of M_1; batches
    give the single-state values."""
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


def test_angle_sums_expanded_only_when_no_new_calls():
    """sin/cos(theta_i - theta_j) become products of the sin/cos of the angles
    when those are computed anyway (the snake: one sincos per angle instead of
    one per pair); otherwise (the snakeboard's theta +- phi) they are kept."""
    from nhham.numerics.codegen.emit import expand_angle_sums

    a, b, c = sp.symbols("a b c", real=True)
    out = expand_angle_sums([sp.sin(a - b) + sp.cos(a) * sp.sin(b)], [a, b])
    assert out[0].atoms(sp.sin, sp.cos) <= {sp.sin(a), sp.cos(a), sp.sin(b), sp.cos(b)}
    assert sp.simplify(out[0] - sp.sin(a - b) - sp.cos(a) * sp.sin(b)) == 0
    kept = [sp.sin(a + b) * sp.cos(b)]  # sin(a) / cos(a) not computed: no gain
    assert expand_angle_sums(kept, [a, b]) == kept
    three = expand_angle_sums([sp.cos(a + b - c), sp.sin(a), sp.cos(b), sp.sin(c)], [a, b, c])
    assert sp.simplify(three[0] - sp.cos(a + b - c)) == 0
    if HAVE_CC:
        snake = numeric_model(nhham.models.snake(5), backend="c")
        saddle = snake.c_source.split("static void saddle(")[-1].split("\n}\n")[0]
        calls = saddle.count("sin(") + saddle.count("cos(")
        assert calls == 2 * 5  # one sin and one cos per link angle


def test_cpython_entry_points_and_their_fallbacks():
    """The single-state calls through the CPython entry points return fresh
    arrays equal to the ctypes route; inputs they do not take (lists, strided
    or float32 arrays, batches, wrong lengths) go through the general path
    with the same values and errors."""
    system = chaplygin_sleigh()
    ref_model = numeric_model(system, backend="numpy")
    model = numeric_model(system)
    y = sleigh_state()
    ref = ref_model.rhs(0, y)
    a, b = model.rhs(0, y), model.rhs(0, y)
    assert a is not b and np.allclose(a, ref, rtol=1e-13, atol=1e-14)
    a[:] = 0.0
    assert np.allclose(model.rhs(0, y), ref, rtol=1e-13, atol=1e-14)
    strided = np.zeros((6, 2))
    strided[:, 0] = y
    for variant in (list(y), strided[:, 0], y.astype(np.float32)):
        assert np.allclose(model.rhs(0, variant), ref_model.rhs(0, np.asarray(variant, float)),
                           rtol=1e-12, atol=1e-13)
    assert model.rhs(0, np.array([y, y])).shape == (2, 6)
    with pytest.raises(ValueError, match="2n = 6"):
        model.rhs(0, np.zeros(5))
    dy, lam, P, status = model.evaluate(y)
    dy0, lam0, P0, _ = ref_model.evaluate(y)
    assert status == 0 and np.allclose(dy, dy0) and np.allclose(lam, lam0)
    assert P == pytest.approx(P0, abs=1e-13)
    for m in (model, ref_model):
        f = m.field_function()
        z = np.append(y, 123.0)  # the last entry (the work) is ignored
        assert np.allclose(f(z), np.append(ref, P0), rtol=1e-13, atol=1e-13)
        assert np.allclose(f(y), np.append(ref, P0), rtol=1e-13, atol=1e-13)
        fb = m.field_function((1.0, 2.0))
        dyb = ref_model.evaluate(y, (1.0, 2.0))[0]
        assert np.allclose(fb(z)[:6], dyb, rtol=1e-13, atol=1e-13)
    if HAVE_CC and model.compiled.ext is not None:
        block = model.parameter_block()
        out, status = model.compiled.one(y, block.pointer)
        assert status == 0 and np.allclose(model.compiled.ext.rhs(y, block.address), out[:6])
        assert "CPython" in model.backend_note
    singular = numeric_model(nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2",
                                          ["x*x_dot + y*y_dot"]))
    assert singular.field_function()(np.zeros(4)) == Status.SINGULAR


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")
def test_without_python_headers_the_plain_library_is_used(monkeypatch, tmp_path):
    """When the CPython entry points cannot be built (no Python.h, say), the
    plain ctypes library is built instead, says so, gives the same values, and
    later models with the same source do not try again (the failure is kept in the
    cache, beside where the library would be)."""
    import nhham.numerics.codegen.build as build
    from nhham.numerics.integrate import simulate

    monkeypatch.setattr(build, "pyext_flags",
                        lambda: (["-DNHHAM_PYEXT", "-I/nonexistent-include"], "none"))
    with pytest.warns(NumericsWarning, match="CPython entry points could not be built"):
        model = numeric_model(chaplygin_sleigh(), cache_dir=str(tmp_path))
    assert model.backend == "c" and model.compiled.ext is None
    assert "CPython entry points unavailable" in model.backend_note
    assert [f for f in os.listdir(tmp_path) if f.endswith(".failed")]
    y = sleigh_state()
    ref = numeric_model(chaplygin_sleigh(), backend="numpy")
    assert np.allclose(model.rhs(0, y), ref.rhs(0, y), rtol=1e-13, atol=1e-14)
    res = simulate(model, (0, 1), y, warn=False)
    assert res.settings["loop"] == "compiled" and res.success
    with pytest.warns(NumericsWarning, match="Python.h.*remembered in"):
        again = numeric_model(chaplygin_sleigh(m=2.0), cache_dir=str(tmp_path))
    assert again.compiled.ext is None and "unavailable" in again.backend_note


def test_generated_sources_are_kept_by_content_not_by_identity():
    """Equal systems share their generated sources; a system is not kept alive by them;
    a different system, or another path, gets its own."""
    import gc
    import weakref

    from nhham.numerics.codegen.emit import generate_sources, system_fingerprint

    a, b = chaplygin_sleigh(), chaplygin_sleigh()
    assert a is not b and system_fingerprint(a) == system_fingerprint(b)
    assert generate_sources(a) is generate_sources(b)
    assert system_fingerprint(a) != system_fingerprint(a, "closed_form")
    assert system_fingerprint(rolling_disk()) != system_fingerprint(a)
    ref = weakref.ref(a)
    numeric_model(a, backend="numpy")
    del a
    gc.collect()
    assert ref() is None
