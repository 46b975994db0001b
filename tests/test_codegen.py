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
from nhham.codegen import c_compiler, numeric_model
from nhham.errors import ComputationError, MissingParameterValueError
from nhham.lagrangian import lagrangian_geometry
from nhham.numeric import NumericsWarning

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
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    code = textwrap.dedent(f"""
        import sys, types
        pkg = types.ModuleType("nhham"); pkg.__path__ = [{os.path.join(root, 'nhham')!r}]
        sys.modules["nhham"] = pkg
        import nhham.numeric, nhham.integrators, nhham.integrate, nhham.reference
        import nhham.diagnostics, nhham.workprecision
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
    assert sorted(os.listdir(tmp_path)) == files and len(files) == 1
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
