"""Linear algebra in every arithmetic (nhham.lagrangian.linalg), against sympy's own
rank, linear solve and determinants."""

import itertools
import random

import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.domains import ModP
from nhham.lagrangian.linalg import exact_rank, exact_solve, maximal_minors



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



@pytest.mark.parametrize("seed", range(40))
def test_maximal_minors_are_the_determinants(seed):
    """One elimination gives every maximal minor: against C(n, m) determinants, over QQ
    (rank-deficient matrices included) and over Q(a)."""

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


def test_a_list_matrix_without_rows_keeps_its_width():
    """No constraints (m = 0): mu is 0 x n, its transpose n x 0, and K = [[W, mu^T]] is W
    (a width lost there once made K empty and the rank at exact points 0)."""
    from nhham.lagrangian.formulas import bordered_matrix
    from nhham.lagrangian.linalg import ListMatrix

    W = ListMatrix([[MPQ(2), MPQ(1)], [MPQ(1), MPQ(3)]])
    mu = ListMatrix([], 2)
    assert mu.shape == (0, 2) and mu.transpose().shape == (2, 0)
    K = bordered_matrix(W, mu, ListMatrix([], 2))
    assert K.shape == (2, 2) and K.rows == W.rows
    with pytest.raises(ValueError):
        W.hstack(ListMatrix([[MPQ(1)]]))


def test_a_float_determinant_beyond_the_range_is_inf_without_a_warning():
    """det diag(1e200, 1e200, 1e200) overflows float64: +inf, no numpy RuntimeWarning
    (the 48-link snake's classify showed one); the wider field takes it from there."""
    import warnings

    import numpy as np

    from nhham.lagrangian.linalg import FloatMatrix, field_det

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert field_det(FloatMatrix(np.diag([1e200] * 3))) == float("inf")
        assert field_det(FloatMatrix(np.diag([-1e200, 1e200, 1e200]))) == float("-inf")
    assert field_det(FloatMatrix(np.diag([2.0, 3.0]))) == 6.0


def test_log_det_keeps_a_large_determinant_and_its_ratio_in_range():
    """log_det of a 60 x 60 matrix whose determinant is far beyond float64 (about
    1e+1150) against the exact determinant of the same rationals: sign and logarithm,
    and the ratio of two such determinants (what the nearness estimate forms) to 1e-10."""
    import math
    import random

    import numpy as np
    from sympy import QQ
    from sympy.external.gmpy import MPQ
    from sympy.polys.matrices import DomainMatrix

    from nhham.lagrangian.exceptional import _log_slope
    from nhham.lagrangian.linalg import FloatMatrix, LogDet, field_det, log_det

    rng = random.Random(3)
    n = 60
    rows = [[MPQ(rng.randint(-10 ** 6, 10 ** 6) * 10 ** 14 + (10 ** 22 if i == j else 0))
             for j in range(n)] for i in range(n)]
    moved = [list(r) for r in rows]
    moved[0][0] = moved[0][0] * MPQ(10001, 10000)
    exact = DomainMatrix(rows, (n, n), QQ).det()
    exact_moved = DomainMatrix(moved, (n, n), QQ).det()
    got = log_det(FloatMatrix(np.array(rows, dtype=float)))
    got_moved = log_det(FloatMatrix(np.array(moved, dtype=float)))
    assert isinstance(got, LogDet) and got.sign == (1.0 if exact > 0 else -1.0)
    digits = len(str(abs(int(exact)))) - 1
    assert digits > 1100   # beyond float64: field_det gives inf
    assert math.isinf(field_det(FloatMatrix(np.array(rows, dtype=float))))
    assert got.log == pytest.approx(math.log(abs(int(exact))), rel=1e-12)
    assert got_moved / got == pytest.approx(float(exact_moved / exact), rel=1e-10)
    h = MPQ(1, 10 ** 4)
    assert _log_slope(got_moved, got, h) == pytest.approx(
        float((exact_moved - exact) / (h * exact)), rel=1e-6)


def test_a_product_of_residue_matrices_is_the_product_of_their_modp_entries():
    """ListMatrix's product on residues (plain integers) against the same product with
    one entry an exact int, which takes the generic path (ModP objects throughout)."""
    import random

    from nhham.lagrangian.domains import PRIME, ModP
    from nhham.lagrangian.linalg import ListMatrix

    rng = random.Random(5)
    A = [[ModP(rng.randrange(PRIME)) for _ in range(7)] for _ in range(5)]
    B = [[ModP(rng.randrange(PRIME)) for _ in range(4)] for _ in range(7)]
    fast = (ListMatrix(A) * ListMatrix(B)).rows
    B_mixed = [list(r) for r in B]
    B_mixed[0][0] = B[0][0].v   # an int: not all residues, so the generic sum of objects
    slow = (ListMatrix(A) * ListMatrix(B_mixed)).rows
    assert all(type(x) is ModP for r in fast for x in r)
    assert fast == slow
    assert fast[2][3] == ModP(sum(A[2][k].v * B[k][3].v for k in range(7)))


def test_field_solve_over_q_and_f_p_is_sympy_s_lu_solve():
    """Over QQ by fraction-free elimination, over F_p on plain ints: the same solution as
    sympy's lu_solve, and a singular matrix raises what lu_solve raises."""
    from sympy import GF, QQ
    from sympy.polys.matrices import DomainMatrix
    from sympy.polys.matrices.exceptions import DMNonInvertibleMatrixError

    from nhham.lagrangian.linalg import field_solve

    rng = random.Random(3)
    for K, draw in ((QQ, lambda: QQ(rng.randint(-99, 99), rng.randint(1, 99))),
                    (GF(2 ** 61 - 1), lambda: GF(2 ** 61 - 1)(rng.randrange(2 ** 61)))):
        A = DomainMatrix([[draw() for _ in range(7)] for _ in range(7)], (7, 7), K)
        B = DomainMatrix([[draw() for _ in range(3)] for _ in range(7)], (7, 3), K)
        assert field_solve(A, B) == A.lu_solve(B)
        singular = DomainMatrix([[K(1), K(2)], [K(2), K(4)]], (2, 2), K)
        with pytest.raises(DMNonInvertibleMatrixError):
            field_solve(singular, DomainMatrix([[K(1)], [K(1)]], (2, 1), K))


def test_a_product_of_residues_and_ints_is_the_scalars_own():
    """ListMatrix's product on ints (residues mixed with plain ints) gives what the
    scalars' operators give, entry by entry: a residue where a row or column holds one,
    an exact int elsewhere."""
    from nhham.lagrangian.linalg import ListMatrix

    rng = random.Random(5)

    def draw(mod):
        if mod and rng.random() < 0.5:
            return ModP(rng.randrange(2 ** 61))
        return rng.randint(-5, 2 ** 70)

    A = [[draw(i != 1) for _ in range(4)] for i in range(3)]
    B = [[draw(j == 2) for j in range(3)] for _ in range(4)]
    got = (ListMatrix(A) * ListMatrix(B)).rows
    for i in range(3):
        for j in range(3):
            want = sum((A[i][k] * B[k][j] for k in range(4)), 0)
            assert type(got[i][j]) is type(want)
            assert (got[i][j].v == want.v) if type(want) is ModP else got[i][j] == want
