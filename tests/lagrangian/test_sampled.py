"""Ranks and vanishing decided at sampled points of M (nhham.lagrangian.sampled, through
Submanifold with exact=False): whatever the units, rounding noise ignored, near-singular
answers warned about, the best-conditioned regular block. Expected answers are worked out
by hand in each docstring."""

import pytest
import sympy as sp

from nhham import System
from nhham.lagrangian.submanifold import Submanifold

q1, q2 = sp.symbols("q1 q2")
v1, v2 = sp.symbols("q1_dot q2_dot")


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
