"""What a System's expressions may contain: plain symbols, real numbers, smooth
functions of the state, a bounded expansion (nhham.system.screening)."""

import math

import pytest
import sympy as sp
from sympy.physics import mechanics as me

import nhham
from nhham.errors import ValidationError
from nhham.system.screening import MAX_EXPANDED_TERMS, expanded_size

x, y, z = sp.symbols("x y z")
xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
m, R = sp.symbols("m R")
L_free = m * (xd**2 + yd**2 + zd**2) / 2


def refused(**kw):
    """The ValidationError of System(**kw) (coordinates x, y, z and parameter m by default)."""
    args = dict(coordinates=["x", "y", "z"], lagrangian=L_free, parameters={"m": 1.0})
    args.update(kw)
    with pytest.raises(ValidationError) as info:
        nhham.System(**args)
    return info.value


@pytest.mark.parametrize("number, real, imag", [
    (sp.asin(2), math.pi / 2, -math.acosh(2)),   # asin(2) = pi/2 - i acosh(2)
    (sp.I, 0.0, 1.0),
    (sp.log(-2), math.log(2), math.pi),          # principal branch
    ((-1) ** sp.Rational(1, 3), 0.5, math.sqrt(3) / 2),  # principal cube root
])
def test_numbers_that_are_not_real_are_refused_through_the_api(number, real, imag):
    """sympy input skips the parser: the System refuses it, with the value (compared with
    the closed forms above) instead of dropping the imaginary part in the numbers."""
    error = refused(lagrangian=L_free + number * x)
    assert error.key == "lagrangian"
    assert f"is not a real number (its value is {real:.6g}{imag:+.6g}i)" in str(error)


def test_real_constants_that_sympy_cannot_prove_real_are_evaluated():
    nhham.System(["x", "y", "z"], L_free + sp.acos(sp.Rational(1, 3)) * x + sp.sqrt(2) * y,
                 parameters={"m": 1.0})


def test_floats_outside_double_precision_are_refused_through_the_api():
    error = refused(constraints=[xd - sp.Float("1e-400") * yd])
    assert error.key == "constraints[0]" and "outside the range of double precision" in str(error)


def test_dynamicsymbols_are_pointed_to_from_mechanics():
    q1, q2 = me.dynamicsymbols("q1 q2")
    error = refused(coordinates=[q1, q2], lagrangian=q1.diff() ** 2 / 2)
    assert error.key == "coordinates[0]" and "nhham.from_mechanics" in str(error)
    error = refused(lagrangian=L_free + q1.diff() ** 2)
    assert "lagrangian: contains q1(t), a function of time" in str(error)
    assert "from_mechanics" in str(error)


def test_explicit_time_is_the_time_and_other_names_are_parameters_to_declare():
    """t in a constraint is the time (System.time, the last parameter), not unknown."""
    system = nhham.System(["x", "y", "z"], L_free, parameters={"m": 1.0},
                          constraints=[xd - sp.Symbol("t") * yd])
    assert system.time == sp.Symbol("t") and system.parameters[-1] == system.time
    other = refused(lagrangian=L_free + sp.Symbol("k") * x)
    assert "unknown symbol(s) k" in str(other) and "declare parameters in parameters" in str(other)


@pytest.mark.parametrize("kink", [sp.sign(x), sp.Abs(xd), sp.Heaviside(y), sp.Max(x, y)])
def test_functions_without_a_derivative_of_the_state_are_refused(kink):
    error = refused(lagrangian=L_free + kink)
    assert error.key == "lagrangian" and "is not smooth" in str(error)


def test_a_kink_in_the_time_is_refused():
    """sign(t) in L: d/dt of it stays an unevaluated Derivative (sympy knows no sign of
    t), which the generated code cannot print (an internal error of compare)."""
    error = refused(lagrangian=L_free + (1 + sp.sign(sp.Symbol("t"))) * yd**2)
    assert error.key == "lagrangian" and "sign(t) is not smooth" in str(error)
    assert "(and the time t)" in str(error)


def test_kinks_of_parameters_alone_are_fine():
    system = nhham.System(["x", "y"], m * (xd**2 + yd**2) / 2 - sp.Abs(R) * x,
                          [xd - sp.sign(R) * yd], parameters={"m": 1.0, "R": -2.0})
    assert system.m == 1


def test_names_not_in_normal_form_are_refused():
    error = refused(coordinates=["ｍ", "y", "z"], lagrangian=yd**2 + zd**2)
    assert error.key == "coordinates[0]" and "NFKC" in str(error) and "'m'" in str(error)


@pytest.mark.parametrize("power", [2, 3, 5, 9])
def test_expanded_size_of_a_power_is_the_count_of_monomials(power):
    """(a + b + c + d + 1)**k has C(k + 4, 4) monomials, counted here by sympy's Poly."""
    a, b, c, d = sp.symbols("a b c d")
    expr = (a + b + c + d + 1) ** power
    size, part = expanded_size(expr)
    assert size == len(sp.Poly(sp.expand(expr), a, b, c, d).terms())
    assert part == expr


def test_expanded_size_bounds_products_and_denominators():
    a, b, c, d, e = sp.symbols("a b c d e")
    assert expanded_size((a + b) * (c + d + e))[0] == len(sp.expand((a + b) * (c + d + e)).args)
    assert expanded_size(x + 1 / (a + b) ** 3)[0] == 4  # the denominator is expanded
    assert expanded_size(sp.sin((a + b) ** 2) + x)[0] == 3  # and a function's argument


def test_expressions_too_large_to_expand_are_refused_at_once():
    """(x + y + z + 1)**60 would keep the exact steps busy for hours and gigabytes."""
    error = refused(lagrangian=L_free - (x + y + z + 1) ** 60)
    assert math.comb(63, 3) > MAX_EXPANDED_TERMS
    assert f"expands to about {float(math.comb(63, 3)):.3g} terms" in str(error)
    assert "(x + y + z + 1)**60" in str(error)
    nhham.System(["x", "y", "z"], L_free - (x + y + z + 1) ** 6, parameters={"m": 1.0})


def test_docstring_examples():
    import doctest

    from nhham.system import screening

    assert doctest.testmod(screening).failed == 0
