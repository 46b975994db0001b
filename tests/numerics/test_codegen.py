"""Generated numeric models against the symbolic pieces they come from.

Values are compared with the symbolic objects of nhham.lagrangian evaluated
at points of M_1 built by hand (not with the numeric model itself), and the
backends and paths are compared with each other. (The model's own behaviour:
test_model.py; the sources: test_emit.py; the library: test_build.py, test_kernels.py,
test_cache.py, test_background.py; the saddle solve: test_saddle.py.)
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
from nhham.errors import MissingParameterValueError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.model import NumericsWarning

from test_exact_solutions import (chaplygin_sleigh, rolling_disk,
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
    system = nhham.System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - k*x**2/2",
                          ["y_dot - x*x_dot"], parameters={"m": 1.0, "k": None})
    with pytest.raises(MissingParameterValueError, match="k"):
        numeric_model(system)
    model = numeric_model(system, parameters={"k": 2.0}, backend="numpy")
    assert model.parameters == {"m": 1.0, "k": 2.0}
    with pytest.raises(MissingParameterValueError, match="spring"):
        numeric_model(system, parameters={"k": 2.0, "spring": 1.0})


def test_fallback_to_numpy_without_compiler(monkeypatch):
    monkeypatch.setenv("NHHAM_NO_CC", "1")
    auto = numeric_model(chaplygin_sleigh(), backend="auto")
    assert auto.backend == "numpy" and "compiler" in auto.backend_note
    with pytest.warns(NumericsWarning, match="C backend unavailable"):
        forced = numeric_model(chaplygin_sleigh(), backend="c")
    assert forced.backend == "numpy"
    y = sleigh_state()
    assert np.allclose(forced.rhs(0, y), auto.rhs(0, y))

