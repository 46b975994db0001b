"""δ W⁻¹ without division: the inverse-free fields of the constraint algorithm on TQ.

The tangency condition of a constraint χ on M_k, ξ_L(χ) + λ^i Z_i(χ) = 0, is a
linear equation in λ whose coefficients contain W⁻¹ (W = ∂²L/∂v∂v) through
ξ_L = (v, W⁻¹F) and Z_i = (0, −W⁻¹μ_iᵀ) (DESIGN.md §2). Multiplied by a function
δ with δ W⁻¹ free of denominators (δ = det W will do, since δ W⁻¹ = adj W), the
same condition reads

    ξ̃(χ) + λ^i Z̃_i(χ) = 0,   ξ̃ = δ ξ_L = (δ v, δ W⁻¹ F),   Z̃_i = δ Z_i = (0, −δ W⁻¹ μ_iᵀ),

which is equivalent wherever δ ≠ 0 (W is regular there: the denominator that must
not vanish). The multipliers solved from it are the same λ, the ranks of
(Z̃_i(χ_j)) and (Z_i(χ_j)) agree, and a λ-free condition is δ times the old one,
so a new constraint is the old one with factors of δ removed.

The entries of δ W⁻¹ are polynomials in the entries of W (adjugates of its
diagonal blocks), so every tangency row ξ̃(χ), Z̃_i(χ) is a polynomial (in v, and
in q or sines and cosines of q) that is expanded, never a rational function that
must be cancelled. W is split into the diagonal blocks of its sparsity pattern
(connected components), each block's adjugate is formed fraction-free (closed
forms up to 2 x 2, beyond in the polynomial ring of its entries, sines and cosines as
generators, where the characteristic polynomial gives it without division) and::

    δ = lcm of the determinants of the blocks that depend on the state,
    δ W⁻¹ restricted to block k = (δ / det W_k) adj W_k,

a block whose determinant is free of the state (a number, or a function of the
parameters) being inverted outright (adj W_k / det W_k). So δ = 1 and the scaled
fields are ξ_L and Z_i themselves when W does not depend on the state (every
paper example), and nothing changes there.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from sympy.polys.matrices import DomainMatrix
from sympy.polys.matrices.exceptions import DMNotAField

from nhham.errors import ComputationError
from nhham.lagrangian.algebra import POLYNOMIAL_ERRORS, trig_normal
from nhham.lagrangian.graphs import connected_components

__all__ = ["ScaledInverse", "scaled_inverse", "divide_out", "scale_factors",
           "closed_form_size", "CLOSED_FORM_WORK"]

#: Closed forms of W^-1 (P(xi_L), lambda, C, H = E_L o Leg^-1 and all that is transported
#: by Leg^-1) are formed when the operations of delta and delta W^-1 times n (every
#: transported field and bracket has n such components) are at most this. The size of the
#: work, not n alone: a dense 3 x 3 trigonometric W (a rigid body in Euler angles, 333
#: operations: 999) makes every transported bracket a cancellation of minutes; a ball's
#: 5 x 5 one (23: 115) turns a 2 s cross-check into 15 s; a 2 x 2 one (a cart with a
#: pendulum, 21: 42) costs nothing.
CLOSED_FORM_WORK = 100



@dataclass(frozen=True)
class ScaledInverse:
    """S = δ W⁻¹ as diagonal blocks of polynomial entries, and the scale δ.

    Attributes
    ----------
    scale : sympy.Expr
        δ (1 when W does not depend on the state); δ ≠ 0 wherever W is regular.
    blocks : tuple of (tuple of int, sympy.Matrix)
        ``(indices, S_k)``: S restricted to the rows and columns ``indices`` (the
        other entries of S are zero).
    size : int
        n, the size of W.
    """

    scale: sp.Expr
    blocks: tuple
    size: int

    def apply(self, rhs: sp.Matrix) -> sp.Matrix:
        """S rhs = δ W⁻¹ rhs with expanded entries (no division), shape of ``rhs``."""
        out = sp.zeros(self.size, rhs.cols)
        for idx, S in self.blocks:
            part = S * rhs.extract(list(idx), list(range(rhs.cols)))
            for a, i in enumerate(idx):
                for c in range(rhs.cols):
                    out[i, c] = sp.expand(part[a, c])
        return out

    def matrix(self) -> sp.Matrix:
        """S as an n x n matrix (for tests and reports)."""
        out = sp.zeros(self.size, self.size)
        for idx, S in self.blocks:
            for a, i in enumerate(idx):
                for c, j in enumerate(idx):
                    out[i, j] = S[a, c]
        return out


def scaled_inverse(W: sp.Matrix, state) -> ScaledInverse:
    """δ W⁻¹ without a symbolic inverse (see the module docstring).

    Parameters
    ----------
    W : sympy.Matrix, shape (n, n)
        The velocity Hessian of L (regular).
    state : iterable of sympy.Symbol
        The variables of TQ (q, v): a block whose determinant contains none of them
        is inverted outright instead of scaling.

    Returns
    -------
    ScaledInverse

    Raises
    ------
    ComputationError
        When a diagonal block of W has determinant identically zero.
    """
    state = set(state)
    parts = []
    dets = []
    for idx in _diagonal_blocks(W):
        Wk = W.extract(idx, idx)
        adj, det = _adjugate(Wk)
        if det == 0:
            raise ComputationError(f"the block {idx} of W has determinant 0 (W is singular)")
        parts.append((tuple(idx), adj, det))
        if det.free_symbols & state:
            dets.append(det)
    scale = _lcm(dets)
    blocks = []
    for idx, adj, det in parts:
        if det.free_symbols & state:
            factor = _exact_quotient(scale, det)
            S = adj if factor == 1 else adj.applyfunc(lambda e: sp.expand(factor * e))
        else:
            # Free of the state: invert outright (numbers, or parameters only).
            S = adj.applyfunc(lambda e: sp.expand(scale * _over(e, det)))
        blocks.append((idx, S))
    return ScaledInverse(scale, tuple(blocks), W.rows)


def closed_form_size(W: sp.Matrix, state, scaled=None, max_terms: int = 64) -> int | None:
    """The size (operations) of W^-1 in closed form, or None when it is too large to form.

    0 when W is diagonal or free of the state (its inverse divides entrywise, or is a
    matrix of numbers and parameters); else the operations of delta and delta W^-1
    (:func:`scaled_inverse`), formed only when :func:`determinant_terms` bounds every
    block's determinant by ``max_terms`` terms (a rigid body in Euler angles: 41, its
    adjugate formed in 0.05 s; the rattleback: 2,716 and 19 s; the Whipple bicycle: 7e10,
    minutes and gigabytes). ``scaled``: a callable returning the :class:`ScaledInverse`
    when it is to be formed (the geometry's cached one), default :func:`scaled_inverse`.

    Examples
    --------
    >>> import sympy as sp
    >>> th, m, l = sp.symbols("theta m l")
    >>> W = sp.Matrix([[2*m, m*l*sp.cos(th)], [m*l*sp.cos(th), m*l**2]])
    >>> closed_form_size(W, [th])
    21
    >>> closed_form_size(W, [th], max_terms=1) is None    # det W: up to 2 terms
    True
    """
    state = set(state)
    if not (W.free_symbols & state) or all(W[i, j] == 0 for i in range(W.rows)
                                            for j in range(W.cols) if i != j):
        return 0
    for idx in _diagonal_blocks(W):
        if determinant_terms(W.extract(idx, idx)) > max_terms:
            return None
    S = scaled() if scaled is not None else scaled_inverse(W, state)
    return sum(sp.count_ops(e) for e in S.matrix() if e != 0) + sp.count_ops(S.scale)


def determinant_terms(Wk: sp.Matrix) -> int:
    """An upper bound on the terms of det W_k expanded: the permanent of the matrix of
    its entries' term counts (every product of a Leibniz term expanded, nothing
    cancelling), by dynamic programming over the column sets (2^k k steps)."""
    k = Wk.rows
    counts = [[_terms(Wk[i, j]) for j in range(k)] for i in range(k)]
    if k > 20:  # pragma: no cover - 2^k states; such a block is never small
        return 2 ** 64
    perm = {0: 1}
    for i in range(k):
        nxt: dict = {}
        for mask, value in perm.items():
            for j in range(k):
                if counts[i][j] and not mask & (1 << j):
                    key = mask | (1 << j)
                    nxt[key] = nxt.get(key, 0) + value * counts[i][j]
        perm = nxt
    return sum(perm.values())


def _terms(entry) -> int:
    """Terms of an entry once expanded, bounded from above without expanding: a sum counts
    its summands' terms, a product multiplies them, a power p**k counts p's to the k."""
    if entry == 0:
        return 0
    if entry.is_Add:
        return sum(_terms(a) for a in entry.args)
    if entry.is_Mul:
        out = 1
        for a in entry.args:
            out *= _terms(a)
        return out
    if entry.is_Pow and entry.exp.is_Integer and entry.exp > 0 and entry.base.is_Add:
        return _terms(entry.base) ** int(entry.exp)
    return 1


def scale_factors(scale) -> tuple:
    """The distinct non-constant factors of δ (what :func:`divide_out` removes)."""
    scale = sp.sympify(scale)
    if scale.is_number:
        return ()
    try:
        _, factors = sp.factor_list(scale)
    except POLYNOMIAL_ERRORS:  # pragma: no cover - not a polynomial in its generators
        return (scale,)
    return tuple(f for f, _ in factors if not f.is_number)


def divide_out(expr, factors) -> sp.Expr:
    """The numerator of ``expr`` with every power of each factor of δ divided out.

    Where δ ≠ 0 (the domain: W regular) the result has the zeros of ``expr``: a
    λ-free condition ψ̃ = δ ψ becomes a function with the zeros of ψ and without
    the factors of δ (the numerators of the paper's conditions, common factors
    removed). A factor is divided out only where the polynomial division (sines
    and cosines as generators) is exact.
    """
    num = sp.numer(sp.together(expr)) if factors else expr
    for p in factors:
        while num != 0 and not num.is_number:
            try:
                quo, rem = sp.div(num, p)
            except POLYNOMIAL_ERRORS:
                break
            if rem != 0:
                break
            num = quo
    return sp.expand(num) if factors else num


# ------------------------------------------------------------------ helpers
def _diagonal_blocks(W) -> list:
    """Index sets of the diagonal blocks of W (connected components of its pattern)."""
    edges = [(i, j) for i in range(W.rows) for j in range(i + 1, W.cols)
             if W[i, j] != 0 or W[j, i] != 0]
    return sorted(sorted(c) for c in connected_components(range(W.rows), edges))


def _adjugate(Wk):
    """(adj W_k, det W_k), fraction-free, entries expanded.

    Up to 2 x 2 in closed form; beyond, in the polynomial ring of the entries (sines and
    cosines as generators, :func:`_ring_adjugate`), else by sympy's Bareiss cofactors.
    The determinant is reduced modulo sin^2 + cos^2 = 1 when that makes it shorter (a
    block whose determinant is a number there is then inverted outright).
    """
    k = Wk.rows
    if k == 1:
        return sp.Matrix([[1]]), sp.expand(Wk[0, 0])
    if k == 2:
        a, b, c, d = Wk[0, 0], Wk[0, 1], Wk[1, 0], Wk[1, 1]
        adj = sp.Matrix([[d, -b], [-c, a]]).applyfunc(sp.expand)
    else:
        adj = _ring_adjugate(Wk)
        if adj is None:
            # Each cofactor a Bareiss determinant of a minor: exact divisions only.
            adj = Wk.adjugate(method="bareiss").applyfunc(sp.expand)
    # Laplace expansion along the first row reuses the cofactors: det = W[0, :] adj[:, 0].
    det = sp.expand(sum((Wk[0, j] * adj[j, 0] for j in range(k)), sp.S.Zero))
    if det.has(sp.sin, sp.cos):
        # adj W = det W^-1 as functions, so any form of det that is equal modulo
        # sin^2 + cos^2 = 1 serves; the shortest keeps δ and its factors small.
        short = trig_normal(det)
        if short is not None and sp.count_ops(short) < sp.count_ops(det):
            det = sp.expand(short)
    return adj, det


def _ring_adjugate(Wk):
    """adj W_k computed in the polynomial ring of its entries (division-free), or None.

    Sines and cosines become independent generators; the adjugate (characteristic
    polynomial, no division) is exact there, hence also as functions. None when an
    entry is not a polynomial in its generators (sympy's EX domain).
    """
    rep, back = {}, {}
    for atom in Wk.atoms(sp.sin, sp.cos):
        d = sp.Dummy(atom.func.__name__)
        rep[atom], back[d] = d, atom
    try:
        dM = DomainMatrix.from_Matrix(Wk.xreplace(rep))
        if dM.domain.is_EX or dM.domain.is_EXRAW:
            return None
        adj, _ = dM.adj_det()
    except POLYNOMIAL_ERRORS + (NotImplementedError, DMNotAField):  # pragma: no cover
        return None
    return adj.to_Matrix().applyfunc(lambda e: sp.expand(e.xreplace(back)))


def _lcm(dets) -> sp.Expr:
    """lcm of the state-dependent block determinants (their product if sympy cannot)."""
    out = sp.S.One
    for d in dets:
        try:
            out = sp.lcm(out, d)
        except POLYNOMIAL_ERRORS:  # pragma: no cover - not polynomial in its generators
            out = out * d
    if out.is_number:
        return sp.S.One
    # The numeric content is irrelevant to the zero set: keep the primitive part.
    content, prim = sp.factor_terms(sp.expand(out)).as_coeff_Mul()
    return sp.expand(prim) if content.is_number and content != 0 else sp.expand(out)


def _exact_quotient(a, b) -> sp.Expr:
    """a / b for b dividing a (polynomial division, sines and cosines as generators)."""
    try:
        quo, rem = sp.div(a, b)
    except POLYNOMIAL_ERRORS:  # pragma: no cover - not polynomial in its generators
        return sp.cancel(a / b)
    return sp.expand(quo) if rem == 0 else sp.cancel(a / b)


def _over(entry, det) -> sp.Expr:
    """entry / det for a state-free det: a number divides, parameters are cancelled."""
    if det.is_number:
        return sp.expand(entry / det)
    return sp.cancel(entry / det)
