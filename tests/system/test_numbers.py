"""Which numbers are data: real constants, floats within double precision
(nhham.system.numbers), with the values compared against closed forms."""

import doctest
import math

import pytest
import sympy as sp

from nhham.system import numbers
from nhham.system.numbers import complex_string, number_problems

x = sp.Symbol("x")


@pytest.mark.parametrize("number, value", [
    (sp.asin(2), complex(math.pi / 2, -math.acosh(2))),     # asin(2) = pi/2 - i acosh(2)
    (sp.acos(3), complex(0.0, math.acosh(3))),              # acos(3) = i acosh(3)
    (sp.log(-2), complex(math.log(2), math.pi)),            # principal branch
    ((-1) ** sp.Rational(1, 3), complex(0.5, math.sqrt(3) / 2)),
    (sp.exp(sp.I), complex(math.cos(1), math.sin(1))),
])
def test_constants_that_are_not_real_give_their_value(number, value):
    assert complex_string(number) == f"{value.real:.6g}{value.imag:+.6g}i"
    (problem,) = number_problems(x + number * x)
    assert problem.startswith(f"{sp.sstr(number)} is not a real number")


@pytest.mark.parametrize("number", [sp.acos(sp.Rational(1, 3)), sp.sqrt(2), sp.atan2(1, -3),
                                    sp.log(3) - sp.pi, sp.Integer(7), sp.Float(2.5e-320)])
def test_real_constants_pass(number):
    assert complex_string(number) is None and number_problems(number * x) == []


def test_floats_beyond_double_precision():
    (tiny,) = number_problems(sp.Float("1e-400") * x)
    (huge,) = number_problems(x + sp.Float("1e400"))
    assert "1.00000000000000e-400 is outside the range of double precision" in tiny
    assert "outside the range of double precision" in huge
    assert number_problems(sp.Float(0.0) + x) == []  # zero is a double


def test_docstring_examples():
    assert doctest.testmod(numbers).failed == 0


@pytest.mark.parametrize("constraint, values, part", [
    # atan2(0, 1/2) = 0, so 1/atan2(k, 1/2)^2 is 1/0 (sympy's zoo) at k = 0
    ("x_dot/atan2(k, 0.5)**2 + y_dot", {"k": 0.0}, "atan2(k, 0.5)**(-2) is not finite at k = 0"),
    # atan2(0, 0) is undefined (nan)
    ("atan2(k, k)*x_dot + y_dot", {"k": 0.0}, "atan2(k, k) is not finite at k = 0"),
    # log(k) at k = 0 is -infinity
    ("x_dot + log(k)*y_dot", {"k": 0.0}, "log(k) is not finite at k = 0"),
    # sqrt(-2) = i sqrt(2): the numbers would drop it
    ("x_dot + sqrt(k)*y_dot", {"k": -2.0}, "sqrt(k) is not a real number at k = -2 (its value "
                                            "is 0+1.41421i)"),
])
def test_an_expression_undefined_at_the_parameter_values_is_refused(constraint, values, part):
    """Every sample point met NaN or inf there (an SVD that did not converge: an internal
    error), or an imaginary part was dropped; the problem names the key and the part."""
    import nhham

    with pytest.raises(nhham.ValidationError) as info:
        nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2", [constraint], parameters=values)
    assert str(info.value).startswith(f"constraints[0]: {part}")
    assert info.value.key == "constraints[0]"
    nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2", [constraint], parameters={"k": 2.0})
