"""The registry of integration methods against what the methods do.

Each record's capabilities (keeps the constraints, takes forces, takes time-dependent
forces, needs a quadratic L, its order, its scipy class, its loops) are checked against a
run of the method on a problem with a closed-form solution; the options of each family
are refused by the library and by the command line in the same words; and no module but
the registry writes a method's name (``test_no_method_name_outside_the_registry``).
"""

from __future__ import annotations

import ast
import doctest
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate

import nhham
from nhham.cli.parser import COMMAND_LINE, METHODS as COMMAND_METHODS
from nhham.errors import InputError, UsageError
from nhham.numerics import integrate, simulate_options
from nhham.numerics import methods as registry
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate
from nhham.numerics.methods import FAMILY_OPTIONS, METHODS, lookup, names
from nhham.numerics.simulate_options import (FixedStepOptions, ReferenceOptions, RunOptions,
                                             check_method_options, split_options)

from test_exact_solutions import chaplygin_sleigh, sleigh_exact, sleigh_state

ROOT = Path(__file__).resolve().parents[2]
ALL = list(METHODS)

#: Options each family needs to run on the small problems below.
RUN = {"adaptive": {"rtol": 1e-10, "atol": 1e-12}, "fixed-step": {"step": 0.01},
       "reference": {"reference_digits": 20}}


def _run(system, method, t_end, y0, **kw):
    return simulate(system, (0.0, t_end), y0, method=method, warn=False,
                    **RUN[METHODS[method].family], **kw)


@pytest.fixture(scope="module")
def damped():
    """x'' = -x - x'/2 (L = x'^2/2 - x^2/2, Rayleigh R = x'^2/4): a forced system."""
    return nhham.System(["x"], "x_dot**2/2 - x**2/2", dissipation="x_dot**2/4")


@pytest.fixture(scope="module")
def timed():
    """x'' = sin t: a force that depends on the time."""
    return nhham.System(["x"], "x_dot**2/2", forces={"x": "sin(t)"})


# ----------------------------------------------------------------- the records
def test_lookup_names_the_key_and_the_choices():
    assert lookup("rk4") is METHODS["rk4"] and lookup(METHODS["BDF"]) is METHODS["BDF"]
    with pytest.raises(InputError) as info:
        lookup("Euler", key="simulate.method")
    assert info.value.key == "simulate.method"
    assert "'Euler'" in str(info.value) and ", ".join(METHODS) in str(info.value)


def test_the_command_line_lists_the_registry():
    """The registry's methods, then ``auto`` (a choice among them: method_choice)."""
    assert COMMAND_METHODS == tuple(METHODS) + ("auto",)
    assert ALL[0] == registry.DEFAULT_METHOD


@pytest.mark.parametrize("name", [m for m in ALL if METHODS[m].scipy_name])
def test_every_scipy_entry_is_a_scipy_solver_of_that_order(name):
    """The class exists in scipy.integrate under the record's name, and its order is
    scipy's (the explicit Runge-Kutta classes carry ``order``; Radau IIA is of order 5;
    BDF's highest order is bdf.MAX_ORDER)."""
    method = METHODS[name]
    cls = getattr(scipy.integrate, method.scipy_name)
    assert issubclass(cls, scipy.integrate.OdeSolver) and method.load() is cls
    assert method.adaptive and method.scipy_loop
    if isinstance(getattr(cls, "order", None), int):
        assert method.order == cls.order
        assert method.compiled_loop and not method.stiff   # the explicit ones
    elif name == "Radau":
        assert method.order == 5 and "order 5" in cls.__doc__
    elif name == "BDF":
        from scipy.integrate._ivp import bdf
        assert method.order == bdf.MAX_ORDER
    assert method.stiff == (cls.__name__ in {"Radau", "BDF", "LSODA"})


def test_the_other_steppers_load():
    for method in METHODS.values():
        if method.scipy_name is None:
            assert callable(method.load()), method.name


@pytest.mark.parametrize("name", names(lambda m: m.fixed_step and not m.needs_reduction))
def test_fixed_step_order_measured_on_the_sleigh_matches_the_record(name):
    """Chaplygin sleigh: the slope of log(error at t = 2) against log(h), the error taken
    against the tanh/sech closed form, is the record's order (the sleigh has no conformal
    factor: the Hamiltonized method's order is measured on the nonholonomic particle,
    tests/numerics/test_hamiltonized.py)."""
    model = numeric_model(chaplygin_sleigh())
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = []
    for h in steps:
        res = simulate(model, (0, 2.0), sleigh_state(), method=name, step=h, warn=False)
        th, xd, yd, w = (res["theta"][-1], res["x_dot"][-1], res["y_dot"][-1],
                         res["theta_dot"][-1])
        u, w_ex, th_ex = sleigh_exact(np.array(2.0))
        errors.append(max(abs(math.cos(th) * xd + math.sin(th) * yd - u), abs(w - w_ex),
                          abs(th - th_ex)))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(slope - METHODS[name].order) < 0.3, (name, slope, errors)


# ------------------------------------------------------------ capabilities
@pytest.mark.parametrize("name", ALL)
def test_keeps_constraints_against_projection(name, sleigh):
    """A method that keeps the constraints refuses projection and keeps the sleigh's
    constraint to round-off; the others take projection, which brings it there."""
    method = METHODS[name]
    if method.needs_reduction:   # a System or model alone: refused, the scene is needed
        with pytest.raises(InputError, match="needs the Hamiltonized reduction"):
            _run(sleigh, name, 0.3, sleigh_state())
        return
    if method.keeps_constraints:
        with pytest.raises(InputError, match="keeps the constraints itself") as info:
            _run(sleigh, name, 0.3, sleigh_state(), projection=True)
        assert info.value.key == "projection"
        res = _run(sleigh, name, 0.3, sleigh_state())
    else:
        res = _run(sleigh, name, 0.3, sleigh_state(), projection=True)
    assert res.success and res.constraint_residual_max < 1e-12, res.constraint_residual_max


@pytest.mark.parametrize("name", ALL)
def test_takes_forces_against_a_damped_oscillator(name, damped):
    """x'' + x'/2 + x = 0 from x = 1: x(t) = exp(-t/4) (cos wt + sin(wt) / (4w)),
    w^2 = 15/16. A method that takes no forces refuses with the registry's reason."""
    method = METHODS[name]
    y0 = {"x": 1.0, "x_dot": 0.0}
    if not method.takes_forces:
        with pytest.raises(InputError, match=method.forces_refused) as info:
            _run(damped, name, 1.0, y0)
        assert info.value.key == "method"
        return
    res = _run(damped, name, 1.0, y0)
    w = math.sqrt(15 / 16)
    exact = math.exp(-0.25) * (math.cos(w) + math.sin(w) / (4 * w))
    assert res.success and abs(res["x"][-1] - exact) < 1e-7, (res["x"][-1], exact)


@pytest.mark.parametrize("name", names(lambda m: m.batched_jacobian))
def test_a_batched_jacobian_of_a_forced_model_on_the_python_kernels(name, damped):
    """The batched saddle kernel carries the applied power of a forced system (its
    output had no room for it: IndexError in Radau's and BDF's Jacobian)."""
    res = simulate(damped, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method=name,
                   backend="numpy", rtol=1e-10, atol=1e-12, warn=False)
    w = math.sqrt(15 / 16)
    exact = math.exp(-0.25) * (math.cos(w) + math.sin(w) / (4 * w))
    assert res.settings["backend"] == "numpy" and res.njev > 0
    assert res.success and abs(res["x"][-1] - exact) < 1e-7


@pytest.mark.parametrize("name", ALL)
def test_takes_time_against_a_driven_particle(name, timed):
    """x'' = sin t from rest (a force in t): x(t) = t - sin t; a method that takes no
    forces (RATTLE: t in L and the constraints only) refuses it for the forces."""
    method = METHODS[name]
    y0 = {"x": 0.0, "x_dot": 0.0}
    if not (method.takes_time and method.takes_forces):
        why = "time-dependent forces" if method.takes_forces else method.forces_refused
        with pytest.raises(InputError, match=why):
            _run(timed, name, 1.0, y0)
        return
    res = _run(timed, name, 1.0, y0)
    assert res.success and abs(res["x"][-1] - (1.0 - math.sin(1.0))) < 1e-8


@pytest.mark.parametrize("name", ALL)
def test_needs_quadratic_against_a_lagrangian_linear_in_the_velocities(name):
    """L = (x'^2 + y'^2)/2 + x y' with y' = x x': not of the form v^T W v / 2 - V."""
    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + x*y_dot", ["y_dot - x*x_dot"])
    y0 = [0.0, 0.0, 1.0, 0.0]
    method = METHODS[name]
    if method.needs_quadratic and not method.takes_gyroscopic:
        with pytest.raises(InputError, match=r"1/2 v\^T W"):
            _run(system, name, 0.2, y0)
    else:
        assert _run(system, name, 0.2, y0).success


@pytest.mark.parametrize("name", ALL)
def test_needs_quadratic_against_a_metric_that_depends_on_the_velocities(name):
    """L = x'^4/12 + y'^2/2 with y' = x x': W = diag(x'^2, 1) reads v."""
    system = nhham.System(["x", "y"], "x_dot**4/12 + y_dot**2/2", ["y_dot - x*x_dot"])
    y0 = [0.0, 0.0, 1.0, 0.0]
    if METHODS[name].needs_quadratic:
        with pytest.raises(InputError, match=r"1/2 v\^T W"):
            _run(system, name, 0.2, y0)
    else:
        assert _run(system, name, 0.2, y0).success


def test_compiled_loop_entries_are_those_the_compiled_loop_runs(sleigh):
    if sleigh.compiled is None:
        pytest.skip("no compiled backend here")
    for name in ALL:
        kw = {"loop": "compiled"}
        if METHODS[name].compiled_loop:
            res = _run(sleigh, name, 0.2, sleigh_state(), **kw)
            assert res.settings["loop"] == "compiled", name
        else:
            with pytest.raises(InputError, match="'compiled' is not possible"):
                _run(sleigh, name, 0.2, sleigh_state(), **kw)


def test_dense_output_and_events_only_where_scipy_s_loop_runs(sleigh):
    for name in ALL:
        if METHODS[name].scipy_loop:
            res = _run(sleigh, name, 0.2, sleigh_state(), dense_output=True)
            assert np.allclose(res.sol(0.2), res.y[:, -1]), name
        else:
            with pytest.raises(InputError, match="only with the scipy methods"):
                _run(sleigh, name, 0.2, sleigh_state(), dense_output=True)


# ----------------------------------------------------------------- options
OPTION_VALUES = {"rtol": 1e-6, "atol": 1e-9, "max_step": 0.1, "first_step": 1e-3,
                 "step": 0.1, "reference_digits": 20}


@pytest.mark.parametrize("name", ALL)
def test_options_of_another_family_are_refused_by_library_and_command_alike(name):
    """Every family option the method does not take is refused, naming it: by
    ``simulate``'s keywords (InputError, key ``rtol``) and on the command line
    (UsageError, key ``--rtol``), in the same sentence up to the spelling."""
    method = METHODS[name]
    base = {"step": 0.1} if method.fixed_step else {}
    for key in (k for family in FAMILY_OPTIONS.values() for k in family):
        if key in method.options:
            split_options(name, **{**base, key: OPTION_VALUES[key]})
            continue
        with pytest.raises(InputError) as library:
            split_options(name, **{**base, key: OPTION_VALUES[key]})
        assert library.value.key == key and type(library.value) is InputError
        with pytest.raises(UsageError) as command:
            check_method_options(name, {key}, available=base, spelling=COMMAND_LINE)
        option = "--" + key.replace("_", "-")
        assert command.value.key == option
        spelled = re.sub(r"(?<![\w-])(max_step|reference_digits|rtol|atol|first_step|step)"
                         r"(?![\w-])", lambda k: "--" + k[1].replace("_", "-"),
                         str(library.value).replace(repr(name), name))
        assert str(command.value) == spelled


def test_a_fixed_step_method_without_step_is_refused_in_both_spellings():
    with pytest.raises(InputError, match=r"method='rk4' is a fixed-step method and needs "
                                         r"step=DT \(e.g. step=0.01\)"):
        split_options("rk4")
    with pytest.raises(UsageError, match=r"--method rk4 is a fixed-step method and needs "
                                         r"--step DT \(e.g. --step 0.01\)"):
        check_method_options("rk4", set(), spelling=COMMAND_LINE)
    check_method_options("rk4", set(), available={"step"}, spelling=COMMAND_LINE)


def test_keywords_and_option_objects_give_the_same_run(sleigh):
    by_keywords = simulate(sleigh, (0, 0.5), sleigh_state(), method="rk4", step=0.05,
                           save_every=3, warn=False)
    by_objects = simulate(sleigh, (0, 0.5), sleigh_state(), method="rk4",
                          options=RunOptions(save_every=3, warn=False),
                          method_options=FixedStepOptions(0.05))
    assert np.array_equal(by_keywords.y, by_objects.y)
    assert by_objects.settings["save_every"] == 3 and by_objects.settings["step"] == 0.05
    common, own = split_options("reference", RunOptions(progress=True),
                                ReferenceOptions(25), warn=False)
    assert common.progress and not common.warn and own.digits == 25
    with pytest.raises(TypeError, match="unexpected keyword argument 'rtoll'"):
        simulate(sleigh, (0, 0.5), sleigh_state(), rtoll=1e-6)
    with pytest.raises(InputError, match="FixedStepOptions is not for adaptive") as info:
        split_options("DOP853", method_options=FixedStepOptions(0.1))
    assert info.value.key == "method_options"


# ------------------------------------------------------------ the registry alone
def test_the_registry_imports_neither_numpy_nor_scipy():
    probe = ("import sys, nhham.numerics.methods, nhham.numerics.simulate_options, "
             "nhham.study.kinds, nhham.cli.parser\n"
             "print(sorted(m for m in ('numpy', 'scipy', 'sympy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("module", [registry, simulate_options, integrate])
def test_the_examples_run(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def method_name_literals(root: Path) -> list:
    """``path:line: 'name'`` for every string constant equal to a method's name in the
    package's code, outside the registry. Docstrings, dictionary keys (JSON fields, the
    lazy exports' module names) and ``__all__`` (the steppers' function names) are not
    method names."""
    found = []
    for path in sorted((root / "nhham").rglob("*.py")):
        if path.name == "methods.py" and path.parent.name == "numerics":
            continue
        tree = ast.parse(path.read_text(), str(path))
        skip = set()
        for node in ast.walk(tree):
            body = getattr(node, "body", None)
            if isinstance(body, list) and body and isinstance(body[0], ast.Expr) and \
                    isinstance(body[0].value, ast.Constant):
                skip.add(id(body[0].value))        # a docstring
            if isinstance(node, ast.Dict):
                skip.update(id(k) for k in node.keys if k is not None)
            if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
                skip.update(id(n) for n in ast.walk(node.value))
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and node.value in METHODS and \
                    id(node) not in skip:
                found.append(f"{path.relative_to(root)}:{node.lineno}: {node.value!r}")
    return found


def test_no_method_name_outside_the_registry(tmp_path):
    assert method_name_literals(ROOT) == []
    # A planted comparison by name is found.
    planted = tmp_path / "nhham" / "numerics" / "planted.py"
    planted.parent.mkdir(parents=True)
    planted.write_text('"""Doc "rk4"."""\n\nX = {"rk4": 1}\n\n\ndef f(m):\n'
                       '    return m in ("rattle", "rattle4")\n')
    assert method_name_literals(tmp_path) == ["nhham/numerics/planted.py:7: 'rattle'",
                                              "nhham/numerics/planted.py:7: 'rattle4'"]


def test_a_scene_s_options_for_another_method_leave_out_the_table_s_tolerances():
    """The sleigh's [simulate] table gives rtol (for its adaptive method): asked for
    rattle, the scene's keywords drop it, and simulate runs them."""
    from nhham.system.scene import load_scene

    scene = load_scene(ROOT / "examples" / "chaplygin_sleigh.toml")
    assert "rtol" in scene.simulate.given()
    table = scene.simulate_options(t_end=0.1)
    assert table["rtol"] == scene.simulate.given()["rtol"]
    opts = scene.simulate_options(t_end=0.1, method="rattle", step=0.01)
    assert "rtol" not in opts and opts["step"] == 0.01
    assert simulate(scene.system, warn=False, **opts).success
    with pytest.raises(InputError, match="rtol applies to the adaptive methods"):
        simulate(scene.system, **scene.simulate_options(t_end=0.1, method="rattle",
                                                        step=0.01, rtol=1e-6))
