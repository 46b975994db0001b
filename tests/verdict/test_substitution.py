"""Parameter conditions substituted into a system (nhham.verdict.substitution): the
branches solving a set of conditions, their composition and canonical form, and the
system rebuilt on a branch. Expected substitutions are solved by hand."""

import sympy as sp

from nhham.verdict.results import Verdict
from nhham.verdict.substitution import branches, canonical, compose, rebuild
from parametric_systems import two_bodies

a, b, c, k, m = sp.symbols("a b c k m")
I1, I2 = sp.symbols("I1 I2")


def test_a_linear_condition_with_a_constant_coefficient_is_solved_first():
    """a*b - 2 + c = 0 is linear in each parameter; c has the constant coefficient 1:
    c = 2 - a*b (one branch), rather than a = (2 - c)/b."""
    assert branches([a * b - 2 + c], [a, b, c], {}) == [{c: 2 - a * b}]


def test_a_quadratic_condition_gives_a_branch_per_real_root():
    """m - 1 = 0 and k^2 - 4 = 0: m = 1 with k = -2 or k = 2; k^2 + 4 = 0 has no real
    root, so no branch."""
    found = branches([m - 1, k**2 - 4], [m, k], {})
    assert sorted(found, key=lambda s: s[k]) == [{m: 1, k: -2}, {m: 1, k: 2}]
    assert branches([k**2 + 4], [k], {}) == []


def test_conditions_already_met_or_never_met():
    """After a = 1, the condition a - 1 is 0 (kept as it is) and a - 2 is the nonzero
    number -1 (the branch is dropped)."""
    assert branches([a - 1, a - 1], [a], {}) == [{a: 1}]
    assert branches([a - 1, a - 2], [a], {}) == []


def test_composition_and_canonical_form():
    """{a: b + 1} then {b: 2} is {a: 3, b: 2}; the canonical form does not depend on the
    order of the keys or on how equal values are written."""
    assert compose({a: b + 1}, {b: 2}) == {a: 3, b: 2}
    assert canonical({a: 3, b: 2}) == canonical({b: 2, a: sp.Integer(6) / 2})
    assert canonical({a: (b + 1) ** 2 - b**2}) == canonical({a: 2 * b + 1})
    assert canonical({a: 3}) != canonical({a: 4})


def test_rebuilt_systems():
    """two_bodies, L = (I1 x1'^2 - I2 x2'^2)/2 - k x1^2/2: with I2 = I1 it is a valid
    system in the remaining parameters I1, k (W = diag(I1, -I1)); with I2 = 0 its W =
    diag(I1, 0) is singular and the case is "invalid", saying so."""
    system = two_bodies()
    equal = rebuild(system, {I2: I1}, None)
    assert [p.name for p in equal.parameters] == ["I1", "k"]
    assert sp.Matrix(equal.hessian) == sp.diag(I1, -I1)
    valued = rebuild(system, {I2: I1}, {I1: 2.0, k: 3.0})
    assert {p.name: v for p, v in valued.parameter_values.items()} == {"I1": 2.0, "k": 3.0}
    singular = rebuild(system, {I2: sp.Integer(0)}, None)
    assert isinstance(singular, Verdict) and singular.status == "invalid"
    assert "singular" in singular.note and "det W = 0" in singular.note
