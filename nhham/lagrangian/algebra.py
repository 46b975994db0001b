"""Small symbolic algebra shared by the exact layers: one home for each helper.

- :func:`cancel`: one rational normal form (identically zero expressions
  become 0);
- :func:`tidy`: :func:`cancel`, then a normal form modulo sin^2 + cos^2 = 1
  when sines and cosines remain (kept only when shorter);
- :func:`solve_linear`: A^{-1} B for a small square A of functions, never
  an explicit symbolic inverse of anything large;
- :func:`block_inverse`: the inverse of a small block (closed forms for 1x1
  and antisymmetric 2x2);
- :func:`guard_closed_form`: the size guard in front of a symbolic solve with C.
"""

from __future__ import annotations

from typing import Callable

import sympy as sp

__all__ = ["cancel", "tidy", "tidy_light", "trig_normal", "solve_linear", "block_inverse",
           "guard_closed_form", "CLOSED_FORM_OPS"]

#: A symbolic solve with an m x m matrix (m >= 2) of more operations than this is refused
#: unless asked for: the car with a trailer (n = 4, C of 547 operations) takes 30 s, the
#: 3-D rolling disc (13,053) more than an hour; the rolling ball (82) 0.3 s.
CLOSED_FORM_OPS = 300

# Exceptions sympy's polynomial machinery raises on input it cannot treat as a
# polynomial in its generators.
POLYNOMIAL_ERRORS = (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError,
                     ValueError, ZeroDivisionError, sp.polys.polyerrors.CoercionFailed)


def cancel(expr) -> sp.Expr:
    """One fraction with the polynomial gcd cancelled (numbers pass through)."""
    expr = sp.sympify(expr)
    if expr.is_number:
        return expr
    try:
        # cancel() brings nested fractions over one denominator and cancels the
        # polynomial gcd; expanding first only costs time.
        return sp.cancel(expr)
    except (sp.PolynomialError, TypeError):  # pragma: no cover - exotic functions
        return sp.expand(expr)


def tidy(expr) -> sp.Expr:
    """Cancel, and where sines and cosines remain reduce modulo sin^2 + cos^2 = 1.

    cos^2(u) is rewritten as 1 - sin^2(u) in numerator and denominator (a normal
    form modulo the identity) and the result is cancelled again; it is kept only
    if it is shorter. Much cheaper than ``trigsimp`` on large expressions.
    """
    expr = cancel(expr)
    if not expr.has(sp.sin, sp.cos):
        return expr
    alt = trig_normal(expr)
    return alt if alt is not None and sp.count_ops(alt) < sp.count_ops(expr) else expr


def tidy_light(expr, limit: int = 150) -> sp.Expr:
    """:func:`tidy` for expressions of moderate size; larger ones are left as they are."""
    return tidy(expr) if sp.count_ops(expr) <= limit else expr


def trig_normal(expr) -> sp.Expr | None:
    """The normal form of :func:`tidy` modulo sin^2 + cos^2 = 1, or None if not polynomial."""
    rep, back, rels, gens = {}, {}, [], []
    for atom in expr.atoms(sp.sin, sp.cos):
        u = atom.args[0]
        if sp.sin(u) in rep:
            continue
        sn, cs = sp.Dummy("s"), sp.Dummy("c")
        rep[sp.sin(u)], rep[sp.cos(u)] = sn, cs
        back[sn], back[cs] = sp.sin(u), sp.cos(u)
        rels.append(cs**2 + sn**2 - 1)
        gens += [cs, sn]
    try:
        num, den = sp.fraction(sp.cancel(expr.xreplace(rep)))
        others = sorted((num.free_symbols | den.free_symbols) - set(gens),
                        key=sp.default_sort_key)
        order = gens + others
        parts = []
        for part in (num, den):
            if not part.free_symbols & set(gens):
                parts.append(part)
                continue
            parts.append(sp.reduced(sp.expand(part), rels, *order, order="lex")[1])
        return sp.cancel(parts[0] / parts[1]).xreplace(back)
    except POLYNOMIAL_ERRORS:
        return None


def solve_linear(A: sp.Matrix, B: sp.Matrix, *, iszero: Callable | None = None,
                 simplify: Callable | None = cancel) -> sp.Matrix:
    """A^{-1} B for a small square matrix A of functions.

    Diagonal A divides entrywise; up to 3 x 3 the adjugate over the
    determinant (one cancelled determinant, no nested fractions); larger
    systems by LU, with pivots accepted only where ``iszero`` says the entry
    is not zero (for functions on a submanifold M, pass "reduces to 0 on M":
    sympy's own test could pick an entry that vanishes on M).

    Parameters
    ----------
    A : sympy.Matrix, shape (k, k)
    B : sympy.Matrix, shape (k, r)
    iszero : callable, optional
        Zero test for LU pivots.
    simplify : callable or None
        Applied to every entry of the result (default :func:`cancel`).
    """
    if A.rows == 0:
        return sp.zeros(0, B.cols)
    if A.is_diagonal():
        out = sp.Matrix(B.rows, B.cols, lambda i, j: B[i, j] / A[i, i])
    elif A.rows <= 3:
        det = cancel(A.det(method="berkowitz"))
        out = (A.adjugate(method="berkowitz") * B).applyfunc(lambda e: cancel(e) / det)
    elif iszero is not None:
        out = A.LUsolve(B, iszerofunc=iszero)
    else:
        out = A.LUsolve(B)
    return out.applyfunc(simplify) if simplify is not None else out


def block_inverse(B: sp.Matrix) -> sp.Matrix:
    """Inverse of a small block: closed forms for 1x1 and antisymmetric 2x2."""
    if B.rows == 1:
        return sp.Matrix([[1 / B[0, 0]]])
    if B.rows == 2 and B[0, 0] == 0 and B[1, 1] == 0 and sp.expand(B[0, 1] + B[1, 0]) == 0:
        b = B[0, 1]
        return sp.Matrix([[0, -1 / b], [1 / b, 0]])
    return B.inv(method="LU").applyfunc(cancel)


def guard_closed_form(C: sp.Matrix, what: str, owner: str) -> None:
    """Raise :class:`~nhham.errors.ClosedFormTooLarge` before a symbolic solve with ``C``
    that would not finish in reasonable time (m >= 2 and more than CLOSED_FORM_OPS
    operations in C).

    Parameters
    ----------
    C : sympy.Matrix, shape (m, m)
    what : str
        The closed form asked for (``"multipliers"``).
    owner : str
        How the user built the object (``"lagrangian_geometry"``), for the advice.
    """
    from nhham.errors import ClosedFormTooLarge

    if C.rows < 2:
        return
    ops = sum(sp.count_ops(e) for e in C)
    if ops <= CLOSED_FORM_OPS:
        return
    raise ClosedFormTooLarge(
        f"{owner}(...).{what}: the closed form needs a symbolic solve with C ({C.rows} x "
        f"{C.cols}, {ops} operations, more than the {CLOSED_FORM_OPS} it is formed for by "
        f"default), which may run for hours. Use the implicit form instead "
        f"(W a + mu^T lambda = F, mu a = -(dphi/dq) v: .equations_of_motion, "
        f"`nhham derive`), numbers (nhham.simulate), or ask for it with "
        f"{owner}(system, closed_form=True), bounded by `with nhham.time_budget(seconds):`")
