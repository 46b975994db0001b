"""Exact points of M_1 and degree bounds: what decisions "exact at points" rest on.

A function on TQ built from polynomials, quotients, sines and cosines of the
coordinates is evaluated *exactly* at random rational points: every coordinate q
carries a rational value r (where it appears polynomially) and a rational point of
the unit circle (c, s) = ((1 − t²)/(1 + t²), 2t/(1 + t²)) (where it appears inside
sin/cos), with r and t drawn independently. This is legitimate for questions about
functions — vanishing identically, generic rank — because q is algebraically
independent of (cos q, sin q): a polynomial in (q, cos q, sin q) vanishes as a
function exactly when it vanishes at every (r, c, s) with c² + s² = 1. Integer
combinations of coordinates inside sin/cos (θ1 − θ2, 2φ) are exact through
(c + i s) products. Parameters with values take their exact decimal value
(``Rational(str(value))``); parameters without values are drawn like coordinates.
Dependent velocities are solved exactly from the affine constraints; holonomic
constraints are eliminated when a coordinate enters one linearly with a constant
coefficient. Anything else (``sqrt``, ``exp``, a parameter with a value inside
sin, a holonomic constraint that is not linear) raises :class:`NotExact`, and the
caller decides at sampled points instead, saying so.

Every evaluation can be repeated with :class:`Degree` objects in place of the
numbers: the same arithmetic then yields an upper bound on the degree of the
numerator of each quantity as a rational function of the drawn variables
(r, t, free velocities, free parameters). That is the "degree" of the
Schwartz–Zippel lemma: a nonzero rational function whose numerator has degree
at most D vanishes at a uniformly random point of S^N with probability at most
D/|S|. So "vanishes at k random exact points" is reported with the computed
error bound (D/(|S| − D_den))^k (points where a denominator vanishes are drawn
again, which the D_den term accounts for), and "nonzero at one exact point" is
a proof.
"""

from __future__ import annotations

import itertools
import random
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy import QQ
from sympy.external.gmpy import MPQ
from sympy.matrices.exceptions import NonInvertibleMatrixError
from sympy.polys.matrices import DomainMatrix
from sympy.polys.matrices.exceptions import DMNonInvertibleMatrixError

from nhham.errors import NhhamError
from nhham.system.expressions import derivative

__all__ = [
    "NotExact",
    "Angle",
    "Degree",
    "SAMPLE_BITS",
    "evaluate",
    "exact_rank",
    "exact_solve",
    "maximal_minors",
    "adjacent_column_sets",
    "field_det",
    "field_solve",
    "FLOAT64",
    "FloatMatrix",
    "rank_bound",
    "minor_degree",
    "solve_degrees",
    "jacobian_row",
    "ExactPoint",
    "PointSampler",
    "ModP",
    "PRIME",
]

# Sample set S = {1, ..., 2**SAMPLE_BITS}: large enough that a handful of points
# gives Schwartz–Zippel bounds far below 1e-30, small enough for quick rationals.
SAMPLE_BITS = 62


class NotExact(NhhamError):
    """The expression cannot be evaluated exactly at rational points."""


# ------------------------------------------------------------------ values
class Angle:
    """A coordinate's value at an exact point: polynomial value ``r`` and the point
    ``(c, s)`` of the unit circle standing for (cos q, sin q).

    Sums and integer multiples of angles stay angles (the circle points multiply
    as unit complex numbers); any other arithmetic uses ``r``. ``r``, ``c``, ``s``
    are exact rationals or :class:`Degree` bounds (the same code serves both).
    """

    __slots__ = ("r", "c", "s")

    def __init__(self, r, c, s):
        self.r, self.c, self.s = r, c, s

    def _rotate(self, other):
        return Angle(self.r + other.r, self.c * other.c - self.s * other.s,
                     self.s * other.c + self.c * other.s)

    def _times(self, k: int):
        out = Angle(0, 1, 0)
        base = self if k >= 0 else Angle(-self.r, self.c, -self.s)
        for _ in range(abs(k)):
            out = out._rotate(base)
        return out

    def __add__(self, other):
        if isinstance(other, Angle):
            return self._rotate(other)
        if isinstance(other, int) and other == 0:
            return self
        return self.r + other

    __radd__ = __add__

    def __neg__(self):
        return Angle(-self.r, self.c, -self.s)

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, int):
            return self._times(other)
        if isinstance(other, Angle):
            return self.r * other.r
        return self.r * other

    __rmul__ = __mul__

    def __truediv__(self, other):
        return self.r / (other.r if isinstance(other, Angle) else other)

    def __rtruediv__(self, other):
        return other / self.r

    def __pow__(self, k):
        return self.r ** k


# A Mersenne prime: reduction is cheap and 1/|F_p| is about 4e-19.
PRIME = 2 ** 61 - 1


class ModP:
    """An element of the field F_p (p = :data:`PRIME`).

    Used for proofs of full rank and of non-vanishing: a value computed from the
    expression tree modulo p (every inverse taken exists) that is nonzero shows
    that the rational value — hence the function — is nonzero. Mixed arithmetic
    with ints and exact rationals reduces them modulo p.
    """

    __slots__ = ("v",)

    def __init__(self, v: int):
        self.v = v % PRIME

    @staticmethod
    def lift(x) -> "ModP":
        if isinstance(x, ModP):
            return x
        if isinstance(x, int):
            return ModP(x)
        q = MPQ(x)
        den = int(q.denominator) % PRIME
        if den == 0:
            raise ZeroDivisionError("denominator divisible by p")
        return ModP(int(q.numerator) * pow(den, -1, PRIME))

    def __add__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v + ModP.lift(other).v)

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v - ModP.lift(other).v)

    def __rsub__(self, other):
        return ModP(ModP.lift(other).v - self.v)

    def __neg__(self):
        return ModP(-self.v)

    def __mul__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v * ModP.lift(other).v)

    __rmul__ = __mul__

    def inverse(self) -> "ModP":
        if self.v == 0:
            raise ZeroDivisionError("division by zero modulo p")
        return ModP(pow(self.v, -1, PRIME))

    def __truediv__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return self * ModP.lift(other).inverse()

    def __rtruediv__(self, other):
        return ModP.lift(other) * self.inverse()

    def __pow__(self, k: int):
        return ModP(pow(self.v, k, PRIME)) if k >= 0 else self.inverse() ** (-k)

    def __eq__(self, other):
        if isinstance(other, (ModP, int)):
            return self.v == ModP.lift(other).v
        return NotImplemented

    def __hash__(self):
        return hash(self.v)

    def __bool__(self):
        return self.v != 0

    def __repr__(self):
        return f"ModP({self.v})"


def _sin(x):
    if isinstance(x, Angle):
        return x.s
    if _is_zero_constant(x):
        return 0
    raise NotExact("sin of a number that is not an angle variable")


def _cos(x):
    if isinstance(x, Angle):
        return x.c
    if _is_zero_constant(x):
        return 1
    raise NotExact("cos of a number that is not an angle variable")


def _inverse(x):
    if isinstance(x, (Degree, ModP)):
        return x.inverse()
    return MPQ(1) / x  # ZeroDivisionError at a bad point: the caller draws again


def _is_zero_constant(x) -> bool:
    return isinstance(x, (int, MPQ)) and x == 0


_FUNCTIONS = {
    sp.sin: _sin,
    sp.cos: _cos,
    sp.tan: lambda x: _sin(x) / _cos(x),
    sp.cot: lambda x: _cos(x) / _sin(x),
}


def evaluate(exprs, env: dict, cache: dict | None = None) -> list:
    """Values of sympy expressions with symbols replaced by ``env`` values.

    Parameters
    ----------
    exprs : sequence of sympy.Expr
    env : dict
        Symbol -> value (exact rational, :class:`Angle`, or :class:`Degree`).
    cache : dict, optional
        Shared memo of subexpression values (for several calls at one point).

    Returns
    -------
    list
        One value per expression (``int``, ``MPQ``, ``Degree`` ...).

    Raises
    ------
    NotExact
        On a symbol missing from ``env``, a transcendental constant, a function
        other than sin/cos/tan/cot, or a non-integer power.
    """
    memo = {} if cache is None else cache
    values = [_value(sp.sympify(e), env, memo) for e in exprs]
    return [x.r if isinstance(x, Angle) else x for x in values]


def _value(e, env, memo):
    if e in memo:
        return memo[e]
    if e.is_Symbol:
        if e not in env:
            raise NotExact(f"no exact value for {e}")
        out = env[e]
    elif e.is_Integer:
        out = int(e)
    elif e.is_Rational:
        out = MPQ(int(e.p), int(e.q))
    elif e.is_Float:
        r = sp.Rational(str(e))
        out = MPQ(int(r.p), int(r.q))
    elif e.is_Add:
        out = 0
        for a in e.args:
            out = out + _value(a, env, memo)
    elif e.is_Mul:
        out = 1
        for a in e.args:
            out = out * _value(a, env, memo)
    elif e.is_Pow:
        if not e.exp.is_Integer:
            raise NotExact(f"non-integer power in {e}")
        base = _value(e.base, env, memo)
        k = int(e.exp)
        if isinstance(base, Angle):
            base = base.r
        out = base ** k if k >= 0 else _inverse(base ** (-k))
    elif e.func in _FUNCTIONS:
        out = _FUNCTIONS[e.func](_value(e.args[0], env, memo))
    else:
        raise NotExact(f"{e.func} cannot be evaluated exactly")
    memo[e] = out
    return out


# ----------------------------------------------------------------- degrees
class Degree:
    """Upper bound on a rational function N/D of the drawn variables.

    ``num`` bounds deg N; ``den`` maps each denominator factor (a key) to
    ``(degree, exponent)``. Circle factors (1 + t²) are shared keys, so sums of
    trigonometric terms keep one common denominator; every other denominator
    gets a fresh key. Arithmetic mirrors the exact evaluation.
    """

    __slots__ = ("num", "den")
    _fresh = itertools.count()

    def __init__(self, num: int = 0, den: dict | None = None):
        self.num, self.den = num, dict(den or {})

    @staticmethod
    def of(x) -> "Degree":
        if isinstance(x, Angle):
            x = x.r
        return x if isinstance(x, Degree) else Degree(0)

    @property
    def den_degree(self) -> int:
        return sum(d * k for d, k in self.den.values())

    def __add__(self, other):
        if _is_zero_constant(other):
            return self
        a, b = self, Degree.of(other)
        common = dict(a.den)
        for key, (d, k) in b.den.items():
            if key not in common or common[key][1] < k:
                common[key] = (d, k)
        total = sum(d * k for d, k in common.values())
        num = max(a.num + total - a.den_degree, b.num + total - b.den_degree)
        return Degree(num, common)

    __radd__ = __add__

    def __neg__(self):
        return self

    def __sub__(self, other):
        return self + other

    def __rsub__(self, other):
        return self + other

    def __mul__(self, other):
        if _is_zero_constant(other):
            return 0
        b = Degree.of(other)
        den = dict(self.den)
        for key, (d, k) in b.den.items():
            den[key] = (d, den[key][1] + k) if key in den else (d, k)
        return Degree(self.num + b.num, den)

    __rmul__ = __mul__

    def inverse(self) -> "Degree":
        if self.num == 0 and not self.den:
            return Degree(0)
        return Degree(self.den_degree, {("denominator", next(Degree._fresh)): (self.num, 1)})

    def __truediv__(self, other):
        return self * Degree.of(other).inverse()

    def __rtruediv__(self, other):
        return self.inverse() * other

    def __pow__(self, k: int):
        out = Degree(0)
        for _ in range(k):
            out = out * self
        return out

    def __repr__(self):
        return f"Degree(num={self.num}, den={self.den_degree})"


def rank_bound(rows) -> list[int]:
    """Per-row numerator degree contributions of a matrix of :class:`Degree` bounds.

    The numerator of any minor using rows I (over the product of those rows'
    common denominators) has degree at most the sum of the contributions of I.
    """
    out = []
    for row in rows:
        entries = [Degree.of(x) for x in row if not _is_zero_constant(x)]
        if not entries:
            out.append(0)
            continue
        lcm = Degree(0)
        for x in entries:
            lcm = lcm + Degree(0, x.den)  # LCM of the denominators
        total = lcm.den_degree
        out.append(max(x.num + total - x.den_degree for x in entries))
    return out


def minor_degree(rows, size: int) -> int:
    """Bound on the numerator degree of every ``size`` x ``size`` minor."""
    contributions = sorted(rank_bound(rows), reverse=True)
    return sum(contributions[:size])


# ------------------------------------------------------------ exact linear algebra
def _domain_matrix(rows):
    M = [[x if isinstance(x, MPQ) else QQ(x) for x in row] for row in rows]
    shape = (len(M), len(M[0]) if M else 0)
    return DomainMatrix(M, shape, QQ)


def exact_rank(rows) -> tuple[int, list[int], list[int]]:
    """Rank of a matrix of exact rationals with its pivot rows and columns.

    sympy's DomainMatrix over QQ (reduced row echelon form); the pivot columns
    are the first independent columns in order, the pivot rows those of the
    transpose.
    """
    if not rows or not rows[0]:
        return 0, [], []
    if any(isinstance(x, ModP) for row in rows for x in row):
        return _rank_mod_p(rows)
    dm = _domain_matrix(rows)
    _, cols = dm.rref(method="GJ")
    if not cols:
        return 0, [], []
    _, prow = dm.extract(list(range(dm.shape[0])), list(cols)).transpose().rref(method="GJ")
    return len(cols), list(prow), list(cols)


def exact_solve(A, b):
    """X with A X = B for a square nonsingular exact matrix A (lists of rationals).

    Raises
    ------
    ZeroDivisionError
        When A is singular.
    """
    n = len(A)
    if n == 0:
        return []
    if any(isinstance(x, ModP) for row in list(A) + list(b) for x in row):
        return _solve_mod_p(A, b)
    dA, dB = _domain_matrix(A), _domain_matrix(b)
    try:
        X = dA.lu_solve(dB)
    except (ZeroDivisionError, NonInvertibleMatrixError, DMNonInvertibleMatrixError) as exc:
        raise ZeroDivisionError("singular block") from exc
    return X.to_list()


def maximal_minors(M: DomainMatrix, pivots=None, subsets=None) -> list:
    """Every maximal minor of an m x n DomainMatrix M (m <= n) over a field, in the order
    of ``itertools.combinations(range(n), m)`` (or of the column sets ``subsets``, each
    sorted; ``adjacent_column_sets`` gives the m (n - m) + 1 that decide the rank).

    One elimination instead of C(n, m) determinants: with P the pivot columns of M and
    R = M[:, P]^{-1} M (so R[:, P] = I), det M[:, S] = det M[:, P] det R[:, S], and
    det R[:, S] is, up to the sign of a generalised Laplace expansion along the unit
    columns, the minor of R on the rows of P \\ S and the columns of S \\ P (at most
    (n - m) x (n - m)). ``pivots`` gives P (the pivot columns, found by an exact
    evaluation) instead of finding it: in floating point a rounded zero is not zero.
    Fewer than m pivots: every minor is zero.
    """
    m, n = M.shape
    if pivots is None:
        _, pivots = M.rref()
    if subsets is None:
        subsets = list(itertools.combinations(range(n), m))
    if len(pivots) < m:
        return [M.domain.zero] * len(subsets)
    P = list(pivots)
    B = M.extract(list(range(m)), P)
    det_B = field_det(B)
    R = field_solve(B, M)
    row_of = {c: i for i, c in enumerate(P)}
    out = []
    for S in subsets:
        unit = [j for j, c in enumerate(S) if c in row_of]
        other = [S[j] for j, c in enumerate(S) if c not in row_of]
        used = [row_of[S[j]] for j in unit]
        taken = set(used)
        rest = [i for i in range(m) if i not in taken]
        sub = field_det(R.extract(rest, other)) if other else M.domain.one
        parity = sum(u + 1 for u in used) + sum(j + 1 for j in unit) + sum(
            1 for a in range(len(used)) for b in range(a + 1, len(used)) if used[a] > used[b])
        out.append(-det_B * sub if parity % 2 else det_B * sub)
    return out


def adjacent_column_sets(pivots, n) -> list:
    """The pivot columns P and every set that swaps one of them for another column.

    Their minors are det M[:, P] and det M[:, P] R_ij (R = M[:, P]^-1 M): all vanish
    exactly where M has rank < m, as all maximal minors do, with m (n - m) + 1 terms
    instead of C(n, m).
    """
    P = sorted(pivots)
    out = [tuple(P)]
    for i in range(len(P)):
        for c in range(n):
            if c not in P:
                out.append(tuple(sorted(P[:i] + [c] + P[i + 1:])))
    return out


class _Float64:
    """float64 in place of a sympy real domain, for estimates (the elements are Python
    floats; :class:`FloatMatrix` holds them)."""

    is_RealField = True
    is_FiniteField = False
    is_QQ = False
    precision = 53
    zero = 0.0
    one = 1.0

    def __repr__(self):
        return "FLOAT64"


#: The float64 "domain" of :class:`FloatMatrix`.
FLOAT64 = _Float64()


class FloatMatrix:
    """The part of the DomainMatrix interface that :func:`field_det`,
    :func:`field_solve` and :func:`maximal_minors` use, on a numpy float64 array
    (LAPACK's partially pivoted LU): for estimates where 200-bit arithmetic is not needed.
    """

    domain = FLOAT64

    def __init__(self, a):
        self.a = np.asarray(a, dtype=float)

    @classmethod
    def zeros(cls, shape) -> "FloatMatrix":
        return cls(np.zeros(shape))

    @property
    def shape(self) -> tuple:
        return self.a.shape

    def hstack(self, other) -> "FloatMatrix":
        return FloatMatrix(np.hstack([self.a, other.a]))

    def vstack(self, other) -> "FloatMatrix":
        return FloatMatrix(np.vstack([self.a, other.a]))

    def transpose(self) -> "FloatMatrix":
        return FloatMatrix(self.a.T)

    def extract(self, rows, cols) -> "FloatMatrix":
        return FloatMatrix(self.a[np.ix_(list(rows), list(cols))])

    def __mul__(self, other) -> "FloatMatrix":
        return FloatMatrix(self.a @ other.a)

    def __sub__(self, other) -> "FloatMatrix":
        return FloatMatrix(self.a - other.a)

    def __neg__(self) -> "FloatMatrix":
        return FloatMatrix(-self.a)

    def to_list(self) -> list:
        return self.a.tolist()


def field_det(M: DomainMatrix):
    """det M; in floating point by elimination with partial pivoting (sympy's
    fraction-free elimination divides by rounded, possibly tiny, pivots)."""
    if isinstance(M, FloatMatrix):
        return float(np.linalg.det(M.a)) if M.shape[0] else 1.0
    K = M.domain
    if K.is_FiniteField:
        # On machine-size residues: sympy's elements invert by an extended gcd per division.
        p = int(K.characteristic())
        return K(_det_mod(
            [[int(K.to_int(x)) % p for x in row] for row in M.to_list()], p))
    if not K.is_RealField:
        return M.det()
    rows, n = M.to_list(), M.shape[0]
    det = K.one
    for c in range(n):
        p = max(range(c, n), key=lambda i: abs(rows[i][c]))
        if not rows[p][c]:
            return K.zero
        if p != c:
            rows[c], rows[p] = rows[p], rows[c]
            det = -det
        det *= rows[c][c]
        for i in range(c + 1, n):
            f = rows[i][c] / rows[c][c]
            if f:
                rows[i] = [a - f * b for a, b in zip(rows[i], rows[c])]
    return det


def field_solve(A: DomainMatrix, B: DomainMatrix) -> DomainMatrix:
    """A^-1 B; in floating point with partial pivoting (see :func:`field_det`)."""
    if isinstance(A, FloatMatrix):
        try:
            return FloatMatrix(np.linalg.solve(A.a, B.a))
        except np.linalg.LinAlgError as exc:
            raise ZeroDivisionError("singular matrix") from exc
    K = A.domain
    if not K.is_RealField:
        return A.lu_solve(B)
    n, k = A.shape[0], B.shape[1]
    rows = [a + b for a, b in zip(A.to_list(), B.to_list())]
    for c in range(n):
        p = max(range(c, n), key=lambda i: abs(rows[i][c]))
        if not rows[p][c]:
            raise ZeroDivisionError("singular matrix")
        rows[c], rows[p] = rows[p], rows[c]
        for i in range(n):
            if i != c and rows[i][c]:
                f = rows[i][c] / rows[c][c]
                rows[i] = [a - f * b for a, b in zip(rows[i], rows[c])]
    X = [[rows[i][n + j] / rows[i][i] for j in range(k)] for i in range(n)]
    return DomainMatrix(X, (n, k), K)


def _det_mod(rows, p: int) -> int:
    """det of a square matrix of residues modulo the prime p (Gaussian elimination)."""
    M, n, det = [list(r) for r in rows], len(rows), 1
    for c in range(n):
        k = next((i for i in range(c, n) if M[i][c]), None)
        if k is None:
            return 0
        if k != c:
            M[c], M[k] = M[k], M[c]
            det = -det
        det = det * M[c][c] % p
        inv = pow(M[c][c], -1, p)
        for i in range(c + 1, n):
            if M[i][c]:
                f = M[i][c] * inv % p
                M[i] = [(a - f * b) % p for a, b in zip(M[i], M[c])]
    return det % p


def _ints_mod_p(rows):
    return [[ModP.lift(x).v for x in row] for row in rows]


def _rank_mod_p(rows):
    """Rank, pivot rows and pivot columns over F_p (Gaussian elimination on ints)."""
    M = _ints_mod_p(rows)
    nrows, ncols = len(M), len(M[0])
    order = list(range(nrows))
    prow, pcol, r = [], [], 0
    for c in range(ncols):
        p = next((i for i in range(r, nrows) if M[i][c]), None)
        if p is None:
            continue
        M[r], M[p] = M[p], M[r]
        order[r], order[p] = order[p], order[r]
        inv = pow(M[r][c], -1, PRIME)
        pivot = M[r]
        for i in range(r + 1, nrows):
            if M[i][c]:
                f = M[i][c] * inv % PRIME
                M[i] = [(a - f * b) % PRIME for a, b in zip(M[i], pivot)]
        prow.append(order[r])
        pcol.append(c)
        r += 1
        if r == nrows:
            break
    return r, sorted(prow), pcol


def _solve_mod_p(A, b):
    n = len(A)
    M = _ints_mod_p([list(A[i]) + list(b[i]) for i in range(n)])
    for c in range(n):
        p = next((i for i in range(c, n) if M[i][c]), None)
        if p is None:
            raise ZeroDivisionError("singular block modulo p")
        M[c], M[p] = M[p], M[c]
        inv = pow(M[c][c], -1, PRIME)
        M[c] = [x * inv % PRIME for x in M[c]]
        for i in range(n):
            if i != c and M[i][c]:
                f = M[i][c]
                M[i] = [(a - f * bb) % PRIME for a, bb in zip(M[i], M[c])]
    return [[ModP(x) for x in row[n:]] for row in M]


def solve_degrees(A, B) -> list:
    """Degree bounds of X = A⁻¹ B (Cramer's rule) for Degree matrices A (square), B.

    Every entry is a ratio of minors of [A | B]: numerator bounded by the minors
    of [A | B], one shared fresh denominator factor for det A.
    """
    size = len(A)
    widths = len(B[0]) if B else 0
    aug = [list(a) + [sum((Degree.of(x) for x in b), Degree(0))] for a, b in zip(A, B)]
    top = minor_degree(aug, size)
    den = minor_degree([list(a) for a in A], size)
    x = Degree(top, {("denominator", next(Degree._fresh)): (den, 1)})
    return [[x] * widths for _ in range(size)]


# ------------------------------------------------------------------ points
@dataclass(frozen=True)
class ExactPoint:
    """One exact point of M_1 with the matching degree bounds.

    Attributes
    ----------
    env : dict
        Symbol -> exact value (``Angle`` for coordinates and free parameters,
        ``MPQ`` for velocities and parameters with values).
    degrees : dict
        Symbol -> :class:`Degree` (or ``Angle`` of degrees) for the same symbols.
    """

    env: dict
    degrees: dict


class PointSampler:
    """Random exact points of M_1 = {g(q) = 0, φ(q, v) = 0}.

    Parameters
    ----------
    coordinates, velocities : sequence of sympy.Symbol
    parameters : sequence of sympy.Symbol
        All parameters; those in ``values`` are fixed, the others drawn.
    values : dict
        Parameter -> value (numbers; taken as exact decimals).
    holonomic : sequence of sympy.Expr
        g(q) = 0; each must be linear, with a constant coefficient, in a
        coordinate not yet eliminated (else :class:`NotExact`).
    affine : sequence of sympy.Expr
        Constraints affine in the velocities (φ = μ(q) v + h(q), lifts included).
    seed : int
    mu : list of list of sympy.Expr, optional
        The velocity coefficients of ``affine`` when the caller has them.
    modular : bool, optional
        Points over F_p (:class:`ModP` values, for proofs of full rank and of
        non-vanishing) instead of rational points.
    """

    def __init__(self, coordinates, velocities, parameters, values, holonomic, affine, seed,
                 mu=None, modular=False):
        self.coordinates = tuple(coordinates)
        self.velocities = tuple(velocities)
        self.fixed = {p: _exact_number(p, values[p]) for p in parameters if p in values}
        self.drawn = tuple(p for p in parameters if p not in values)
        self.rng = random.Random(seed)
        self.solved = eliminate_coordinates(self.coordinates, holonomic)
        self.affine = tuple(sp.sympify(e) for e in affine)
        vels = self.velocities
        self.mu = mu if mu is not None else [jacobian_row(e, vels) for e in self.affine]
        self.h = [e.xreplace({v: 0 for v in vels}) for e in self.affine]
        self.dependent: tuple | None = None
        self.rejected = 0
        self.modular = modular
        if modular:
            self.fixed = {p: ModP.lift(x) for p, x in self.fixed.items()}

    @classmethod
    def on_M1(cls, system, seed: int, *, modular: bool = False) -> "PointSampler":
        """The sampler of M_1 = {g = 0, φ = 0} of a system (its coordinates, velocities,
        parameters with their values, holonomic constraints and φ with μ)."""
        return cls(system.coordinates, system.velocities, system.parameters,
                   dict(system.parameter_values), system.holonomic, system.phi, seed,
                   mu=[list(system.mu.row(i)) for i in range(len(system.phi))],
                   modular=modular)

    # Degree bookkeeping for the denominators that may vanish at a drawn point
    # (they are drawn again): the bound of their numerators.
    @property
    def denominator_degree(self) -> int:
        return self._den_degree

    def _draw(self):
        if self.modular:
            return ModP(self.rng.randrange(1, PRIME))
        return MPQ(self.rng.randint(1, 2 ** SAMPLE_BITS))

    def point(self) -> ExactPoint:
        """A random exact point of M_1 (raises NotExact when there is no exact route)."""
        for _ in range(50):
            pt = self._try_point()
            if pt is not None:
                return pt
            self.rejected += 1
        raise NotExact("no exact point found: the affine constraints are singular at "
                       "every point tried")

    def _try_point(self):
        env, deg = dict(self.fixed), {p: 0 for p in self.fixed}
        for s in self.drawn + tuple(q for q in self.coordinates if q not in self.solved):
            t = self._draw()
            one = 1 + t * t
            if not one:
                return None
            env[s] = Angle(self._draw(), (1 - t * t) / one, 2 * t / one)
            key = ("circle", s)
            circ = Degree(2, {key: (2, 1)})
            deg[s] = Angle(Degree(1), circ, circ)
        for q, expr in self.solved.items():
            try:
                env[q], = evaluate([expr], env)
            except ZeroDivisionError:
                return None
            deg[q], = evaluate([expr], deg)
        vels = self.velocities
        if not self.affine:
            for v in vels:
                env[v], deg[v] = self._draw(), Degree(1)
            self._den_degree = 0
            return ExactPoint(env, deg)
        cache, dcache = {}, {}
        try:
            mu = [evaluate(row, env, cache) for row in self.mu]
            h = evaluate(self.h, env, cache)
        except ZeroDivisionError:
            return None
        if self.dependent is None:
            r, rows, cols = exact_rank(mu)
            if r < len(self.affine):
                raise NotExact("the affine constraints are dependent at a random point")
            self.dependent = tuple(cols)
        dep = list(self.dependent)
        free = [i for i in range(len(vels)) if i not in dep]
        for i in free:
            env[vels[i]], deg[vels[i]] = self._draw(), Degree(1)
        block = [[row[j] for j in dep] for row in mu]
        rhs = [[-(h[k] + sum((mu[k][i] * env[vels[i]] for i in free), 0))]
               for k in range(len(mu))]
        # Degrees of the dependent velocities (Cramer): numerator and denominator
        # are minors of [block | rhs].
        dmu = [evaluate(row, deg, dcache) for row in self.mu]
        dh = evaluate(self.h, deg, dcache)
        dblock = [[row[j] for j in dep] + [dh[k] + sum((row[i] * Degree(1) for i in free), 0)]
                  for k, row in enumerate(dmu)]
        size = len(dep)
        top = minor_degree(dblock, size)
        self._den_degree = minor_degree([r[:size] for r in dblock], size)
        try:
            sol = exact_solve(block, rhs)
        except ZeroDivisionError:
            return None
        fresh = ("denominator", next(Degree._fresh))
        for pos, j in enumerate(dep):
            env[vels[j]] = sol[pos][0]
            deg[vels[j]] = Degree(top, {fresh: (self._den_degree, 1)})
        return ExactPoint(env, deg)


def jacobian_row(expr, symbols) -> list:
    """[d expr / d s for s in symbols], differentiating only where s occurs."""
    expr = sp.sympify(expr)
    present = expr.free_symbols
    return [derivative(expr, s) if s in present else sp.S.Zero for s in symbols]


def _exact_number(name, value):
    try:
        r = sp.Rational(str(value))
    except (TypeError, ValueError, sp.SympifyError) as exc:
        raise NotExact(f"parameter {name} = {value!r} is not an exact number") from exc
    return MPQ(int(r.p), int(r.q))


def eliminate_coordinates(coordinates, holonomic) -> dict:
    """Coordinates solved from holonomic constraints linear in them (constant coefficient)."""
    solved: dict = {}
    for g in holonomic:
        e = sp.expand(sp.sympify(g).xreplace(solved))
        if e == 0:
            continue
        for q in coordinates:
            if q in solved or q not in e.free_symbols:
                continue
            coeff = e.coeff(q, 1)
            rest = sp.expand(e - coeff * q)
            if coeff.free_symbols or coeff == 0 or rest.has(q):
                continue
            value = sp.expand(-rest / coeff)
            solved = {k: sp.expand(v.xreplace({q: value})) for k, v in solved.items()}
            solved[q] = value
            break
        else:
            raise NotExact(f"the holonomic constraint {g} = 0 is not linear in a coordinate "
                           f"with a constant coefficient")
    return solved
