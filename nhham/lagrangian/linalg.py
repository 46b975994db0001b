"""Linear algebra in every arithmetic: ranks, solves, determinants, minors.

Exact matrices are sympy ``DomainMatrix`` over QQ, GF(p) or Q(params) (their
``*``, ``-`` and ``transpose``), or lists of rows of :mod:`nhham.lagrangian.domains`
values; :class:`FloatMatrix` gives a numpy array the same interface, so a formula
written against it (:mod:`nhham.lagrangian.formulas`) runs in floating point too.
:func:`field_solve` and :func:`field_det` dispatch on the kind of matrix.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import operator

import numpy as np
from sympy import QQ
from sympy.external.gmpy import MPQ
from sympy.matrices.exceptions import NonInvertibleMatrixError
from sympy.polys.matrices import DomainMatrix
from sympy.polys.matrices.exceptions import DMNonInvertibleMatrixError

from nhham.lagrangian.domains import PRIME, Degree, ModP, Program, minor_degree
from nhham.lagrangian.modular_program import ModularProgram
from nhham.system.evaluation import Backend, flatten

__all__ = [
    "exact_rank",
    "exact_solve",
    "maximal_minors",
    "adjacent_column_sets",
    "field_det",
    "log_det",
    "LogDet",
    "field_solve",
    "FLOAT64",
    "FloatMatrix",
    "ListMatrix",
    "zeros_like",
    "degree_solve",
    "solve_degrees",
    "ModularBackend",
]


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


def maximal_minors(M: DomainMatrix, pivots=None, subsets=None, det=None) -> list:
    """Every maximal minor of an m x n DomainMatrix M (m <= n) over a field, in the order
    of ``itertools.combinations(range(n), m)`` (or of the column sets ``subsets``, each
    sorted; ``adjacent_column_sets`` gives the m (n - m) + 1 that decide the rank).

    One elimination instead of C(n, m) determinants: with P the pivot columns of M and
    R = M[:, P]^{-1} M (so R[:, P] = I), det M[:, S] = det M[:, P] det R[:, S], and
    det R[:, S] is, up to the sign of a generalised Laplace expansion along the unit
    columns, the minor of R on the rows of P \\ S and the columns of S \\ P (at most
    (n - m) x (n - m)). ``pivots`` gives P (the pivot columns, found by an exact
    evaluation) instead of finding it: in floating point a rounded zero is not zero.
    Fewer than m pivots: every minor is zero. ``det`` forms the determinants (default
    :func:`field_det`; :func:`log_det` keeps a large float64 system's in range).
    """
    det = field_det if det is None else det
    m, n = M.shape
    if pivots is None:
        _, pivots = M.rref()
    if subsets is None:
        subsets = list(itertools.combinations(range(n), m))
    if len(pivots) < m:
        return [M.domain.zero] * len(subsets)
    P = list(pivots)
    B = M.extract(list(range(m)), P)
    det_B = det(B)
    R = field_solve(B, M)
    row_of = {c: i for i, c in enumerate(P)}
    out = []
    for S in subsets:
        unit = [j for j, c in enumerate(S) if c in row_of]
        other = [S[j] for j, c in enumerate(S) if c not in row_of]
        used = [row_of[S[j]] for j in unit]
        taken = set(used)
        rest = [i for i in range(m) if i not in taken]
        sub = det(R.extract(rest, other)) if other else M.domain.one
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
    :func:`field_solve`, :func:`maximal_minors` and the formulas use, on a numpy float64
    array (LAPACK's partially pivoted LU): for estimates where 200-bit arithmetic is not
    needed. An ``object`` array of mpmath numbers is kept as it is (the mpmath backend;
    its solve is then the caller's).
    """

    domain = FLOAT64

    def __init__(self, a):
        a = np.asarray(a)
        self.a = a if a.dtype == object else a.astype(float)

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

    def __add__(self, other) -> "FloatMatrix":
        return FloatMatrix(self.a + other.a)

    def __sub__(self, other) -> "FloatMatrix":
        return FloatMatrix(self.a - other.a)

    def __neg__(self) -> "FloatMatrix":
        return FloatMatrix(-self.a)

    def to_list(self) -> list:
        return self.a.tolist()


def backend_solve(backend):
    """The ``solve`` of the formulas (:mod:`nhham.lagrangian.formulas`) for
    :class:`FloatMatrix` of a :class:`~nhham.system.evaluation.Backend`'s arrays
    (float64, mpmath, or residues with :class:`ModularBackend`)."""
    return lambda A, X: FloatMatrix(backend.solve(A.a, X.a))


def _residue_rows(rows):
    """(values, flags) when every entry is a :class:`~nhham.lagrangian.domains.ModP` or
    an int: the entries as ints and, per row, whether it holds a residue; else None."""
    values, flags = [], []
    for r in rows:
        row, mod = [], False
        for x in r:
            t = type(x)
            if t is ModP:
                row.append(x.v)
                mod = True
            elif t is int:
                row.append(x)
            else:
                return None
        values.append(row)
        flags.append(mod)
    return values, flags


class ListMatrix:
    """Rows of Python scalars (``MPQ``, :class:`~nhham.lagrangian.domains.ModP`,
    :class:`~nhham.lagrangian.domains.Degree`) with the part of the DomainMatrix
    interface the formulas use: ``*`` (the matrix product), ``-``, ``transpose``,
    ``extract``, ``hstack``, ``vstack``.

    Values of mixed kinds (an exact angle's rational next to a residue) combine by the
    scalars' own operators; :func:`field_solve` picks the solve by the kind of entry.
    The number of columns is kept apart from the rows, so that a matrix with no rows
    (no constraints) still has its width: its transpose has that many rows.
    """

    def __init__(self, rows, ncols: int | None = None):
        self.rows = [list(r) for r in rows]
        self.ncols = len(self.rows[0]) if self.rows else (ncols or 0)

    @property
    def shape(self) -> tuple:
        return (len(self.rows), self.ncols)

    def transpose(self) -> "ListMatrix":
        return ListMatrix([[r[j] for r in self.rows] for j in range(self.ncols)],
                          len(self.rows))

    def __mul__(self, other) -> "ListMatrix":
        cols = [[r[j] for r in other.rows] for j in range(other.ncols)]
        a = _residue_rows(self.rows)
        b = a and _residue_rows(cols)
        if a and b:
            # on ints: an object per product and per sum was most of a large bracket's
            # cost (the 64-link snake's classes). An entry is a residue where its row or
            # column holds one (as the scalars' own operators give), else an exact int.
            return ListMatrix([[ModP(x) if rm or cm else x for x, cm in zip(
                (sum(map(operator.mul, row, col)) for col in b[0]), b[1])]
                for row, rm in zip(*a)], other.ncols)
        return ListMatrix([[sum((x * y for x, y in zip(row, col)), 0) for col in cols]
                           for row in self.rows], other.ncols)

    def __add__(self, other) -> "ListMatrix":
        return ListMatrix([[x + y for x, y in zip(r, s)] for r, s in zip(self.rows, other.rows)],
                          self.ncols)

    def __sub__(self, other) -> "ListMatrix":
        return ListMatrix([[x - y for x, y in zip(r, s)] for r, s in zip(self.rows, other.rows)],
                          self.ncols)

    def __neg__(self) -> "ListMatrix":
        return ListMatrix([[-x for x in r] for r in self.rows], self.ncols)

    def extract(self, rows, cols) -> "ListMatrix":
        return ListMatrix([[self.rows[i][j] for j in cols] for i in rows], len(cols))

    def hstack(self, other) -> "ListMatrix":
        if len(self.rows) != len(other.rows):
            raise ValueError(f"hstack: {self.shape} beside {other.shape}")
        return ListMatrix([r + s for r, s in zip(self.rows, other.rows)],
                          self.ncols + other.ncols)

    def vstack(self, other) -> "ListMatrix":
        if self.ncols != other.ncols:
            raise ValueError(f"vstack: {self.shape} above {other.shape}")
        return ListMatrix(self.rows + other.rows, self.ncols)

    def to_list(self) -> list:
        return [list(r) for r in self.rows]


def zeros_like(M, shape):
    """A zero matrix of ``shape`` of the same kind (and domain) as ``M``."""
    if isinstance(M, ListMatrix):
        return ListMatrix([[0] * shape[1] for _ in range(shape[0])], shape[1])
    if isinstance(M, FloatMatrix):
        return FloatMatrix.zeros(shape)
    return DomainMatrix.zeros(shape, M.domain)


def field_det(M: DomainMatrix):
    """det M; in floating point by elimination with partial pivoting (sympy's
    fraction-free elimination divides by rounded, possibly tiny, pivots)."""
    if isinstance(M, FloatMatrix):
        if not M.shape[0]:
            return 1.0
        # a large system's determinant overflows float64 (the 48-link snake's did, with
        # numpy's warning shown to the user): +-inf then, which the caller takes to a
        # wider field (exceptional.FLOAT_MARGIN), not a warning
        with np.errstate(over="ignore", under="ignore"):
            return float(np.linalg.det(M.a))
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


class LogDet:
    """A float64 determinant as ``sign * exp(log)``: the products of many pivots stay in
    range (the 48-link snake's bracket minors overflowed float64, and the estimate fell
    back to 200-bit arithmetic for that alone).

    Products (with LogDets or numbers), negation, truth (nonzero) and the ratio of two
    (a float) are what the nearness estimates use.

    Examples
    --------
    >>> import numpy as np
    >>> big = log_det(FloatMatrix(np.diag([1e200] * 3)))
    >>> big.sign, round(big.log / math.log(10), 6), bool(big)
    (1.0, 600.0, True)
    >>> round((-big * 2.0) / big, 9)   # a ratio from logarithms: about 1e-13 relative
    -2.0
    """

    __slots__ = ("sign", "log")

    def __init__(self, sign: float, log: float) -> None:
        self.sign, self.log = float(sign), float(log)

    @classmethod
    def of(cls, x) -> "LogDet":
        """A number (or a LogDet) as a LogDet."""
        if isinstance(x, LogDet):
            return x
        x = float(x)
        return cls(math.copysign(1.0, x), math.log(abs(x))) if x else cls(0.0, -math.inf)

    def __mul__(self, other) -> "LogDet":
        other = LogDet.of(other)
        return LogDet(self.sign * other.sign, self.log + other.log)

    __rmul__ = __mul__

    def __neg__(self) -> "LogDet":
        return LogDet(-self.sign, self.log)

    def __bool__(self) -> bool:
        return self.sign != 0.0

    def __truediv__(self, other) -> float:
        other = LogDet.of(other)
        if not other:
            raise ZeroDivisionError("division by a zero determinant")
        if not self:
            return 0.0
        try:
            return self.sign * other.sign * math.exp(self.log - other.log)
        except OverflowError:
            return self.sign * other.sign * math.inf

    def __repr__(self) -> str:
        return f"LogDet(sign={self.sign:g}, log={self.log!r})"


def log_det(M):
    """:func:`field_det`, but a :class:`FloatMatrix`'s determinant as a :class:`LogDet`
    (numpy's ``slogdet``: LU, the logarithms of the pivots added)."""
    if not isinstance(M, FloatMatrix) or M.a.dtype == object:
        return field_det(M)
    if not M.shape[0]:
        return LogDet(1.0, 0.0)
    sign, log = np.linalg.slogdet(M.a)
    return LogDet(sign, log) if sign else LogDet(0.0, -math.inf)


def field_solve(A: DomainMatrix, B: DomainMatrix) -> DomainMatrix:
    """A^-1 B; in floating point with partial pivoting (see :func:`field_det`).

    ``A`` and ``B`` of one kind: DomainMatrix (over a field), :class:`FloatMatrix`
    (float64) or :class:`ListMatrix` of exact scalars (:func:`exact_solve`; degree
    bounds solve by :func:`degree_solve`). ZeroDivisionError where ``A`` is singular.
    """
    if isinstance(A, ListMatrix):
        return ListMatrix(exact_solve(A.rows, B.rows), B.ncols)
    if isinstance(A, FloatMatrix):
        try:
            return FloatMatrix(np.linalg.solve(A.a, B.a))
        except np.linalg.LinAlgError as exc:
            raise ZeroDivisionError("singular matrix") from exc
    K = A.domain
    if K.is_QQ:  # fraction-free elimination: 8x lu_solve's speed on the 64-link snake
        X, den = A.solve_den(B)
        return X if den == K.one else X.mul(K.one / den)
    if K.is_FiniteField:  # on plain ints (sympy's residues are objects): 6x lu_solve's
        p, n = int(K.characteristic()), A.shape[0]
        try:
            X = _solve_ints_mod([[int(K.to_int(x)) % p for x in a + b] for a, b in
                                 zip(A.to_list(), B.to_list())], n, p)
        except ZeroDivisionError as exc:  # what lu_solve raises
            raise DMNonInvertibleMatrixError("singular matrix") from exc
        return DomainMatrix([[K(x) for x in row] for row in X], B.shape, K)
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
    return [[x.v if type(x) is ModP else ModP.lift(x).v for x in row] for row in rows]


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
    return [[ModP(x) for x in row] for row in _solve_ints_mod(M, n, PRIME)]


def _solve_ints_mod(M, n: int, p: int) -> list:
    """The rows of A^-1 B from [A | B] (n rows of residues modulo the prime p, changed in
    place) by Gauss-Jordan elimination; ZeroDivisionError when A is singular."""
    for c in range(n):
        k = next((i for i in range(c, n) if M[i][c]), None)
        if k is None:
            raise ZeroDivisionError("singular block modulo p")
        M[c], M[k] = M[k], M[c]
        inv = pow(M[c][c], -1, p)
        M[c] = [x * inv % p for x in M[c]]
        for i in range(n):
            if i != c and M[i][c]:
                f = M[i][c]
                M[i] = [(a - f * bb) % p for a, bb in zip(M[i], M[c])]
    return [row[n:] for row in M]


def degree_solve(A: ListMatrix, B: ListMatrix) -> ListMatrix:
    """The solve of the Degree arithmetic: bounds of A⁻¹ B (:func:`solve_degrees`)."""
    return ListMatrix(solve_degrees(A.rows, B.rows), B.ncols)


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


class ModularBackend(Backend):
    """Exact arithmetic in F_p (p = 2^61 - 1) at the modular points of
    :class:`~nhham.lagrangian.points.PointSampler` (``modular=True``).

    Arrays are ``object`` arrays of :class:`~nhham.lagrangian.domains.ModP`. A
    coordinate's value is an :class:`~nhham.lagrangian.domains.Angle` (its sine and
    cosine exact), so coordinate values are only handed to :class:`Lambdified`, never
    computed with. Two quantities are equal or they are not: the tolerance is 0, and
    the "size" of a difference is 0 or 1 (F_p has no absolute value). Fixed-size
    residues keep this fast where exact rationals at random points grow large.
    """

    def __init__(self):
        self.precision = "modular"
        self.module = "modular"

    def evaluate(self, f, values) -> np.ndarray:
        """``f``'s expressions at the exact point ``values``: no compilation, the sines
        and cosines of Angles exact."""
        program = f.__dict__.get("_modular_program")
        if program is None:  # compiled once per function: it is run at every point
            program = f.__dict__["_modular_program"] = ModularProgram(Program(f.exprs))
        out = [ModP(x) for x in program.run(dict(zip(f.args, values)))]
        return np.array(out, dtype=object)

    @property
    def label(self) -> str:
        return "exact mod p = 2^61 - 1"

    def context(self):
        return contextlib.nullcontext()

    def default_tol(self) -> float:
        return 0.0

    def scalar(self, x):
        return ModP.lift(x)

    def vector(self, xs) -> np.ndarray:
        return np.array(flatten(xs), dtype=object)

    def matrix(self, rows, shape=None) -> np.ndarray:
        out = np.array([[ModP.lift(x) for x in r] for r in rows], dtype=object) \
            if len(rows) else np.zeros((0, 0), dtype=object)
        return out.reshape(shape) if shape is not None else out

    def zeros(self, *shape) -> np.ndarray:
        out = np.empty(shape, dtype=object)
        out.fill(ModP(0))
        return out

    def norm(self, x):
        return 1.0 if any(e != 0 for e in x.ravel()) else 0.0

    def solve(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """A^{-1} B over F_p; ZeroDivisionError when A is singular modulo p."""
        n = A.shape[0]
        vec = B.ndim == 1
        rhs = B.reshape(n, 1) if vec else B
        if rhs.shape[1] == 0:
            return np.empty(B.shape, dtype=object)
        X = exact_solve([[ModP.lift(x) for x in row] for row in A],
                        [[ModP.lift(x) for x in row] for row in rhs])
        out = np.array(X, dtype=object).reshape(n, rhs.shape[1])
        return out[:, 0] if vec else out
