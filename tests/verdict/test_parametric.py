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
from nhham.verdict.parametric import parametric_classification
from parametric_systems import key, paper_3_1, paper_3_2, rolling_disc, two_bodies


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


# ------------------------------------------------ the scene's values in the cases


def test_scene_values_are_placed_in_their_case():
    pv = parametric_classification(two_bodies({"I1": 0.5, "I2": 0.5, "k": 2.0}),
                                   positive=["I1", "I2"])
    assert pv.scene_case is not None
    assert conditions_text(pv.cases[pv.scene_case]) == ["I1 - I2"]
    assert key(pv.scene_verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    generic = parametric_classification(two_bodies({"I1": 0.5, "I2": 0.7, "k": 2.0}))
    assert generic.scene_case is None


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


