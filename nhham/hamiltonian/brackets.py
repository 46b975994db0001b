"""Bracket algebra on functions of (q, p): canonical, Dirac and bivector brackets.

Conventions (``DESIGN.md`` §2): omega_Q = dq^A ^ dp_A and

    {f, g} = df/dq^A dg/dp_A - df/dp_A dg/dq^A,

the Hamiltonian vector field X_f = (df/dp, -df/dq) satisfies
i_{X_f} omega_Q = df, X_f(g) = {g, f} and {f, g} = omega_Q(X_f, X_g); so the
Hamiltonian flow is X_H(f) = {f, H}. Vector fields on T*Q are columns of length
2n in the order (q, p).

Every bracket here is bilinear and a derivation in each argument, so it is
given by a bivector Lambda (a 2n x 2n antisymmetric matrix of functions) with
{f, g} = grad(f)^T Lambda grad(g); for the canonical bracket Lambda = Omega_Q
= [[0, I], [-I, 0]]. The Jacobiator Jac(f, g, h) = {f, {g, h}} + {g, {h, f}} +
{h, {f, g}} of such a bracket is a trivector, so it is determined by its
values on triples of coordinate functions (:meth:`BivectorBracket.jacobiator_tensor`).
"""

from __future__ import annotations

from functools import cached_property
from itertools import combinations
from typing import Callable, Sequence

import numpy as np
import sympy as sp

from nhham.lagrangian.algebra import block_inverse, cancel
from nhham.lagrangian.graphs import connected_components

__all__ = [
    "canonical_bracket",
    "hamiltonian_vector_field",
    "BracketAlgebra",
    "BracketMatrix",
    "BivectorBracket",
    "DiracBracket",
    "jacobiator",
    "numeric_bracket_matrix",
    "connected_blocks",
]


def canonical_bracket(f, g, q: Sequence[sp.Symbol], p: Sequence[sp.Symbol]) -> sp.Expr:
    """{f, g} = df/dq^A dg/dp_A - df/dp_A dg/dq^A (not simplified).

    Parameters
    ----------
    f, g : sympy.Expr
        Functions of (q, p) (and parameters).
    q, p : sequence of sympy.Symbol, length n
        Coordinates and their conjugate momenta.

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import canonical_bracket
    >>> q, p = sp.symbols("q p")
    >>> canonical_bracket(q**2, p, [q], [p]), canonical_bracket(p**2 / 2, q, [q], [p])
    (2*q, -p)
    """
    f, g = sp.sympify(f), sp.sympify(g)
    return sum((sp.diff(f, qa) * sp.diff(g, pa) - sp.diff(f, pa) * sp.diff(g, qa)
                for qa, pa in zip(q, p)), sp.S.Zero)


def hamiltonian_vector_field(f, q: Sequence[sp.Symbol], p: Sequence[sp.Symbol]) -> sp.Matrix:
    """X_f = (df/dp, -df/dq) with i_{X_f} omega_Q = df; shape (2n, 1)."""
    f = sp.sympify(f)
    return sp.Matrix([sp.diff(f, pa) for pa in p] + [-sp.diff(f, qa) for qa in q])


def jacobiator(bracket: Callable, f, g, h, simplify: Callable = cancel) -> sp.Expr:
    """{f, {g, h}} + {g, {h, f}} + {h, {f, g}} for any bracket callable."""
    return simplify(bracket(f, bracket(g, h)) + bracket(g, bracket(h, f))
                    + bracket(h, bracket(f, g)))


class BracketAlgebra:
    """Canonical brackets on T*Q, computed on demand and cached.

    Parameters
    ----------
    coordinates, momenta : sequence of sympy.Symbol, length n
    simplify : callable, optional
        Applied to every bracket (default: rational cancellation, which makes
        identically vanishing brackets come out as 0).

    Notes
    -----
    Gradients and brackets are cached by expression; {g, f} is served as
    -{f, g} when the latter is known.

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import BracketAlgebra
    >>> q, p = sp.symbols("q p")
    >>> algebra = BracketAlgebra([q], [p])
    >>> algebra.bracket(q, p), algebra.bracket(q * p, q)
    (1, -q)
    """

    def __init__(self, coordinates: Sequence[sp.Symbol], momenta: Sequence[sp.Symbol],
                 simplify: Callable = cancel):
        self.coordinates = tuple(coordinates)
        self.momenta = tuple(momenta)
        self.simplify = simplify
        self._grad: dict = {}
        self._brackets: dict = {}

    @property
    def variables(self) -> tuple:
        """(q^1..q^n, p_1..p_n)."""
        return self.coordinates + self.momenta

    @property
    def n(self) -> int:
        return len(self.coordinates)

    def gradient(self, f) -> tuple[tuple, tuple]:
        """(df/dq, df/dp) as tuples of expressions (cached)."""
        f = sp.sympify(f)
        got = self._grad.get(f)
        if got is None:
            got = (tuple(sp.diff(f, q) for q in self.coordinates),
                   tuple(sp.diff(f, p) for p in self.momenta))
            self._grad[f] = got
        return got

    def bracket(self, f, g) -> sp.Expr:
        """{f, g} (cached, simplified)."""
        f, g = sp.sympify(f), sp.sympify(g)
        key = (f, g)
        if key in self._brackets:
            return self._brackets[key]
        if (g, f) in self._brackets:
            return -self._brackets[(g, f)]
        if f == g:
            value = sp.S.Zero
        else:
            fq, fp = self.gradient(f)
            gq, gp = self.gradient(g)
            value = self.simplify(sum((a * d - b * c for a, b, c, d in zip(fq, fp, gq, gp)),
                                      sp.S.Zero))
        self._brackets[key] = value
        return value

    __call__ = bracket

    def hamiltonian_field(self, f) -> sp.Matrix:
        """X_f = (df/dp, -df/dq), shape (2n, 1); X_f(g) = {g, f}."""
        fq, fp = self.gradient(f)
        return sp.Matrix(list(fp) + [-x for x in fq])

    def apply(self, field: sp.Matrix, f) -> sp.Expr:
        """X(f) = df(X) for a field given by its 2n components."""
        fq, fp = self.gradient(f)
        return sum((c * d for c, d in zip(list(field), fq + fp)), sp.S.Zero)

    def bracket_matrix(self, fs: Sequence, gs: Sequence | None = None) -> "BracketMatrix":
        """The matrix {f_a, g_b}, evaluated entry by entry on first access.

        With ``gs`` omitted it is the antisymmetric matrix {f_a, f_b}, of which
        only the upper triangle is ever computed.
        """
        return BracketMatrix(self, tuple(sp.sympify(f) for f in fs),
                             None if gs is None else tuple(sp.sympify(g) for g in gs))


class BracketMatrix:
    """Lazy matrix of brackets B[a, b] = {f_a, g_b} (entries cached in the algebra)."""

    def __init__(self, algebra: BracketAlgebra, fs: tuple, gs: tuple | None):
        self.algebra = algebra
        self.rows_functions = fs
        self.cols_functions = fs if gs is None else gs
        self.antisymmetric = gs is None

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.rows_functions), len(self.cols_functions)

    def __getitem__(self, index) -> sp.Expr:
        a, b = index
        return self.algebra.bracket(self.rows_functions[a], self.cols_functions[b])

    @cached_property
    def matrix(self) -> sp.Matrix:
        """All entries as a sympy Matrix."""
        r, c = self.shape
        if not self.antisymmetric:
            return sp.Matrix(r, c, lambda a, b: self[a, b])
        M = sp.zeros(r, r)
        for a in range(r):
            for b in range(a + 1, r):
                M[a, b] = self[a, b]
                M[b, a] = -M[a, b]
        return M


def numeric_bracket_matrix(Gq: np.ndarray, Gp: np.ndarray, Hq: np.ndarray | None = None,
                           Hp: np.ndarray | None = None) -> np.ndarray:
    """{f_a, g_b} at a point from gradient rows: Gq Hp^T - Gp Hq^T.

    Parameters
    ----------
    Gq, Gp : array, shape (k, n)
        d f_a / dq and d f_a / dp at the point.
    Hq, Hp : array, shape (l, n), optional
        Gradients of the g_b (default the f_a themselves); both or neither.
    """
    if Hq is None and Hp is None:
        Hq, Hp = Gq, Gp
    elif Hq is None or Hp is None:
        raise TypeError("numeric_bracket_matrix: give both Hq and Hp, or neither")
    return Gq @ Hp.T - Gp @ Hq.T


def connected_blocks(nonzero: np.ndarray | Sequence) -> list[list[int]]:
    """Index sets of the connected components of a symmetric nonzero pattern.

    Parameters
    ----------
    nonzero : array of bool, shape (k, k)
        nonzero[a, b] True when B[a, b] may be nonzero.

    Returns
    -------
    list of list of int
        Components in order of their smallest index, each sorted.
    """
    nz = np.asarray(nonzero, dtype=bool)
    k = nz.shape[0]
    edges = [(a, b) for a in range(k) for b in range(a + 1, k) if nz[a, b] or nz[b, a]]
    return sorted((sorted(c) for c in connected_components(range(k), edges)),
                  key=lambda c: c[0])


class BivectorBracket:
    """The bracket {f, g} = grad(f)^T Lambda grad(g) of a bivector Lambda.

    Parameters
    ----------
    tensor : sympy.Matrix, shape (2n, 2n)
        Lambda^{ij} = {z^i, z^j} on the variables z = (q, p).
    variables : sequence of sympy.Symbol, length 2n
    simplify : callable, optional
    """

    def __init__(self, tensor: sp.Matrix, variables: Sequence[sp.Symbol],
                 simplify: Callable = cancel):
        self.tensor = sp.Matrix(tensor)
        self.variables = tuple(variables)
        self.simplify = simplify
        self._cache: dict = {}

    def gradient(self, f) -> sp.Matrix:
        return sp.Matrix([sp.diff(f, z) for z in self.variables])

    def __call__(self, f, g) -> sp.Expr:
        f, g = sp.sympify(f), sp.sympify(g)
        key = (f, g)
        if key not in self._cache:
            self._cache[key] = self.simplify((self.gradient(f).T * self.tensor
                                              * self.gradient(g))[0])
        return self._cache[key]

    def field(self, f) -> sp.Matrix:
        """The vector field g -> {g, f}: Lambda grad(f), shape (2n, 1)."""
        return (self.tensor * self.gradient(f)).applyfunc(self.simplify)

    def jacobiator(self, f, g, h) -> sp.Expr:
        """{f, {g, h}} + {g, {h, f}} + {h, {f, g}}."""
        return jacobiator(self, f, g, h, self.simplify)

    @cached_property
    def _tensor_derivatives(self):
        return [self.tensor.diff(z) for z in self.variables]

    def jacobiator_component(self, i: int, j: int, k: int) -> sp.Expr:
        """Jac(z^i, z^j, z^k) = sum_l (L^{il} d_l L^{jk} + L^{jl} d_l L^{ki} + L^{kl} d_l L^{ij})."""
        L, dL = self.tensor, self._tensor_derivatives
        total = sp.S.Zero
        for l in range(len(self.variables)):
            total += L[i, l] * dL[l][j, k] + L[j, l] * dL[l][k, i] + L[k, l] * dL[l][i, j]
        return self.simplify(total)

    def jacobiator_tensor(self) -> dict:
        """Nonzero Jacobiator components ``{(i, j, k): expr}`` for i < j < k.

        Zero components are omitted; an empty dict means the bracket is
        Poisson wherever it is defined.
        """
        out = {}
        for i, j, k in combinations(range(len(self.variables)), 3):
            value = self.jacobiator_component(i, j, k)
            if value != 0:
                out[(i, j, k)] = value
        return out


class DiracBracket:
    """{f, g}_D = {f, g} - {f, chi_a} (B^{-1})^{ab} {chi_b, g} over second-class chi.

    B_ab = {chi_a, chi_b} is inverted block by block: the connected
    components of its nonzero pattern are independent (B is block diagonal
    in them), so each block is inverted separately.

    Parameters
    ----------
    algebra : BracketAlgebra
    constraints : sequence of sympy.Expr
        A second-class set chi_a (B invertible near the constraint set).
    blocks : sequence of sequence of int, optional
        Index sets of the blocks; default the connected components of the
        entries of B that are not identically zero (then the block inverse is
        the exact inverse of B wherever B is invertible, and the Dirac bracket
        satisfies the Jacobi identity there).
    matrix : sympy.Matrix, optional
        B to use instead of {chi_a, chi_b} (e.g. B reduced on M_f: the
        bracket is then the Dirac bracket on M_f only).
    """

    def __init__(self, algebra: BracketAlgebra, constraints: Sequence, blocks=None,
                 matrix: sp.Matrix | None = None):
        self.algebra = algebra
        self.constraints = tuple(sp.sympify(c) for c in constraints)
        self._matrix = None if matrix is None else sp.Matrix(matrix)
        self._blocks = None if blocks is None else [list(b) for b in blocks]
        self._cache: dict = {}

    @cached_property
    def matrix(self) -> sp.Matrix:
        """B_ab = {chi_a, chi_b}, shape (k, k)."""
        if self._matrix is not None:
            return self._matrix
        return self.algebra.bracket_matrix(self.constraints).matrix

    @cached_property
    def blocks(self) -> list[list[int]]:
        """Index sets of the independent blocks of B."""
        if self._blocks is not None:
            return self._blocks
        B = self.matrix
        nz = np.array([[B[a, b] != 0 for b in range(B.cols)] for a in range(B.rows)], dtype=bool)
        return connected_blocks(nz) if B.rows else []

    @cached_property
    def block_inverses(self) -> list[sp.Matrix]:
        """(B_block)^{-1} for every block, in the order of :attr:`blocks`."""
        out = []
        for block in self.blocks:
            Bb = self.matrix.extract(block, block)
            out.append(block_inverse(Bb))
        return out

    def correction(self, f, g) -> sp.Expr:
        """{f, chi_a} (B^{-1})^{ab} {chi_b, g}."""
        total = sp.S.Zero
        for block, inv in zip(self.blocks, self.block_inverses):
            left = [self.algebra.bracket(f, self.constraints[a]) for a in block]
            right = [self.algebra.bracket(self.constraints[b], g) for b in block]
            for i, la in enumerate(left):
                if la == 0:
                    continue
                for j, rb in enumerate(right):
                    if rb != 0 and inv[i, j] != 0:
                        total += la * inv[i, j] * rb
        return total

    def __call__(self, f, g) -> sp.Expr:
        f, g = sp.sympify(f), sp.sympify(g)
        key = (f, g)
        if key not in self._cache:
            self._cache[key] = self.algebra.simplify(self.algebra.bracket(f, g)
                                                     - self.correction(f, g))
        return self._cache[key]

    def field(self, H) -> sp.Matrix:
        """The Dirac flow of H: the field z -> {z, H}_D on z = (q, p), shape (2n, 1)."""
        return sp.Matrix([self(z, H) for z in self.algebra.variables])

    def jacobiator(self, f, g, h) -> sp.Expr:
        return jacobiator(self, f, g, h, self.algebra.simplify)
