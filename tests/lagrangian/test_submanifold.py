"""Decisions on submanifolds: exact reduction first, seeded sampling second.

Expected answers are worked out by hand in each docstring.
"""

import mpmath
import pytest
import sympy as sp

from nhham import System
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.submanifold import Submanifold

q1, q2, q3 = sp.symbols("q1 q2 q3")
v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
x, y, th, ph = sp.symbols("x y theta phi")
xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
m, R = sp.symbols("m R")


def disk(values=True):
    params = {"m": 1.3, "I1": 0.5, "I2": 0.25, "R": 0.7} if values else ["m", "I1", "I2", "R"]
    I1, I2 = sp.symbols("I1 I2")
    return System(["x", "y", "theta", "phi"],
                  m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2,
                  [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd], parameters=params)


def disk_M1(**kw):
    s = disk(**kw.pop("sys", {}))
    return Submanifold(s, s.phi, **kw)


def test_reduction_solves_dependent_velocities():
    """On M_1, x' = R c phi', y' = R s phi' (the mu block of (x', y') is the identity,
    the best conditioned one)."""
    M = disk_M1()
    red = M.reduction
    assert red.residual == ()
    assert sp.simplify(red.substitution[xd] - R * sp.cos(th) * phd) == 0
    assert sp.simplify(red.substitution[yd] - R * sp.sin(th) * phd) == 0


def test_exact_vanishing_and_nonvanishing():
    """x' s - y' c = R phi'(c s - s c) = 0 on M_1; x'^2 + y'^2 - R^2 phi'^2 =
    R^2 phi'^2 (c^2 + s^2 - 1) = 0 only modulo the trig identity; R theta' phi' s is a
    nonzero function (M_1 is parametrised, no residual)."""
    M = disk_M1()
    d = M.vanishes(xd * sp.sin(th) - yd * sp.cos(th))
    assert d.value is True and d.method == "exact"
    d = M.vanishes(xd**2 + yd**2 - R**2 * phd**2)
    assert d.value is True and d.method == "exact" and "sin^2+cos^2" in d.detail
    d = M.vanishes(R * thd * phd * sp.sin(th))
    assert d.value is False and d.method == "exact"
    assert isinstance(d, Decision) and "nonzero" in d.describe()


def test_vanishing_modulo_residual_equations():
    """M = {q1^2 + q2^2 - 1 = 0} (not solvable by the linear elimination):
    q1^2 (q1^2 + q2^2 - 1) vanishes (Groebner remainder 0); q1 does not, and with a
    residual equation non-vanishing is decided at samples."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    M = Submanifold(s, [q1**2 + q2**2 - 1], fibre=())
    assert M.reduction.residual
    d = M.vanishes(q1**2 * (q1**2 + q2**2 - 1))
    assert d.value is True and d.method == "exact"
    d = M.vanishes(q1)
    assert d.value is False and d.method == "sampled" and d.samples == 6
    pts, res = M.points()
    assert res < 1e-12
    assert all(abs(p[q1]**2 + p[q2]**2 - 1) < 1e-12 for p in pts)


def test_parameter_values_that_cancel_an_exact_answer_are_warned():
    """(m - 13/10) x' is nonzero for generic m, but zero at the given m = 1.3."""
    M = disk_M1()
    d = M.vanishes((m - sp.Rational(13, 10)) * thd)
    assert d.value is False and d.method == "exact"
    assert d.warnings and "parameter values" in d.warnings[0]


def test_rank_exact_paths():
    """Numbers: rank of [[1, 2], [2, 4]] is 1.  Full rank: det of C_disk is
    1/m^2 + R^2/(m I2) (c^2 + s^2), a nonzero function.  Certificate: [[q1, q1 q2],
    [1, q2]] has the nonzero 1x1 minor 1 and Schur complement q1 q2 - q1 q2 = 0."""
    M = disk_M1()
    assert M.rank(sp.Matrix([[1, 2], [2, 4]])).value == 1
    I2 = sp.Symbol("I2")
    c, s = sp.cos(th), sp.sin(th)
    C = sp.Matrix([[-1 / m - R**2 * c**2 / I2, -R**2 * c * s / I2],
                   [-R**2 * c * s / I2, -1 / m - R**2 * s**2 / I2]])
    d = M.rank(C)
    assert d.value == 2 and d.method == "exact"
    Q = Submanifold(System(["q1", "q2"], (v1**2 + v2**2) / 2), [], fibre=())
    d = Q.rank(sp.Matrix([[q1, q1 * q2], [1, q2]]))
    assert d.value == 1 and d.method == "exact" and "Schur" in d.detail
    assert Q.rank(sp.Matrix([[q1 - q1, 0]])).value == 0
    assert Q.rank(sp.zeros(0, 3)).value == 0


@pytest.mark.parametrize("precision", [None, 30])
def test_sampled_rank_does_not_depend_on_the_units(precision):
    """diag(m (1 + q1^2), 1) has rank 2 for every m != 0; m = 1e-16 (a mass in other units)
    was rank 1 against the old absolute floor, and m = 1e-16 on both rows rank 0."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    M = Submanifold(s, [], fibre=(), exact=False, precision=precision)
    e = sp.Rational(1, 10**16)
    assert M.rank(sp.diag(e * (1 + q1**2), 1)).value == 2
    assert M.rank(sp.diag(e * (1 + q1**2), e * (2 + q2**2))).value == 2
    assert M.rank(sp.Matrix([[e * q1, e * q1 * q2], [e, e * q2]])).value == 1


def test_sampled_rank_ignores_rounding_noise_of_functions_vanishing_on_M():
    """On M = {q1 - q2^2 = 0}, [[q1 - q2^2, 0], [0, 1]] has rank 1: the (1, 1) entry is the
    Newton projection's rounding there, which equilibration alone would scale up to 1."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2, holonomic=[q1 - q2**2])
    M = Submanifold(s, [q1 - q2**2], fibre=(), exact=False)
    d = M.rank(sp.Matrix([[q1 - q2**2, 0], [0, 1 + q1**2]]))
    assert d.value == 1


def test_sampled_rank_near_singular_warns_and_more_digits_decide():
    """[[1, 1], [1, 1 + e]] with e = 10^-11: singular value ratio ~ e/4 = 2.5e-12,
    between float64's zero level (1e-12) and its tolerance (1e-9): rank 1 with a warning;
    at 30 digits rank 2, no warning."""
    e = sp.Rational(1, 10**11)
    A = sp.Matrix([[1, 1], [1, 1 + e]]) * (1 + q1**2)
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    f64 = Submanifold(s, [], fibre=(), exact=False).rank(A)
    assert f64.value == 1 and f64.method == "sampled"
    assert any("near-singular" in w for w in f64.warnings)
    # The evidence: the sample points, the singular values and the point residual.
    assert len(f64.points) == 6 and len(f64.singular_values) == 6
    assert "smallest singular value per point" in f64.describe()
    mp = Submanifold(s, [], fibre=(), exact=False, precision=30).rank(A)
    assert mp.value == 2 and mp.warnings == () and mp.precision == "mpmath:30"
    exact = Submanifold(s, [], fibre=()).rank(A)
    assert exact.value == 2 and exact.method == "exact"


def test_sampled_vanishing_near_tolerance_warns():
    """sin^2 + cos^2 - 1 + 1e-11 q1: its value, relative to the size of its terms (about
    2), is below float64's tolerance but above its zero level."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    expr = sp.sin(q1)**2 + sp.cos(q1)**2 - 1 + q1 / 10**11
    d = Submanifold(s, [], fibre=(), exact=False).vanishes(expr)
    assert d.value is True and d.warnings
    d = Submanifold(s, [], fibre=(), exact=False, precision=30).vanishes(expr)
    assert d.value is False and d.warnings == ()


def test_sampled_vanishing_does_not_depend_on_the_units():
    """A single term is as far from zero whatever its size: q1 * 1e-11 and q1 * 1e11
    are both nonzero without a warning (the old absolute floor called the first zero)."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    for scale in (sp.Rational(1, 10**11), sp.Integer(10**11)):
        d = Submanifold(s, [], fibre=(), exact=False).vanishes(q1 * scale)
        assert d.value is False and d.warnings == ()


def test_regular_block_prefers_large_well_conditioned_blocks():
    """Rank 1 [[1e-3, 1], [2e-3, 2]]: the best 1x1 block is the entry 2 (row 1, col 1).
    Rank 2 [[1, 1, 0], [1, 1 + 1e-6, 1]]: columns {0, 1} are nearly dependent, so a
    block with column 2 is chosen."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    Q = Submanifold(s, [], fibre=())
    rows, cols, _ = Q.regular_block(sp.Matrix([[sp.Rational(1, 1000), 1],
                                               [sp.Rational(2, 1000), 2]]), 1)
    assert (rows, cols) == ([1], [1])
    rows, cols, _ = Q.regular_block(sp.Matrix([[1, 1, 0], [1, 1 + sp.Rational(1, 10**6), 1]]),
                                    2)
    assert rows == [0, 1] and 2 in cols


def test_with_equations_keeps_settings_and_points_lie_on_M():
    M = disk_M1(precision=30, samples=3, seed=5, exact=False)
    N = M.with_equations(M.equations + (thd - 1,))
    assert (N.precision, N.samples, N.seed, N.exact, N.fibre) == (30, 3, 5, False, M.fibre)
    pts, res = N.points()
    assert len(pts) == 3 and res < 1e-29
    with mpmath.workdps(40):
        for p in pts:
            assert isinstance(p[thd], mpmath.mpf)
            assert abs(p[thd] - 1) < mpmath.mpf(10) ** -29
            assert abs(p[xd] - p[R] * mpmath.cos(p[th]) * p[phd]) < mpmath.mpf(10) ** -29


def test_points_are_seeded():
    a, _ = disk_M1(seed=11).points()
    b, _ = disk_M1(seed=11).points()
    c, _ = disk_M1(seed=12).points()
    assert [p[thd] for p in a] == [p[thd] for p in b]
    assert [p[thd] for p in a] != [p[thd] for p in c]


def test_empty_submanifold_raises():
    from nhham.errors import ComputationError

    s = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    with pytest.raises(ComputationError):
        Submanifold(s, [q1**2 + 1], fibre=()).points()
