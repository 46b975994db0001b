"""The Dirac bracket and the Dirac flow against the projected field (nhham.hamiltonian.dirac).

Expected values by hand: the Dirac bracket annihilates the second-class constraints; for
holonomic constraints the Dirac flow is the true dynamics, for the Chaplygin sleigh
X_D - X = -lambda Z with lambda derived in the test.
"""

import json
import math

import pytest
import sympy as sp

import handmade
from nhham.lagrangian.engine import Policy
import nhham
from nhham import models
from nhham.errors import ComputationError
from nhham.hamiltonian.classification import classify_constraints
from nhham.hamiltonian.dirac import dirac_bracket, dirac_vs_projected
from nhham.hamiltonian.side import hamiltonian_side


def pendulum():
    return handmade.pendulum()


def sleigh():
    return handmade.sleigh_with_values()


def on(classes, expr):
    return classes.manifold.vanishes(expr).value


def test_dirac_bracket_kills_second_class_constraints():
    c = classify_constraints(handmade.sphere_with_knife())
    D = dirac_bracket(c)
    px = c.side.momenta[0]
    x = c.side.coordinates[0]
    for chi in c.second_class_constraints:
        for f in (x * px, px**2, sp.sin(x)):
            assert sp.simplify(D(chi, f)) == 0
    Dm = dirac_bracket(c, on_manifold=True)
    for chi in c.second_class_constraints:
        assert on(c, Dm(chi, x * px))


def test_dirac_bracket_of_a_classification_without_constraints_is_refused():
    sampled = classify_constraints(handmade.sphere_with_knife(), method="sampled")
    for on_manifold in (False, True):
        with pytest.raises(ComputationError, match="method='exact'.*'sampled'"):
            dirac_bracket(sampled, on_manifold=on_manifold)


# ---------------------------------------------------- Dirac flow vs projected field
def test_dirac_flow_equals_projected_field_for_the_pendulum():
    report = dirac_vs_projected(pendulum())
    assert report.equal
    assert report.difference == sp.zeros(4, 1)
    assert report.max_abs_difference < 1e-12
    assert all(d.value for d in report.decisions)


def test_the_two_fields_are_formed_when_read_and_differ_by_the_difference():
    """X_D and X (formed on first reading) differ by the report's X_D - X on M_f; the
    sleigh's one constraint is first class, so X_D = X_H there; the pendulum's X is the
    side's projected field."""
    for system, which in ((pendulum(), "projected"), (sleigh(), "dirac")):
        report = dirac_vs_projected(system)
        assert "dirac_field" not in vars(report)   # not formed until read
        M, side = report.classes.manifold, report.classes.side
        XD, X = report.dirac_field, report.projected_field
        assert XD.shape == X.shape == (2 * len(side.coordinates), 1)
        for d, x, diff in zip(XD, X, report.difference):
            assert M.vanishes(d - x - diff).value
        pairs = zip(X, side.projected_field) if which == "projected" else zip(XD, side.X_H)
        for mine, theirs in pairs:
            assert M.vanishes(mine - theirs).value
    assert dirac_vs_projected(sleigh(), method="sampled").dirac_field is None


def test_dirac_flow_differs_on_the_chaplygin_sleigh():
    s = sleigh()
    report = dirac_vs_projected(s)
    x, y, th = s.coordinates
    px, py, pth = report.classes.side.momenta
    m, I, a = sp.symbols("m I a")
    c, sn = sp.cos(th), sp.sin(th)
    # One constraint, first class: no second-class set, X_D = X_H, so X_D - X = -lambda Z.
    # mu = (-s, c, -a), C = -(1/m + a^2/I), X_H(phi) = -(c p_x + s p_y) p_theta/(m I),
    # lambda = -X_H(phi)/C = -(c p_x + s p_y) p_theta/(I + m a^2); Z = (s, -c, a) d/dp.
    assert not report.equal
    lam = -(c * px + sn * py) * pth / (I + m * a**2)
    expected = [0, 0, 0, -lam * sn, lam * c, -lam * a]
    for got, want in zip(report.difference, expected):
        assert report.classes.manifold.vanishes(got - want).value
    assert report.max_abs_difference > 1e-3
    assert report.notes and "first-class" in report.notes[0]
    assert "NOT the true dynamics" in report.describe()


@pytest.mark.parametrize("make, equal", [(pendulum, True), (sleigh, False)])
def test_dirac_vs_projected_sampled_mode(make, equal):
    report = dirac_vs_projected(make(), method="sampled")
    assert report.equal is equal and report.difference is None
    assert report.decisions[0].method == "sampled" and report.samples >= 3
    json.dumps(report.to_dict())


def _coupled_holonomic():
    """Four coordinates, a q-dependent non-diagonal W (beyond the symbolic size) and two
    linear holonomic constraints: the Dirac flow is the true dynamics (holonomic)."""
    q = sp.symbols("q1:5")
    v = sp.symbols("q1_dot q2_dot q3_dot q4_dot")
    A = sp.Matrix(4, 4, lambda i, j: 2 if i == j else (1 if abs(i - j) == 1 else 0))
    A[0, 1] = A[1, 0] = sp.cos(q[3]) / 2
    L = (sp.Matrix([v]) * A * sp.Matrix(v))[0] / 2 - q[0] ** 2 - 3 * q[2]
    return nhham.System([str(x) for x in q], L, [], holonomic=[q[0] - q[1], q[2] + q[3]])


@pytest.mark.parametrize("make, equal", [(_coupled_holonomic, True),
                                         (lambda: models.snake(3), False)])
def test_dirac_vs_projected_at_exact_points(make, equal):
    """Beyond the symbolic size, X_D - X is decided at exact points of M_f: nonzero at a
    point over F_p is a proof that the Dirac flow is not the true dynamics (snake);
    holonomic constraints give zero at every rational point, with the Schwartz-Zippel
    bound."""
    system = make()
    assert not hamiltonian_side(system).symbolic_affordable
    # (the first-class combinations are not formed in closed form: not the question here)
    report = dirac_vs_projected(system, policy=Policy(samples=3, combination_size=0))
    assert report.classes.method == "exact at points"
    d = report.decisions[0]
    assert report.equal is equal and math.isnan(report.max_abs_difference)
    if equal:
        assert d.method == "exact at points" and d.error_bound < 1e-30
        assert report.components == ()
    else:
        assert d.method == "exact" and d.error_bound == 0 and report.samples == 1
        assert "a proof" in d.detail and "p_theta1" in report.components
    sampled = dirac_vs_projected(system, method="sampled", policy=Policy(combination_size=0))
    assert sampled.equal is equal and sampled.decisions[0].method == "sampled"
