"""The polynomial structure of expressions in the velocities.

A Lagrangian quadratic in v (L = v^T A(q) v / 2 + b(q) . v + c(q)) has constant fibre
derivatives' Hessian W = A: the geometry's fast path. Constraints affine in v have
one-forms mu = d phi / d v free of v. Read by collecting monomials, without expanding
the coefficients.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import sympy as sp


__all__ = ["QuadraticParts", "velocity_polynomial", "velocity_free_part", "quadratic_parts",
           "one_forms", "non_affine_terms"]


@dataclass(frozen=True)
class QuadraticParts:
    """L = v^T W(q) v / 2 + b(q) . v - V(q), read from the terms of L.

    Attributes
    ----------
    W : sympy.ImmutableMatrix, shape (n, n)
        d2L/dv^A dv^B (free of velocities).
    b : tuple of sympy.Expr, length n
        The coefficients of the terms linear in the velocities.
    V : sympy.Expr
        Minus the velocity-free part of L.
    """

    W: sp.ImmutableMatrix
    b: tuple
    V: sp.Expr


# ------------------------------------------------- polynomial structure in v
class _NotPolynomial(Exception):
    """Raised inside :func:`velocity_polynomial` when the structure does not fit."""


def velocity_polynomial(expr, velocities, max_degree: int = 2):
    """The coefficients of ``expr`` as a polynomial in the velocities, or None.

    One pass over the expression tree: sums and products are distributed only
    where a velocity is involved, so velocity-free factors (sin, cos, sums in
    q) stay as they are and nothing is differentiated or fully expanded.

    Parameters
    ----------
    expr : sympy.Expr
    velocities : sequence of sympy.Symbol
    max_degree : int
        Largest total degree accepted.

    Returns
    -------
    dict or None
        ``{key: coefficient}`` where ``key`` is the sorted tuple of velocity
        indices of the monomial (``()``, ``(A,)``, ``(A, C)``, ...), with
        coefficients free of the velocities and structurally nonzero; None
        when ``expr`` is not structurally such a polynomial (a velocity inside
        a function, a negative or fractional power of a velocity, or a product
        of degree > ``max_degree`` before cancellation), so the caller falls
        back to differentiation.
    """
    found = _velocity_polynomial(sp.sympify(expr), tuple(velocities), max_degree)
    return None if found is None else dict(found)


@functools.lru_cache(maxsize=1024)
def _velocity_polynomial(expr, velocities, max_degree):
    # Memoised: the kind of each constraint, its one-forms and its velocity-free part
    # read the same constraints (a pass over each of the 64-link snake's takes 0.2 s).
    vidx = {v: i for i, v in enumerate(velocities)}
    try:
        terms = _poly(expr, vidx, max_degree)
    except _NotPolynomial:
        return None
    out = {}
    for key, summands in terms.items():
        c = sp.Add(*summands)
        if c != 0:
            out[key] = c
    return out


def _poly(expr, vidx, max_degree):
    """{monomial key: list of summands of its coefficient}."""
    if not (expr.free_symbols & vidx.keys()):
        return {(): [expr]}
    if expr.is_Symbol:
        return {(vidx[expr],): [sp.S.One]}
    if expr.is_Add:
        out: dict = {}
        for a in expr.args:
            for key, summands in _poly(a, vidx, max_degree).items():
                out.setdefault(key, []).extend(summands)
        return out
    if expr.is_Mul:
        cur = {(): [sp.S.One]}
        for a in expr.args:
            cur = _poly_mul(cur, _poly(a, vidx, max_degree), max_degree)
        return cur
    if expr.is_Pow and expr.exp.is_Integer and expr.exp > 0 and expr.exp <= max_degree:
        base = _poly(expr.base, vidx, max_degree)
        cur = base
        for _ in range(int(expr.exp) - 1):
            cur = _poly_mul(cur, base, max_degree)
        return cur
    raise _NotPolynomial


def _poly_mul(p1, p2, max_degree):
    out: dict = {}
    for k1, c1 in p1.items():
        for k2, c2 in p2.items():
            if len(k1) + len(k2) > max_degree:
                raise _NotPolynomial
            lst = out.setdefault(tuple(sorted(k1 + k2)), [])
            lst.extend(a * b for a in c1 for b in c2)
    return out


def quadratic_parts(lagrangian, velocities) -> QuadraticParts | None:
    """W, b, V of L = v^T W v / 2 + b . v - V(q), read from the terms of L.

    Returns None when L is not structurally of degree <= 2 in the velocities
    (see :func:`velocity_polynomial`); W, b and V are then undefined and the
    callers differentiate L instead.
    """
    poly = velocity_polynomial(lagrangian, velocities, 2)
    if poly is None:
        return None
    n = len(velocities)
    W = [[sp.S.Zero] * n for _ in range(n)]
    b = [sp.S.Zero] * n
    V = sp.S.Zero
    for key, c in poly.items():
        if len(key) == 2:
            A, C = key
            if A == C:
                W[A][A] = 2 * c
            else:
                W[A][C] = W[C][A] = c
        elif len(key) == 1:
            b[key[0]] = c
        else:
            V = -c
    return QuadraticParts(sp.ImmutableMatrix(W), tuple(b), V)


def velocity_free_part(expr, velocities) -> sp.Expr:
    """h = phi at v = 0: the velocity-free terms of phi read off in one pass when phi is
    affine in v (:func:`velocity_polynomial`, memoised), else by setting v = 0.
    Substituting 0 builds every subexpression anew: 1.2 s on the 64-link snake's
    constraints, against 0.25 s.

    Examples
    --------
    >>> import sympy as sp
    >>> q, qd, a = sp.symbols("q q_dot a")
    >>> velocity_free_part(sp.sin(q) * (a + qd) - 1, [qd])
    a*sin(q) - 1
    """
    poly = velocity_polynomial(expr, velocities, 1)
    if poly is None:
        return expr.xreplace({v: sp.S.Zero for v in velocities})
    return poly.get((), sp.S.Zero)


def one_forms(rows, vels) -> sp.Matrix:
    """mu_iA = d phi_i / d v^A, read from the terms of affine phi_i when possible."""
    out = []
    for f in rows:
        poly = velocity_polynomial(f, vels, 1)
        if poly is None:
            out.append([sp.diff(f, v) for v in vels])
        else:
            out.append([poly.get((A,), sp.S.Zero) for A in range(len(vels))])
    return sp.Matrix(out)


def non_affine_terms(expr, vels):
    """Terms of ``expr`` whose velocity derivatives still involve velocities."""
    poly = velocity_polynomial(expr, vels, 1)
    if poly is not None and not expr.has(sp.Derivative):
        return []  # a polynomial of degree <= 1 in v: no term can be offending
    vset = set(vels)
    bad = []
    for term in sp.Add.make_args(sp.expand(expr)):
        if not term.free_symbols & vset:
            continue
        for v in vels:
            d = sp.diff(term, v)
            if d.free_symbols & vset or d.has(sp.Derivative):
                bad.append(term)
                break
    return bad
