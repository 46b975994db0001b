"""Plain ``classify`` answers at the scene's values when they lie on an exceptional set.

For each kind of generic decision (rank of C, a lambda-free condition, Frobenius, the
rank of the bracket matrix) a system is written whose exceptional set is known by hand;
random values are placed on that set and the headline must be the case's verdict, with
the condition in ``parameter_case``. The hand derivations are in each system's docstring.
"""

import json

import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import run_inprocess

VALUES = st.integers(min_value=1, max_value=500).map(lambda n: n / 100)


def classify(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    rc, out, err = run_inprocess("classify", str(path), "--json")
    assert rc == 0, err
    return json.loads(out)["result"]


def assert_case(result, condition, params):
    """``parameter_case`` lists one condition, proportional to ``condition``."""
    case = result["parameter_case"]
    assert case is not None and case["generic_differs"]
    (got,) = case["conditions"]
    syms = {p: sp.Symbol(p) for p in params}
    ratio = sp.cancel(sp.sympify(got, locals=syms) / sp.sympify(condition, locals=syms))
    assert ratio.is_number and ratio != 0
    return case["generic"]


@settings(max_examples=4, deadline=None)
@given(A=VALUES)
def test_rank_of_C_drops_at_the_values(A, tmp_path_factory):
    """L = (q1'^2 + A q2'^2 + B q3'^2)/2, phi = q2' + q3': C = -(1/A + 1/B), zero exactly
    on A + B = 0; there xi_L(phi) = 0, so the multiplier is free (underdetermined)."""
    res = classify(tmp_path_factory.mktemp("c"), f"""
coordinates = ["q1", "q2", "q3"]
parameters = {{ A = {A!r}, B = {-A!r} }}
lagrangian = "(q1_dot**2 + A*q2_dot**2 + B*q3_dot**2)/2"
constraints = ["q2_dot + q3_dot"]
""")
    assert (res["regular"], res["rank_c"], res["status"], res["free_multipliers"]) == \
        (False, 0, "underdetermined", 1)
    generic = assert_case(res, "A + B", "AB")
    assert (generic["regular"], generic["status"]) == (True, "determined")


@settings(max_examples=4, deadline=None)
@given(k=VALUES)
def test_a_lambda_free_condition_vanishes_at_the_values(k, tmp_path_factory):
    """L = (q1'^2 + q2'^2 - q3'^2)/2 - k q1 - c q3, phi = q1' + q3': C = -(1 - 1) = 0 and
    xi_L(phi) = q1'' + q3'' = -k + c, a nonzero constant (inconsistent) except on c = k,
    where it holds identically and the multiplier is free."""
    res = classify(tmp_path_factory.mktemp("l"), f"""
coordinates = ["q1", "q2", "q3"]
parameters = {{ k = {k!r}, c = {k!r} }}
lagrangian = "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2 - k*q1 - c*q3"
constraints = ["q1_dot + q3_dot"]
""")
    assert (res["status"], res["free_multipliers"], res["inconsistency"]) == \
        ("underdetermined", 1, None)
    generic = assert_case(res, "c - k", "ck")
    assert generic["status"] == "inconsistent"


@settings(max_examples=4, deadline=None)
@given(a=VALUES)
def test_the_distribution_becomes_integrable_at_the_values(a, tmp_path_factory):
    """mu = dz - a y dx + b x dy: dmu = (a + b) dx ^ dy, mu ^ dmu = (a + b) dx ^ dy ^ dz."""
    res = classify(tmp_path_factory.mktemp("f"), f"""
coordinates = ["x", "y", "z"]
parameters = {{ a = {a!r}, b = {-a!r} }}
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
constraints = ["z_dot - a*y*x_dot + b*x*y_dot"]
""")
    assert res["integrable"] is True
    generic = assert_case(res, "a + b", "ab")
    assert generic["integrable"] is False


@settings(max_examples=4, deadline=None)
@given(a=VALUES)
def test_the_bracket_rank_drops_at_the_values(a, tmp_path_factory):
    """chi_1 = p_x + a y, chi_2 = p_y + b x on T*Q (L = |v|^2/2): {chi_1, chi_2} = a - b,
    so both are second class except on a = b, where both are first class."""
    res = classify(tmp_path_factory.mktemp("b"), f"""
coordinates = ["x", "y", "z"]
parameters = {{ a = {a!r}, b = {a!r} }}
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
constraints = ["x_dot + a*y", "y_dot + b*x"]
""")
    assert (res["first_class"], res["second_class"]) == (2, 0)
    generic = assert_case(res, "a - b", "ab")
    assert (generic["first_class"], generic["second_class"]) == (0, 2)
