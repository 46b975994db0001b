"""The verdicts of a classification (nhham.verdict.results): a verdict's differences, text
and JSON keys; which parameter values a case holds at (read exactly); the verdict at the
scene's values. (The file is not named test_results.py: tests/cli/test_results.py has
that name, and test modules are imported by their file name.)"""

import sympy as sp

from nhham.verdict.results import Case, ParametricVerdict, ValuesVerdict, Verdict, exact_value

a, b = sp.symbols("a b")


def _verdict(**changes):
    fields = dict(status="determined", regular=True, rank_C=2, stages=1, free_multipliers=0,
                  integrable=False, first_class=2, second_class=2)
    return Verdict(**{**fields, **changes})


def test_differences_text_and_json_of_a_verdict():
    generic = _verdict()
    singular = _verdict(regular=False, rank_C=1, stages=3, redundant=("constraints[2]",))
    assert singular.differences(generic) == ("regular", "rank_C", "stages", "redundant")
    assert generic.differences(_verdict(system=object())) == ()  # the system is not compared
    assert singular.describe() == (
        "C regular no (rank 1), determined, 3 stage(s), 0 free multiplier(s), integrable no, "
        "2 first class, 2 second class, redundant constraints[2]")
    assert _verdict(integrable=None, first_class=None).describe() == (
        "C regular yes (rank 2), determined, 1 stage(s), 0 free multiplier(s), "
        "integrable undecided")
    assert Verdict("invalid", None, None, 0, 0, None, None, None,
                   note="W is singular").describe() == "invalid: W is singular"
    assert singular.to_dict() == {
        "status": "determined", "regular": False, "rank_c": 1, "stage_count": 3,
        "free_multipliers": 0, "integrable": False, "first_class": 2, "second_class": 2,
        "redundant": ["constraints[2]"], "final_constraint_count": 0, "dimension": None,
        "note": None}


def test_a_case_holds_at_values_read_exactly():
    """b = 1/10 holds at the float 0.1 (read as its decimal, not as the binary double
    0.1000000000000000055...); (a - 1) excluded: not at a = 1; None without a value of b."""
    case = Case(conditions=(10 * b - 1,), excluding=(a - 1,), verdict=_verdict())
    assert case.holds_at({"a": 2, "b": 0.1}) is True
    assert case.holds_at({a: 2.0, b: 0.1000001}) is False
    assert case.holds_at({"a": 1, "b": 0.1}) is False
    assert case.holds_at({"a": 2}) is None
    assert case.describe() == "10*b - 1 = 0 (excluding a - 1 = 0)"
    assert exact_value(0.1) == sp.Rational(1, 10) and exact_value(sp.pi) is sp.pi


def test_the_verdict_at_the_scene_values():
    generic, special = _verdict(), _verdict(status="underdetermined", free_multipliers=1)
    case = Case(conditions=(b,), excluding=(), verdict=special, reasons=("C drops rank",))
    common = dict(cases=(case,), dropped=(), notes=(), warnings=(), parameters=(a, b),
                  positive=(a,))
    at_case = ParametricVerdict(generic=generic, scene_case=0, values={a: 1.0, b: 0.0}, **common)
    assert at_case.scene_verdict is special
    assert ParametricVerdict(generic=generic, scene_case=None, **common).scene_verdict is generic
    lines = str(at_case).splitlines()
    assert lines[0] == "parameters: a, b (positive: a)"
    assert lines[1] == f"generic: {generic.describe()}"
    assert lines[2:5] == ["case 0: b = 0", f"  verdict: {special.describe()}",
                          "  why: C drops rank"]
    assert lines[-1] == "values a = 1.0, b = 0.0: case 0"
    assert ValuesVerdict(special, generic, (b,), system=None).differs
    assert not ValuesVerdict(generic, _verdict(), (), system=None).differs
