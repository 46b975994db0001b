"""Decisions on submanifolds: exact reduction first, seeded sampling second (the sampled
decisions themselves: test_sampled.py).

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


def test_an_expression_undefined_on_M_is_refused_by_name():
    """z' - y'/x on M = {x = 0}: 1/x is not defined anywhere on M (sympy's zoo once x = 0
    is substituted; every sample point was NaN, an SVD that did not converge)."""
    from nhham.errors import InputError

    z, zd = sp.symbols("z z_dot")
    s = System(["x", "y", "z"], (xd**2 + yd**2 + zd**2) / 2, [zd - yd / x], ["x"])
    M = Submanifold(s, (x,) + s.phi)   # M_1: the holonomic x = 0 and phi
    with pytest.raises(InputError, match=r"z_dot - y_dot/x is not defined on the constraint "
                                         r"set, where x = 0 \(it becomes zoo\*y_dot"):
        M.reduction
    assert M.with_equations([x]).reduce(yd / (1 + x)) == yd   # defined there: reduced


def test_sampled_ranks_skip_points_where_the_matrix_is_not_finite():
    """log(x) is NaN at the sample points with x < 0: those are left out and said; the
    rank of [[log(x), 1]] is 1 at the others. log(-1 - x^2) is NaN at every point: the
    entry is named."""
    from nhham.errors import InputError

    M = Submanifold(disk(), [])
    (decision,) = M.sampled_ranks([sp.Matrix([[sp.log(x), 1]])])
    assert decision.value == 1
    skipped = sum(1 for pt in M.points()[0] if pt[x] < 0)
    assert skipped and decision.samples == len(M.points()[0]) - skipped
    assert f"{skipped} sample point(s) skipped: the matrix is not finite there" in \
        decision.warnings
    with pytest.raises(InputError, match=r"log\(-x\*\*2 - 1\) is not finite at any of 6 "
                                         r"points of the constraint set"):
        M.sampled_ranks([sp.Matrix([[sp.log(-1 - x**2), 1]])])


def test_finite_values_keep_the_points_where_the_matrices_are_real():
    """sqrt(x) is not real at x < 0 (float() of a complex number was an internal error
    in the bracket's sampled step): those points are left out, the values at the others
    are sqrt(x) and x^2; sqrt(-1 - x^2) is real nowhere, and is named."""
    from nhham.errors import InputError

    M = Submanifold(disk(), [])
    points, values = M.finite_values([sp.Matrix([[sp.sqrt(x)]]), sp.Matrix([[x**2]])])
    assert points == [pt for pt in M.points()[0] if pt[x] >= 0] and points
    for pt, (root, square) in zip(points, values):
        assert root[0, 0] == pytest.approx(pt[x] ** 0.5) and square[0, 0] == pt[x] ** 2
    with pytest.raises(InputError, match=r"sqrt\(-x\*\*2 - 1\) is not finite at any of 6"):
        M.finite_values([sp.Matrix([[1, sp.sqrt(-1 - x**2)]])])


def test_a_regular_block_is_chosen_at_the_points_where_the_matrix_is_finite():
    """[[log(x), 1]] has rank 1; at the points with x < 0 log(x) is NaN (np.linalg.norm
    of it: an SVD that did not converge). The block is chosen at the others, and a
    matrix finite nowhere is named."""
    from nhham.errors import InputError

    M = Submanifold(disk(), [], exact=False)
    rows, cols, decision = M.regular_block(sp.Matrix([[sp.log(x), 1]]), 1)
    assert rows == [0] and len(cols) == 1 and decision.method == "sampled"
    with pytest.raises(InputError, match="is not finite at any of 6"):
        M.regular_block(sp.Matrix([[sp.log(-1 - x**2), 1]]), 1)
