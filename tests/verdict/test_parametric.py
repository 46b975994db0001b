"""Verdicts for every parameter value, against cases derived by hand.

Each system below has its exceptional cases derived in its docstring; the tests check
the cases :func:`parametric_classification` reports, and verify every case by
substituting a parameter point of the case into the *ordinary* classification of a
system whose expressions carry the numbers (no parameters left to be generic about).
"""

from __future__ import annotations

import functools
import random

import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import nhham
from nhham.errors import InputError
from nhham.hamiltonian.classification import classify_constraints
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.linalg import FLOAT64
from nhham.lagrangian.exceptional import exceptional_conditions
from nhham.verdict.parametric import parametric_classification
from nhham.verdict.values import classification_at_values


# ------------------------------------------------------------------ systems
def paper_3_1(values=None):
    """Example 3.1 with a parameter in front of each term.

    L = (a v1^2 + b v2^2 - c v3^2)/2, phi = v2 + e v3. W = diag(a, b, -c), mu = (0, 1, e),
    C = -mu W^-1 mu^T = -(1/b - e^2/c) = -(c - b e^2)/(b c).

    * generic (c != b e^2): C regular (rank 1), determined, 1 stage; mu constant, so the
      distribution is integrable; one final constraint, B = 0: 1 first class.
    * c = b e^2: C = 0; xi_L(phi) = 0 (no forces), so M_f = M_1 and lambda_1 is free:
      underdetermined, 1 stage, 1 free multiplier, 1 first class.
    * a = 0, b = 0 or c = 0: W singular (dropped when a, b, c are declared positive; with
      c = b e^2 also e = 0 gives c = 0).
    """
    return nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2",
                        ["q2_dot + e*q3_dot"], parameters=values or ["a", "b", "c", "e"],
                        name="paper 3.1 with parameters")


def paper_3_2(values=None):
    """Example 3.2 with a parameter in front of each term.

    L = (a v1^2 + b v2^2 - c v3^2)/2 + d q1^2/2, phi = v1 + e v3, F = (d q1, 0, 0).
    C = -(1/a - e^2/c) = -(c - a e^2)/(a c).

    * generic: regular, determined, 1 stage, integrable, 1 first class.
    * c = a e^2, d != 0: C = 0 and xi_L(phi) = F_1/a - e F_3/c = d q1/a: secondary q1 = 0;
      on M_2 xi_L(q1) = v1: secondary v1 = 0; on M_3 Z(v1) = -1/a != 0, rank 1: determined,
      3 stages; final constraints (phi, q1, v1): {q1, v1} second class, 1 first class.
    * c = a e^2, d = 0: xi_L(phi) = 0: underdetermined, 1 stage, 1 free multiplier.
    """
    return nhham.System(["q1", "q2", "q3"],
                        "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2 + d*q1**2/2",
                        ["q1_dot + e*q3_dot"], parameters=values or ["a", "b", "c", "d", "e"],
                        name="paper 3.2 with parameters")


def rolling_disc(values=None):
    """The vertical rolling disc, the rolling written through the radius R.

    phi_1 = x' - R cos(theta) phi', phi_2 = y' - R sin(theta) phi'. ker mu is spanned by
    X_1 = d/dtheta and X_2 = d/dphi + R cos(theta) d/dx + R sin(theta) d/dy, and
    [X_1, X_2] = R(-sin(theta) d/dx + cos(theta) d/dy) is outside ker mu unless R = 0.

    * generic: regular (rank 2), determined, not integrable, 2 first class.
    * R = 0 (x' = y' = 0: the disc spins in place): integrable, otherwise the same.
    * C = -(diag(1/m) + (R^2/I2) (cos, sin)(cos, sin)^T) has det (I2 + m R^2)/(m^2 I2):
      no real zero with m, I2 > 0 (dropped).
    """
    return nhham.System(["x", "y", "theta", "phi"],
                        "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
                        ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"],
                        parameters=values or ["m", "I1", "I2", "R"], name="rolling disc")


def two_bodies(values=None):
    """Two rotors geared 1:1, with kinetic terms of opposite sign, and a spring on the first.

    For a positive-definite W, C = -mu W^-1 mu^T is negative definite, so a singular C
    needs an indefinite kinetic term (as in the paper's own examples):
    L = (I1 x1'^2 - I2 x2'^2)/2 - k x1^2/2, phi = x1' - x2'. C = -(1/I1 - 1/I2).

    * generic (I1 != I2): regular, determined, 1 stage, 1 first class.
    * I1 = I2, k != 0: xi_L(phi) = -k x1/I1 -> x1 = 0, then x1' = 0, then Z(x1') = -1/I1:
      determined, 3 stages, 2 second class, 1 first class.
    * I1 = I2, k = 0: underdetermined, 1 free multiplier.
    """
    return nhham.System(["x1", "x2"], "(I1*x1_dot**2 - I2*x2_dot**2)/2 - k*x1**2/2",
                        ["x1_dot - x2_dot"], parameters=values or ["I1", "I2", "k"],
                        name="two bodies")


# ------------------------------------------------------------------ helpers
def numeric_verdict(system, point):
    """The ordinary classification with the parameter values written into the expressions."""
    sub = {p: sp.Rational(point[p.name]) for p in system.parameters}
    plain = nhham.System(system.coordinates, system.lagrangian.xreplace(sub),
                         [c.xreplace(sub) for c in system.constraints],
                         [g.xreplace(sub) for g in system.holonomic], drop_redundant=True)
    analysis = analyze_constraints(plain)
    classes = None if analysis.status == "inconsistent" else classify_constraints(analysis)
    return (analysis.status, bool(analysis.regular), int(analysis.rank_C),
            len(analysis.stages), int(analysis.free_multipliers), analysis.integrable,
            None if classes is None else int(classes.first_class),
            None if classes is None else int(classes.second_class))


def key(v):
    return (v.status, v.regular, v.rank_C, v.stages, v.free_multipliers, v.integrable,
            v.first_class, v.second_class)


def conditions_text(case):
    return sorted(str(sp.factor(c)) for c in case.conditions)


def point_on(case, free_values):
    """A parameter point of a case: free parameters given, the others from its substitution."""
    point = dict(free_values)
    for p, expr in case.substitution.items():
        point[p.name] = sp.sympify(expr).xreplace({sp.Symbol(k): sp.Rational(v)
                                                   for k, v in free_values.items()})
    return {k: sp.Rational(v) for k, v in point.items()}


# ---------------------------------------------------------------- the cases
@pytest.fixture(scope="module")
def pv_3_1():
    return parametric_classification(paper_3_1(), positive=["a", "b", "c"])


@pytest.fixture(scope="module")
def pv_3_2():
    return parametric_classification(paper_3_2(), positive=["a", "b", "c"])


@pytest.fixture(scope="module")
def pv_disc():
    return parametric_classification(rolling_disc(), positive=["m", "I1", "I2"])


@pytest.fixture(scope="module")
def pv_two():
    return parametric_classification(two_bodies(), positive=["I1", "I2"])


def test_paper_3_1_cases(pv_3_1):
    g = pv_3_1.generic
    assert key(g) == ("determined", True, 1, 1, 0, True, 1, 0)
    assert [conditions_text(c) for c in pv_3_1.cases] == [["b*e**2 - c"]]
    assert key(pv_3_1.cases[0].verdict) == ("underdetermined", False, 0, 1, 1, True, 1, 0)
    dropped = {str(e) for eqs, _ in pv_3_1.dropped for e in eqs}
    assert {"a", "b", "c"} <= dropped


def test_paper_3_2_cases(pv_3_2):
    assert key(pv_3_2.generic) == ("determined", True, 1, 1, 0, True, 1, 0)
    cases = {tuple(conditions_text(c)): c for c in pv_3_2.cases}
    assert set(cases) == {("a*e**2 - c", "d"), ("a*e**2 - c",)}
    both = cases[("a*e**2 - c", "d")]
    assert key(both.verdict) == ("underdetermined", False, 0, 1, 1, True, 1, 0)
    singular = cases[("a*e**2 - c",)]
    assert key(singular.verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    # the more specific case comes first; the other one excludes it
    assert pv_3_2.cases.index(both) < pv_3_2.cases.index(singular)
    assert [str(e) for e in singular.excluding] == ["d"]


def test_rolling_disc_integrable_at_zero_radius(pv_disc):
    assert key(pv_disc.generic) == ("determined", True, 2, 1, 0, False, 2, 0)
    assert [conditions_text(c) for c in pv_disc.cases] == [["R"]]
    case = pv_disc.cases[0]
    assert key(case.verdict) == ("determined", True, 2, 1, 0, True, 2, 0)
    assert "integrable" in case.reasons[0]
    dropped = {str(e) for eqs, _ in pv_disc.dropped for e in eqs}
    assert "I2 + R**2*m" in dropped or "R**2*m + I2" in dropped


def test_rolling_disc_positive_radius_drops_the_case():
    pv = parametric_classification(rolling_disc(), positive=["m", "I1", "I2", "R"])
    assert pv.cases == ()
    assert any("R > 0" in why for _, why in pv.dropped)


def test_two_bodies_singular_exactly_when_inertias_are_equal(pv_two):
    assert key(pv_two.generic) == ("determined", True, 1, 1, 0, True, 1, 0)
    cases = {tuple(conditions_text(c)): c for c in pv_two.cases}
    assert set(cases) == {("I1 - I2", "k"), ("I1 - I2",)}
    assert key(cases[("I1 - I2",)].verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    assert key(cases[("I1 - I2", "k")].verdict) == ("underdetermined", False, 0, 1, 1,
                                                     True, 1, 0)


def test_without_declared_signs_the_singular_lagrangian_is_a_case():
    pv = parametric_classification(two_bodies())
    invalid = [c for c in pv.cases if c.verdict.status == "invalid"]
    assert sorted(str(c.conditions[0]) for c in invalid) == ["I1", "I2"]
    assert all("singular" in c.verdict.note for c in invalid)


@pytest.mark.parametrize("make, positive, free", [
    (paper_3_1, ["a", "b", "c"], {"a": "2", "b": "3", "e": "5/7", "c": "11"}),
    (paper_3_2, ["a", "b", "c"], {"a": "2", "b": "3", "d": "3/2", "e": "5/7", "c": "11"}),
    (rolling_disc, ["m", "I1", "I2"], {"m": "2", "I1": "1/3", "I2": "1/4", "R": "3/5"}),
    (two_bodies, ["I1", "I2"], {"I1": "1/2", "I2": "3/4", "k": "2"}),
])
def test_every_case_matches_the_ordinary_classification_at_a_point(make, positive, free):
    system = make()
    pv = parametric_classification(system, positive=positive)
    assert numeric_verdict(system, {k: sp.Rational(v) for k, v in free.items()}) == \
        key(pv.generic)
    for case in pv.cases:
        point = point_on(case, {k: v for k, v in free.items()
                                if sp.Symbol(k) not in case.substitution})
        assert case.holds_at(point), (case, point)
        assert numeric_verdict(system, point) == key(case.verdict), case.describe()


# ---------------------------------------------------- the verdict at the values
def test_issue_example_says_singular_at_b_equal_one():
    """L = (a q1'^2 + q2'^2 - q3'^2)/2, phi = q2' + b q3', C = -(1 - b^2): zero at b = 1."""
    S = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
                     ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    at = classification_at_values(S)
    assert key(at.verdict)[:5] == ("underdetermined", False, 0, 1, 1)
    assert [str(c) for c in at.conditions] == ["b - 1"]
    assert at.differs and at.generic.regular and at.generic.rank_C == 1
    assert at.system.constraints == (sp.Symbol("q2_dot") + sp.Symbol("q3_dot"),)
    # generic values: the generic verdict, nothing substituted
    S2 = nhham.System(S.coordinates, S.lagrangian, S.constraints,
                      parameters={"a": 1.0, "b": 0.5})
    at2 = classification_at_values(S2)
    assert at2.conditions == () and not at2.differs and at2.verdict.rank_C == 1


def test_values_on_a_two_parameter_condition_keep_the_names():
    at = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5, "k": 2.0}))
    assert key(at.verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    assert [str(c) for c in at.conditions] == ["I1 - I2"]
    assert sp.Symbol("I2") in at.system.lagrangian.free_symbols
    at0 = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5, "k": 0.0}))
    assert key(at0.verdict)[:5] == ("underdetermined", False, 0, 1, 1)


def shift_fields(monkeypatch) -> list:
    """The fields the nearness estimates are made in, appended as they are used."""
    from nhham.lagrangian import exceptional

    fields = []
    original = exceptional.ExceptionalData._with_shifts

    def spy(self, fn, base, values, K=sp.QQ):
        fields.append(K)
        return original(self, fn, base, values, K)

    monkeypatch.setattr(exceptional.ExceptionalData, "_with_shifts", spy)
    return fields


def test_values_near_an_exceptional_set_are_warned_about(monkeypatch):
    """By hand: C is singular on the plane I1 = I2, at distance |I1 - I2| / sqrt(2) from
    (I1, I2, k) = (0.5, 0.5 + 1e-10, 2), relative to |(I1, I2, k)| = sqrt(4.5): 3.3e-11.
    float64 finds the values near and the estimate is made again in 200-bit; for far
    values float64 is enough."""
    from nhham.lagrangian import exceptional

    fields = shift_fields(monkeypatch)
    near = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5 + 1e-10, "k": 2.0}))
    assert near.conditions == () and near.verdict.regular
    (warning,) = near.warnings
    assert "relative distance 3.3e-11" in warning and "C singular" in warning
    assert exceptional.SHIFT_FIELD in fields and FLOAT64 in fields
    fields.clear()
    far = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.7, "k": 2.0}))
    assert far.warnings == ()
    assert FLOAT64 in fields and exceptional.SHIFT_FIELD not in fields


def test_scene_values_are_placed_in_their_case():
    pv = parametric_classification(two_bodies({"I1": 0.5, "I2": 0.5, "k": 2.0}),
                                   positive=["I1", "I2"])
    assert pv.scene_case is not None
    assert conditions_text(pv.cases[pv.scene_case]) == ["I1 - I2"]
    assert key(pv.scene_verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    generic = parametric_classification(two_bodies({"I1": 0.5, "I2": 0.7, "k": 2.0}))
    assert generic.scene_case is None


def test_exceptional_conditions_of_one_analysis():
    conds = exceptional_conditions(analyze_constraints(two_bodies()))
    eqs = {tuple(str(e) for e in c.equations) for c in conds}
    assert ("I1 - I2",) in eqs
    rank = next(c for c in conds if c.equations == (sp.Symbol("I1") - sp.Symbol("I2"),))
    assert any("C singular" in r for r in rank.reasons)


def test_bad_input_names_the_key():
    with pytest.raises(InputError, match="positive: 'zz' is not a parameter"):
        parametric_classification(two_bodies(), positive=["zz"])
    with pytest.raises(InputError, match="max_depth"):
        parametric_classification(two_bodies(), max_depth=-1)


def test_depth_bound_is_noted():
    pv = parametric_classification(paper_3_2(), positive=["a", "b", "c"], max_depth=1)
    assert any("depth bound 1 hit" in n for n in pv.notes)
    assert [conditions_text(c) for c in pv.cases] == [["a*e**2 - c"]]


# ------------------------------------------------------------- property test
def _case_points(pv, system, rng, count):
    """Random rational parameter points of each case (free parameters drawn)."""
    out = []
    for case in pv.cases:
        for _ in range(count):
            free = {p.name: sp.Rational(rng.randint(1, 40), rng.randint(1, 9))
                    for p in system.parameters if p not in case.substitution}
            point = point_on(case, free)
            if case.holds_at(point) and all(point[p.name] > 0 for p in pv.positive):
                out.append((case, point))
    return out


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(min_value=0, max_value=2 ** 32), st.sampled_from(["3.2", "two"]))
def test_random_points_of_each_case_give_its_verdict(seed, which):
    system = {"3.2": paper_3_2, "two": two_bodies}[which]()
    pv = _pv(which)
    rng = random.Random(seed)
    for case, point in _case_points(pv, system, rng, 1):
        first = next(i for i, c in enumerate(pv.cases) if c.holds_at(point))
        assert numeric_verdict(system, point) == key(pv.cases[first].verdict)
    generic = {p.name: sp.Rational(rng.randint(1, 40), rng.randint(1, 9))
               for p in system.parameters}
    if not any(c.holds_at(generic) for c in pv.cases):
        assert numeric_verdict(system, generic) == key(pv.generic)


@functools.cache
def _pv(which):
    make, positive = {"3.2": (paper_3_2, ["a", "b", "c"]),
                      "two": (two_bodies, ["I1", "I2"])}[which]
    return parametric_classification(make(), positive=positive)


def test_floating_point_determinants_pivot():
    """The nearness estimate evaluates data in 200-bit floating point: determinants and
    solves there pivot (sympy's fraction-free elimination divides by the rounded zero
    pivots of an antisymmetric bracket matrix). Checked against exact arithmetic."""
    from sympy.polys.matrices import DomainMatrix

    from nhham.lagrangian.exceptional import SHIFT_FIELD
    from nhham.lagrangian.linalg import field_det, field_solve

    rows = [[0, 3, -1, 2], [-3, 0, 5, 1], [1, -5, 0, 7], [-2, -1, -7, 0]]
    exact = DomainMatrix([[sp.QQ(x) for x in r] for r in rows], (4, 4), sp.QQ)
    F = SHIFT_FIELD
    approx = exact.convert_to(F)
    pf = 3 * 7 - (-1) * 1 + 2 * 5  # Pfaffian b01 b23 - b02 b13 + b03 b12 = 32
    assert exact.det() == pf ** 2
    assert abs(float(field_det(approx)) - pf ** 2) < 1e-40
    rhs = DomainMatrix([[sp.QQ(1)], [sp.QQ(0)], [sp.QQ(2)], [sp.QQ(-1)]], (4, 1), sp.QQ)
    x = exact.lu_solve(rhs).to_list()
    y = field_solve(approx, rhs.convert_to(F)).to_list()
    assert all(abs(float(a[0]) - float(b[0])) < 1e-40 for a, b in zip(x, y))


def test_values_far_from_every_exceptional_set_raise_no_warning(monkeypatch):
    """The 4-link snake at m = l = 1: every datum is nonzero modulo p at the values (a
    proof, so none is evaluated over Q) and none is near vanishing -- in particular
    the antisymmetric bracket matrix, whose determinant is estimated in floating point
    at moved values. float64 puts each far beyond the margin, so 200-bit is not used."""
    from nhham import models

    fields = shift_fields(monkeypatch)
    at = classification_at_values(models.snake(4))
    assert at.conditions == () and at.warnings == ()
    assert at.verdict.second_class == 4
    assert len(fields) == 5 and set(fields) == {FLOAT64}
