"""Exact points and degree bounds (nhham.lagrangian.points).

Reference values come from elsewhere: mpmath at the actual angles 2 atan(t),
sympy's own rank and linear solve, and the true degree of a numerator found by
sympy after substituting the circle parametrisation.
"""

import random

import mpmath
import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.points import (
    PRIME,
    Angle,
    Degree,
    ModP,
    NotExact,
    PointSampler,
    evaluate,
    exact_rank,
    exact_solve,
    maximal_minors,
    minor_degree,
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


@pytest.mark.parametrize("seed", range(20))
def test_exact_linear_algebra_agrees_with_sympy(seed):
    rng = random.Random(seed)
    n, m = rng.randint(1, 5), rng.randint(1, 5)
    A = [[MPQ(rng.randint(-4, 4), rng.randint(1, 3)) for _ in range(m)] for _ in range(n)]
    if n > 2:
        A[-1] = [u + 2 * w for u, w in zip(A[0], A[1])]
    S = sp.Matrix([[sp.Rational(int(v.numerator), int(v.denominator)) for v in r] for r in A])
    r, rows, cols = exact_rank(A)
    assert r == S.rank() and S.extract(rows, cols).rank() == r
    # modulo p: the same rank for these small integers
    assert exact_rank([[ModP.lift(v) for v in row] for row in A])[0] == r
    if n == m and r == n:
        b = [[MPQ(rng.randint(-5, 5))] for _ in range(n)]
        X = exact_solve(A, b)
        assert S * sp.Matrix([[sp.Rational(int(v[0].numerator), int(v[0].denominator))]
                              for v in X]) == sp.Matrix([[int(v[0])] for v in b])


def test_modular_values_reduce_rationals_consistently():
    u = ModP.lift(MPQ(3, 7))
    assert (u * 7).v == 3
    assert (ModP(5) / ModP(5)).v == 1
    assert ModP(PRIME) == 0


def test_points_lie_on_the_constraints_exactly():
    """Dependent velocities solved exactly: every constraint vanishes at the point."""
    th, ph = sp.symbols("theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    X, Y = sp.symbols("x y")
    R = sp.Symbol("R")
    cons = [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd]
    sampler = PointSampler((X, Y, th, ph), (xd, yd, thd, phd), (R,), {}, (), cons, seed=3)
    for _ in range(3):
        pt = sampler.point()
        assert evaluate(cons, pt.env) == [0, 0]
    modular = PointSampler((X, Y, th, ph), (xd, yd, thd, phd), (R,), {}, (), cons, seed=3,
                           modular=True)
    assert evaluate(cons, modular.point().env) == [ModP(0), ModP(0)]


def test_holonomic_constraints_linear_in_a_coordinate_are_eliminated():
    q3 = sp.Symbol("q3")
    sampler = PointSampler((q1, q2, q3), (), (), {}, (q3 - q1 + q2,), (), seed=1)
    pt = sampler.point()
    (g,) = evaluate([q3 - q1 + q2], pt.env)
    assert g == 0
    with pytest.raises(NotExact):
        PointSampler((q1, q2), (), (), {}, (q1**2 + q2**2 - 1,), (), seed=1).point()


def test_parameter_values_are_taken_as_exact_decimals():
    m = sp.Symbol("m")
    sampler = PointSampler((q1,), (), (m,), {m: 0.1}, (), (), seed=1)
    assert sampler.point().env[m] == MPQ(1, 10)


@pytest.mark.parametrize("seed", range(40))
def test_maximal_minors_are_the_determinants(seed):
    """One elimination gives every maximal minor: against C(n, m) determinants, over QQ
    (rank-deficient matrices included) and over Q(a)."""
    import itertools

    from sympy import QQ
    from sympy.polys.matrices import DomainMatrix

    rng = random.Random(seed)
    m = rng.randint(1, 5)
    n = rng.randint(m, 8)
    rank = m if seed % 4 else rng.randint(0, m)
    basis = [[rng.randint(-3, 3) for _ in range(n)] for _ in range(max(rank, 1))]
    rows = [[sum(rng.randint(-2, 2) * b[j] for b in basis) if rank else 0 for j in range(n)]
            for _ in range(m)] if rank < m else [[rng.randint(-4, 4) for _ in range(n)]
                                                for _ in range(m)]
    M = DomainMatrix([[QQ(x) for x in r] for r in rows], (m, n), QQ)
    direct = [M.extract(list(range(m)), list(S)).det()
              for S in itertools.combinations(range(n), m)]
    assert maximal_minors(M) == direct
    a = sp.Symbol("a")
    K = QQ.frac_field(a)
    Ma = DomainMatrix([[K.convert(x + (a if (i + j) % 3 == 0 else 0)) for j, x in enumerate(r)]
                       for i, r in enumerate(rows)], (m, n), K)
    direct = [Ma.extract(list(range(m)), list(S)).det()
              for S in itertools.combinations(range(n), m)]
    assert maximal_minors(Ma) == direct
