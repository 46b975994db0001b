"""Small symbolic algebra shared by the exact layers: one home for each helper.

- :func:`cancel`: one rational normal form (identically zero expressions
  become 0);
- :func:`tidy`: :func:`cancel`, then a normal form modulo sin^2 + cos^2 = 1
  when sines and cosines remain (kept only when shorter);
- :func:`determinant`: Berkowitz's, for the callers that cancel it;
- :func:`solve_linear`: A^{-1} B for a small square A of functions, never
  an explicit symbolic inverse of anything large;
- :func:`block_inverse`: the inverse of a small block (closed forms for 1x1
  and antisymmetric 2x2);
- :func:`guard_closed_form`: the size guard in front of a symbolic solve with C.
- :func:`ring_fraction`, :func:`normal_form`: one fraction of sparse
  polynomials, cancelled and reduced modulo sin^2 + cos^2 = 1, by polynomial
  arithmetic on the terms (far cheaper than :func:`cancel` on large sums).
"""

from __future__ import annotations

import math
from typing import Callable

import sympy as sp
from sympy.matrices.utilities import dotprodsimp
from sympy.polys.rings import sring

from nhham.errors import InputError
from nhham.system.expressions import short

__all__ = ["cancel", "determinant", "tidy", "tidy_light", "trig_normal", "solve_linear",
           "block_inverse", "guard_closed_form", "CLOSED_FORM_OPS", "ring_fraction",
           "normal_form", "trig_reduce", "solve_for_coordinates", "defined_where"]

#: A symbolic solve with an m x m matrix (m >= 2) of more operations than this is refused
#: unless asked for: the car with a trailer (n = 4, C of 547 operations) takes 30 s, the
#: 3-D rolling disc (13,053) more than an hour; the rolling ball (82) 0.3 s.
CLOSED_FORM_OPS = 300

# Exceptions sympy's polynomial machinery raises on input it cannot treat as a
# polynomial in its generators (all of its own rooted at BasePolynomialError: a division
# with float coefficients, 1.0*x - 0.048..., fails with PolynomialDivisionFailed).
POLYNOMIAL_ERRORS = (sp.polys.polyerrors.BasePolynomialError, TypeError, ValueError,
                     ZeroDivisionError, NotImplementedError)


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


def determinant(A: sp.Matrix) -> sp.Expr:
    """det A by Berkowitz's algorithm, without sympy's simplification of every product
    on the way (``dotprodsimp``: half the time of the snakeboard's full-rank proofs at
    its values). The caller brings the result to a normal form (:func:`cancel`), which is
    the same whatever the route.

    Examples
    --------
    >>> import sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> cancel(determinant(sp.Matrix([[a, b], [b / a, 1]])))
    (a**2 - b**2)/a
    """
    with dotprodsimp(False):
        return A.det(method="berkowitz")


def tidy(expr) -> sp.Expr:
    """Cancel, and where sines and cosines remain reduce modulo sin^2 + cos^2 = 1.

    Two reductions are tried, each polynomial arithmetic on the terms (much cheaper than
    ``trigsimp`` on large expressions): cos^2(u) -> 1 - sin^2(u) everywhere
    (:func:`trig_normal`), and per angle whichever of cos^2 -> 1 - sin^2 and
    sin^2 -> 1 - cos^2 leaves fewer terms (:func:`normal_form`: (sin^2 + cos^2)/cos^2 is
    1/cos^2); the shortest of the three forms is kept.
    """
    expr = cancel(expr)
    if not expr.has(sp.sin, sp.cos):
        return expr
    forms = [expr, normal_form(expr)]
    alt = trig_normal(expr)
    if alt is not None:
        forms.append(alt)
    return min(forms, key=sp.count_ops)


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


def ring_fraction(expr):
    """``expr`` as num/den of sparse polynomials, cancelled and reduced modulo
    sin(u)^2 + cos(u)^2 - 1.

    The expression is brought over one denominator (``together``), numerator
    and denominator become polynomials in its generators (the symbols, each
    sin(u) and cos(u), any other function as an opaque generator); for every
    angle u with both sin(u) and cos(u) among them both are rewritten with
    cos(u)^2 -> 1 - sin(u)^2 or sin(u)^2 -> 1 - cos(u)^2, whichever leaves
    fewer terms, and then the gcd is cancelled. Every step is polynomial
    arithmetic on the terms: no expression-tree rewriting.

    Returns
    -------
    (PolyElement, PolyElement)
        Numerator and denominator in one ring (``num.ring.symbols`` are the
        generators).

    Raises
    ------
    One of POLYNOMIAL_ERRORS
        When ``expr`` is not a rational function of its generators.
    """
    expr = sp.sympify(expr)
    # ``together`` only where there is a denominator: it costs as much as the rest
    fractional = any(isinstance(a, sp.Pow) and a.exp.is_negative and not a.base.is_number
                     for a in sp.preorder_traversal(expr))
    num, den = sp.fraction(sp.together(expr)) if fractional else (expr, sp.S.One)
    ring, (num, den) = sring([num, den])
    # Reduced before the gcd: the gcd of the unreduced polynomials can cost minutes.
    for i_sin, i_cos in _trig_pairs(ring.symbols):
        options = [(_replace_square(num, i_cos, i_sin), _replace_square(den, i_cos, i_sin)),
                   (_replace_square(num, i_sin, i_cos), _replace_square(den, i_sin, i_cos))]
        num, den = min(options, key=lambda nd: len(nd[0]) + len(nd[1]))
    return num.cancel(den)


def normal_form(expr) -> sp.Expr:
    """:func:`ring_fraction` as one expression (``expr`` itself if it is not rational)."""
    expr = sp.sympify(expr)
    if expr.is_number:
        return expr
    try:
        num, den = ring_fraction(expr)
    except POLYNOMIAL_ERRORS:
        return expr
    return num.as_expr() / den.as_expr()


def trig_reduce(poly):
    """A sparse polynomial reduced modulo sin(u)^2 + cos(u)^2 - 1 for every angle u among
    its ring's generators (cos(u)^2 -> 1 - sin(u)^2: a normal form, the same every time)."""
    for i_sin, i_cos in _trig_pairs(poly.ring.symbols):
        poly = _replace_square(poly, i_cos, i_sin)
    return poly


def _trig_pairs(symbols) -> list:
    """Index pairs (i_sin, i_cos) of generators sin(u), cos(u) with the same u."""
    where = {(type(g), g.args[0]): i for i, g in enumerate(symbols)
             if isinstance(g, (sp.sin, sp.cos))}
    return [(i, where[(sp.cos, u)]) for (kind, u), i in where.items()
            if kind is sp.sin and (sp.cos, u) in where]


def _replace_square(poly, hi: int, lo: int):
    """``poly`` with gen[hi]^2 replaced by 1 - gen[lo]^2 (every power of gen[hi] below 2)."""
    terms: dict = {}
    for mon, coeff in poly.terms():
        k = mon[hi]
        if k < 2:
            terms[mon] = terms.get(mon, 0) + coeff
            continue
        half = k // 2
        for j in range(half + 1):
            new = list(mon)
            new[hi] = k % 2
            new[lo] += 2 * j
            key = tuple(new)
            terms[key] = terms.get(key, 0) + coeff * ((-1) ** j * math.comb(half, j))
    return poly.ring.from_dict({m: c for m, c in terms.items() if c})


def solve_for_coordinates(coordinates, equations, skip=frozenset()) -> tuple[dict, list]:
    """Coordinates solved exactly from the equations linear in them with a constant
    coefficient: the one coordinate elimination of the exact layers.

    Repeatedly, the first equation (in order) that is linear with a constant nonzero
    coefficient in a coordinate not yet solved (the first such coordinate) is solved for
    it, and the value substituted into those solved before; an equation that reduces to 0
    is dropped. Equations that involve a symbol of ``skip`` (velocities) are left alone.

    Parameters
    ----------
    coordinates : sequence of sympy.Symbol
    equations : sequence of sympy.Expr
        Each meaning ``= 0``.
    skip : set of sympy.Symbol, optional

    Returns
    -------
    substitution : dict
        Coordinate -> expanded expression in the others.
    unsolved : list of sympy.Expr
        The equations not used, as given (not substituted), in order.
    """
    sub: dict = {}
    pending = [sp.sympify(e) for e in equations]
    progress = True
    while progress:
        progress = False
        for eq in list(pending):
            e = sp.expand(eq.xreplace(sub)) if sub else sp.expand(eq)
            if e == 0:
                pending.remove(eq)
                progress = True
                continue
            if e.free_symbols & skip:
                continue
            for q in coordinates:
                if q in sub or q not in e.free_symbols:
                    continue
                coeff = e.coeff(q, 1)
                rest = sp.expand(e - coeff * q)
                if coeff.free_symbols or coeff == 0 or rest.has(q):
                    continue
                value = sp.expand(-rest / coeff)
                sub = {k: sp.expand(v.xreplace({q: value})) for k, v in sub.items()}
                sub[q] = value
                pending.remove(eq)
                progress = True
                break
            if progress:
                break
    return sub, pending


def defined_where(expr, value, substitution):
    """``value``, ``expr`` reduced by ``substitution`` (:func:`solve_for_coordinates`),
    unless it is undefined there (sympy's nan or zoo: 1/x, atan2(0, 0) where x = 0 is
    substituted): then the InputError saying so. No sample point could give it a value
    either (every one is NaN: an SVD that does not converge).

    >>> x, y = sp.symbols("x y")
    >>> defined_where(y / (1 + x), y, {x: 0})
    y
    """
    if not value.has(sp.nan, sp.zoo):
        return value
    solved = ", ".join(f"{k} = {short(v, 40)}" for k, v in substitution.items()
                       if k in expr.free_symbols)
    raise InputError(f"{short(expr, 80)} is not defined on the constraint set, where "
                     f"{solved} (it becomes {short(value, 40)}): the Lagrangian's W or a "
                     f"constraint is singular there; nhham needs them defined on M_1")
