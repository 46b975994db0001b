"""The arithmetics of exact decisions (nhham.lagrangian.domains).

Reference values come from elsewhere: mpmath at the actual angles 2 atan(t), and the
true degree of a numerator found by sympy after substituting the circle
parametrisation.
"""

import random

import mpmath
import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.domains import (
    PRIME,
    Angle,
    Degree,
    ModP,
    NotExact,
    Program,
    evaluate,
    minor_degree,
    schwartz_zippel_bound,
)

q1, q2, x, a = sp.symbols("q1 q2 x a")


def circle(t, r):
    t = MPQ(t)
    one = 1 + t * t
    return Angle(MPQ(r), (1 - t * t) / one, 2 * t / one)


def test_exact_values_match_the_angles_they_stand_for():
    """(c, s) = ((1 - t^2)/(1 + t^2), 2t/(1 + t^2)) is the point at angle 2 atan t."""
    t1, t2 = MPQ(3, 7), MPQ(-5, 2)
    env = {q1: circle(t1, 0), q2: circle(t2, 0), x: MPQ(5, 3), a: MPQ(2)}
    exprs = [sp.sin(q1 - 2 * q2) * x + a * sp.cos(3 * q1) ** 2 - sp.tan(q2),
             sp.cos(q1 + q2) / (a + sp.sin(q1))]
    values = evaluate(exprs, env)
    th1, th2 = 2 * mpmath.atan(mpmath.mpf(3) / 7), 2 * mpmath.atan(mpmath.mpf(-5) / 2)
    ref = [mpmath.sin(th1 - 2 * th2) * mpmath.mpf(5) / 3 + 2 * mpmath.cos(3 * th1) ** 2
           - mpmath.tan(th2), mpmath.cos(th1 + th2) / (2 + mpmath.sin(th1))]
    for v, r in zip(values, ref):
        assert isinstance(v, MPQ)
        assert abs(float(v) - float(r)) < 1e-14 * max(1.0, abs(float(r)))


def test_polynomial_and_trigonometric_uses_of_a_coordinate_are_independent():
    """q sin q: the polynomial value r and the circle point are drawn separately."""
    env = {q1: circle(2, 7)}
    (v,) = evaluate([q1 * sp.sin(q1)], env)
    assert v == 7 * MPQ(4, 5)


@pytest.mark.parametrize("expr", [sp.sqrt(q1), sp.exp(q1), sp.sin(q1 / 2), sp.sin(sp.pi * q1),
                                  sp.sin(a)])
def test_what_cannot_be_evaluated_exactly_says_so(expr):
    env = {q1: circle(2, 1), a: MPQ(1, 3)}
    with pytest.raises(NotExact):
        evaluate([expr], env)


def _true_numerator_degree(expr, variables):
    """Total degree of the numerator after t-substitution (computed by sympy)."""
    ts = sp.symbols(f"t0:{len(variables)}")
    rs = sp.symbols(f"r0:{len(variables)}")
    sub = {}
    for v, t, r in zip(variables, ts, rs):
        sub[sp.sin(v)] = 2 * t / (1 + t**2)
        sub[sp.cos(v)] = (1 - t**2) / (1 + t**2)
    e = sp.expand_trig(expr).xreplace(sub).xreplace(dict(zip(variables, rs)))
    num = sp.numer(sp.together(e))
    return sp.Poly(num, *ts, *rs).total_degree() if num != 0 else 0


@pytest.mark.parametrize("seed", range(8))
def test_degree_bounds_are_upper_bounds_of_the_true_degree(seed):
    rng = random.Random(seed)
    atoms = [sp.sin(q1), sp.cos(q1), sp.sin(q2), sp.cos(q1 - q2), q1, q2, sp.Integer(3)]
    expr = sp.Integer(0)
    for _ in range(4):
        term = sp.Integer(rng.randint(-3, 3))
        for _ in range(rng.randint(1, 3)):
            term *= rng.choice(atoms)
        expr += term
    if rng.random() < 0.5:
        expr = expr / (2 + sp.cos(q2))
    c1 = Degree(2, {("circle", q1): (2, 1)})
    c2 = Degree(2, {("circle", q2): (2, 1)})
    deg = {q1: Angle(Degree(1), c1, c1), q2: Angle(Degree(1), c2, c2)}
    (bound,) = evaluate([expr], deg)
    true = _true_numerator_degree(expr, [q1, q2])
    assert Degree.of(bound).num >= true


def test_minor_degree_bounds_a_determinant():
    """Row sums of entry degrees bound the numerator degree of every minor.

    det [[cos q1, x], [x, cos^2 q1]] = c^3 - x^2 = ((1 - t^2)^3 - x^2 (1 + t^2)^3) / (1 + t^2)^3:
    numerator of degree 8, which the bound attains.
    """
    c = Degree(2, {("circle", q1): (2, 1)})
    rows = [[c, Degree(1)], [Degree(1), c * c]]
    det = sp.Matrix([[sp.cos(q1), x], [x, sp.cos(q1) ** 2]]).det()
    true = _true_numerator_degree(det, [q1, x])
    assert minor_degree(rows, 2) >= true == 8
    assert minor_degree(rows, 1) == 5


def test_modular_values_reduce_rationals_consistently():
    u = ModP.lift(MPQ(3, 7))
    assert (u * 7).v == 3
    assert (ModP(5) / ModP(5)).v == 1
    assert ModP(PRIME) == 0



def test_schwartz_zippel_bound_by_hand():
    """D / (|S| - D_den) per point, to the power of the points, times the terms."""
    S = 2 ** 62
    assert schwartz_zippel_bound(4, 1) == pytest.approx(4 / S, rel=1e-15)
    assert schwartz_zippel_bound(4, 3, denominator_degree=2 ** 61) == pytest.approx(
        (4 / (S - 2 ** 61)) ** 3, rel=1e-12)
    assert schwartz_zippel_bound(4, 2, terms=10) == pytest.approx(10 * (4 / S) ** 2, rel=1e-12)
    assert schwartz_zippel_bound(S, 5) == 1.0  # no information: a degree as large as S


def test_a_compiled_program_gives_the_values_of_the_walk():
    """Program (the expressions compiled once) against the same values by hand at a
    rational point, over F_p (with a sqrt), and its degree bounds against evaluate's."""
    t1, t2 = MPQ(3, 7), MPQ(-5, 2)
    env = {q1: circle(t1, 2), q2: circle(t2, 0), x: MPQ(5, 3), a: MPQ(2)}
    exprs = [sp.sin(q1 - 2 * q2) * x + a * sp.cos(3 * q1) ** 2 - sp.tan(q2),
             sp.cos(q1 + q2) / (a + sp.sin(q1)), q1 ** 2 * x - 1, sp.Integer(4)]
    program = Program(exprs)
    assert program.run(env) == evaluate(exprs, env)
    # q1's polynomial value is 2, x = 5/3: q1^2 x - 1 = 17/3 by hand.
    assert program.run(env)[2] == MPQ(17, 3)
    # Over F_p: sqrt(x^2) is x or -x (the branch that is a square), (x + 1)^-2 by hand.
    mod = {x: ModP(12345), a: ModP(7)}
    root, inv = Program([sp.sqrt(x ** 2), (x + a) ** -2]).run(mod)
    assert root in (ModP(12345), ModP(-12345))
    assert inv == ModP(pow(12352 ** 2, -1, PRIME))
    deg = {q1: Angle(Degree(1), Degree(2, {"c1": (2, 1)}), Degree(2, {"c1": (2, 1)})),
           q2: Angle(Degree(1), Degree(2, {"c2": (2, 1)}), Degree(2, {"c2": (2, 1)})),
           x: Degree(1), a: Degree(0)}
    assert ([d.num for d in Program(exprs[:3]).run(deg)]
            == [d.num for d in evaluate(exprs[:3], deg)])
    with pytest.raises(NotExact):
        Program([sp.exp(x)])
