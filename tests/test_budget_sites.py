"""Every broad ``except`` of the package lets a budget's expiry through.

Each test plants the expiry where the timer would deliver it (the call inside the
``try``) and checks that BudgetExceeded comes out, instead of the fallback the ``except``
takes for a genuine failure (an empty list of components, an undecided sign, a warning,
a retried point...). Before the fix each of these returned the fallback: a budget that ran
out inside ``classify --parametric`` printed a truncated verdict with exit 0.
"""

from __future__ import annotations

import random

import pytest
import sympy as sp

from nhham import System
from nhham.render.text import Steps
from nhham.errors import BudgetExceeded


def _expire(*args, **kwargs):
    raise BudgetExceeded("the budget of 1 s ran out during 'planted'")


def _disk(**params):
    x, y, th, ph = sp.symbols("x y theta phi")
    L = "(x_dot**2 + y_dot**2 + theta_dot**2 + phi_dot**2)/2"
    return System([x, y, th, ph], L, ["x_dot - cos(theta)*phi_dot",
                                       "y_dot - sin(theta)*phi_dot"], parameters=params)


# ------------------------------------------------------ the exceptional components
def _two_conditions():
    K, a, b = sp.field("a,b", sp.QQ)
    return [a - 1, b - 2], sp.symbols("a b")


@pytest.mark.parametrize("call", ["groebner", "solve"])
def test_exceptional_components_let_an_expiry_through(monkeypatch, call):
    """The lex Groebner basis and the solve beside it (issue 34: an expiry there dropped
    every component and the verdict said "generic" with exit 0)."""
    from nhham.lagrangian import components

    values, params = _two_conditions()
    assert components._components(values, params)  # a = 1, b = 2: one component
    monkeypatch.setattr(sp, call, _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        components._components(values, params)


class _Expiring(sp.Symbol):
    """A symbol whose sign question is where the timer fires."""

    @property
    def is_positive(self):
        raise BudgetExceeded("the budget of 1 s ran out during 'planted'")


def test_sign_of_a_condition_lets_an_expiry_through():
    from nhham.verdict.parametric import _no_real_solution

    with pytest.raises(BudgetExceeded, match="planted"):
        _no_real_solution([_Expiring("a")], {})


def test_sign_definite_lets_an_expiry_through(monkeypatch):
    from nhham.lagrangian import algorithm

    a = sp.Symbol("a")
    assert algorithm._sign_definite(a ** 2 + 1)
    monkeypatch.setattr(sp, "Dummy", lambda name, **kw: _Expiring(name))
    with pytest.raises(BudgetExceeded, match="planted"):
        algorithm._sign_definite(a ** 2 + 1)


def test_potential_of_a_closed_form_lets_an_expiry_through(monkeypatch):
    from nhham.lagrangian.integrability import _potential

    x, y = sp.symbols("x y")
    assert sp.expand(_potential([y, x], [x, y]) - x * y) == 0  # d(xy) = y dx + x dy
    monkeypatch.setattr(sp, "integrate", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        _potential([y, x], [x, y])


@pytest.mark.parametrize("where", [0, 1])
def test_zero_test_lets_an_expiry_through(monkeypatch, where):
    """The expression's expansion (where = 0) and a residual's (where = 1)."""
    from nhham.lagrangian.sampled import zero_test

    x = sp.Symbol("x")
    calls = []
    real = sp.expand_trig

    def expand_trig(e):
        calls.append(e)
        if len(calls) > where:
            _expire()
        return real(e)

    monkeypatch.setattr(sp, "expand_trig", expand_trig)
    with pytest.raises(BudgetExceeded, match="planted"):
        zero_test(sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1 + x, residual=[x])


def test_exact_point_over_the_parameter_field_lets_an_expiry_through(monkeypatch):
    """A singular block draws again (ZeroDivisionError); an expiry must not."""
    from sympy.polys.matrices import DomainMatrix

    from nhham.lagrangian.points import ParameterFieldSampler

    system = _disk()
    sampler = ParameterFieldSampler(system, system.phi, {}, sp.QQ, random.Random(1))
    env = sampler.point()  # the dependent velocities solved: x_dot = cos(theta) phi_dot
    assert env[sp.Symbol("x_dot")] == env[sp.Symbol("theta")].c * env[sp.Symbol("phi_dot")]
    # the solves over QQ (field_solve takes sympy's solve_den), expiring inside
    monkeypatch.setattr(DomainMatrix, "solve_den", _expire)
    monkeypatch.setattr(DomainMatrix, "lu_solve", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        sampler.point()


def test_rebuild_lets_an_expiry_through(monkeypatch):
    """rebuild turns an invalid system into an "invalid" verdict; an expiry is not one."""
    from nhham.verdict import substitution

    monkeypatch.setattr(substitution, "System", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        substitution.rebuild(_disk(), {}, None)


def test_bracket_coefficients_let_an_expiry_through(monkeypatch):
    from nhham.hamiltonian import classes_at_points
    from nhham.lagrangian.engine import Policy

    class Side:
        system = type("S", (), {"n": 5})()

    class Sampler:   # rational points are there; n > combination_size asks for floats
        on_M1 = staticmethod(lambda system, seed: object())

    monkeypatch.setattr(classes_at_points, "PointSampler", Sampler)
    monkeypatch.setattr(classes_at_points, "float_brackets", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        classes_at_points._coefficients_at_a_point(Side(), [], ["a", "b"], None,
                                                   Policy(combination_size=1), [0], 1, None)


# ------------------------------------------------------------ the system, the command
def test_singular_lagrangian_message_lets_an_expiry_through(monkeypatch):
    from nhham.errors import SingularLagrangianError

    q = sp.symbols("x y")
    L = "(x_dot + a*y_dot)**2/2"
    with pytest.raises(SingularLagrangianError):
        System(list(q), L, parameters={"a": None}).require_regular_lagrangian("it")
    system = System(list(q), L, parameters={"a": None})
    monkeypatch.setattr(sp.MutableDenseMatrix, "nullspace", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        system.require_regular_lagrangian("it")  # the message names the kernel then


def test_quoting_a_parse_error_lets_an_expiry_through(monkeypatch):
    import ast

    from nhham.system.expressions import parse_expression

    monkeypatch.setattr(ast, "get_source_segment", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        parse_expression("x[0]", {"x": sp.Symbol("x")})


def test_a_control_callable_lets_an_expiry_through():
    import numpy as np

    from nhham.numerics.scipy_loop import _control_value

    with pytest.raises(BudgetExceeded, match="planted"):
        _control_value("u", _expire, 0.0, np.zeros(2))


def test_compiler_probes_let_an_expiry_through(monkeypatch):
    import sysconfig

    from nhham.numerics.codegen import build

    monkeypatch.setattr(sysconfig, "get_paths", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        build.pyext_flags()

    class Process:
        pid, returncode = -1, 0

        def communicate(self):
            _expire()

    monkeypatch.setattr(build, "signal_group", lambda process: None)
    with pytest.raises(BudgetExceeded, match="planted"):
        build.kill_group(Process())


def test_the_trace_lets_an_expiry_through(monkeypatch):
    from nhham.render.trace import analysis_text
    from nhham.lagrangian.analysis import analyze_constraints

    analysis = analyze_constraints(_disk())
    assert "integrability of the constraint distribution" in analysis_text(analysis)
    monkeypatch.setattr(type(analysis.integrability), "describe", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        analysis_text(analysis)


def test_free_multipliers_hint_lets_an_expiry_through(monkeypatch):
    import importlib

    from nhham.lagrangian import analysis

    simulation = importlib.import_module("nhham.journeys.simulation")

    monkeypatch.setattr(analysis, "analyze_constraints", _expire)
    with pytest.raises(BudgetExceeded, match="planted"):
        simulation._free_multipliers(_disk())


def test_compare_exits_3_when_the_budget_runs_out_in_the_dirac_comparison(monkeypatch,
                                                                         capsys):
    """compare turned any NhhamError of the Dirac comparison into a warning, an expiry too:
    now exit 3, naming that step."""
    from nhham.cli.main import main
    from nhham.hamiltonian import dirac
    from tests.cli.conftest import EXAMPLES

    monkeypatch.setattr(dirac, "dirac_vs_projected", _expire)
    rc = main(["compare", str(EXAMPLES / "paper_2_1_rolling_disk.toml")])
    err = capsys.readouterr().err
    assert rc == 3
    assert "ran out during 'planted'" in err and "allow more with a larger --budget" in err


# ------------------------------------------------------------------ the step names
def test_an_expiry_between_steps_names_the_last_finished_step():
    """With --budget 20 the message said "during 'start-up'" after listing the parametric
    verdict as finished: between steps the message names the step it follows."""
    steps = Steps()
    assert steps.where() == "start-up"
    with steps.step("load scene"):
        assert steps.where() == "load scene"
    with steps.step("verdicts"):
        pass
    steps.note("a decision")  # a note is not a step
    assert steps.where() == "after 'verdicts', between steps"


def test_the_budget_message_names_a_step_and_a_gap_truly():
    import time

    from nhham.cli.budget import time_budget

    steps = Steps()
    with steps.step("verdicts"):
        pass
    with pytest.raises(BudgetExceeded) as info:
        with time_budget(0.05, steps):
            time.sleep(2)
    assert str(info.value) == "the budget of 0.05 s ran out after 'verdicts', between steps"
    with pytest.raises(BudgetExceeded) as info:
        with time_budget(0.05, steps), steps.step("the report"):
            time.sleep(2)
    assert str(info.value) == "the budget of 0.05 s ran out during 'the report'"
