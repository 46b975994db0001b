"""Display forms of derived expressions: cheap, bounded and effective.

Derived expressions are correct but arrive as one large fraction in which
sin(u)^2 + cos(u)^2 is not reduced (``sin(theta)**3 + sin(theta)*cos(theta)**2``).
``trigsimp`` finds the identity but its cost grows without bound with the size
of the expression; here the work is done in sympy's sparse polynomial rings,
where every step is polynomial arithmetic on the terms:

1. the expression becomes one fraction num/den of polynomials in its
   generators (symbols, each sin(u) and cos(u), other functions as opaque
   generators), with the polynomial gcd cancelled, and for every angle u both
   are reduced modulo sin(u)^2 + cos(u)^2 - 1
   (:func:`nhham.lagrangian.algebra.ring_fraction`);
2. for reading, the numerator is grouped by its monomials in ``group`` (the
   velocities or momenta: the dynamics is polynomial in them), each group's
   coefficient with its common factor taken out (and factored when small), and
   the denominator is factored when small.

Every step is an identity of rational functions (the result equals the input
wherever both are defined); the form is kept only if it has fewer nodes.
Expressions with more than :data:`SIZE_LIMIT` nodes are returned as derived:
expanding them could cost more than the derivation did (``--json`` and
``--latex`` carry them whole; the text output elides them).
"""

from __future__ import annotations

import sympy as sp

from nhham.lagrangian.algebra import POLYNOMIAL_ERRORS, ring_fraction

__all__ = ["display_form", "SIZE_LIMIT"]

#: Expressions with more nodes than this are displayed as derived.
SIZE_LIMIT = 3000
# Polynomials with at most this many terms are factored for display.
_FACTOR_TERMS = 12


def display_form(expr, group=(), limit: int = SIZE_LIMIT):
    """A shorter, equal form of ``expr`` for display (see the module docstring).

    Parameters
    ----------
    expr : sympy.Expr or number
    group : sequence of sympy.Symbol
        Symbols whose monomials group the numerator's terms (e.g. velocities).
    limit : int
        Expressions with more nodes are returned as they are.

    Returns
    -------
    sympy.Expr
        Equal to ``expr`` as a rational function; ``expr`` itself when it is a
        number, too large (more than ``limit`` nodes), not a rational
        function of its generators, or when no shorter form was found.
    """
    expr = sp.sympify(expr)
    if expr.is_number or expr.is_Symbol or _nodes(expr, limit) > limit:
        return expr
    try:
        num, den = ring_fraction(expr)
        out = _presented(num, den, group)
    except POLYNOMIAL_ERRORS:  # not a rational function of its generators: show as derived
        return expr
    return out if _nodes(out, limit) < _nodes(expr, limit) else expr


def _nodes(expr, limit: int) -> int:
    """The number of nodes of ``expr``'s tree, counted up to ``limit + 1``."""
    count = 0
    for _ in sp.preorder_traversal(expr):
        count += 1
        if count > limit:
            break
    return count


# ------------------------------------------------------------- reading
def _presented(num, den, group):
    """num/den as an expression: terms grouped by their monomials in ``group``, then in
    the sines and cosines; small coefficients and the denominator factored."""
    if not num:
        return sp.S.Zero
    if den.ring.domain.is_negative(den.LC):
        num, den = -num, -den
    symbols = num.ring.symbols
    wanted = set(group)
    levels = [[i for i, g in enumerate(symbols) if g in wanted],
              [i for i, g in enumerate(symbols) if isinstance(g, (sp.sin, sp.cos))]]
    levels = [lv for lv in levels if lv]
    number, monomial, num = _common_factor(num)
    dnumber, denominator = _factored(den, levels)
    return sp.Mul(number / dnumber, monomial, _grouped(num, levels),
                  sp.Pow(denominator, -1))


def _grouped(poly, levels):
    """sum over the monomials x^k in the generators of ``levels[0]`` of x^k times its
    coefficient (itself grouped by the next level, factored at the last); the sign
    taken out when most terms are negative."""
    if not levels or len(poly) == 1:
        number, rest = _factored(poly)
        return sp.Mul(number, rest)
    ring, indices = poly.ring, levels[0]
    parts: dict = {}
    for mon, coeff in poly.terms():
        key = tuple(mon[i] for i in indices)
        rest = tuple(0 if i in indices else e for i, e in enumerate(mon))
        parts.setdefault(key, {})[rest] = coeff
    terms = []
    for key, rest in parts.items():
        monomial = sp.Mul(*[ring.symbols[i] ** e for i, e in zip(indices, key)])
        inner = ring.from_dict(rest)
        if len(levels) > 1 and len(inner) > 1:
            terms.append(monomial * _grouped(inner, levels[1:]))
        else:
            number, factors = _factored(inner)
            # one Mul of several factors: sympy does not spread -1 over a sum then
            terms.append(sp.Mul(number, monomial, factors))
    total = sp.Add(*terms)
    if total.is_Add and total.could_extract_minus_sign():
        return sp.Mul(-1, -total, evaluate=False)
    return total


def _factored(poly, levels=()):
    """(number, expression) with product ``poly``: factored when small (factors of
    several terms grouped by ``levels``), else the common monomial out."""
    if poly.is_ground:  # a number (sympy's factor_list fails in a ring without generators)
        return poly.ring.domain.to_sympy(poly.LC), sp.S.One
    if len(poly) <= _FACTOR_TERMS:
        try:
            # in a ring of the generators it has: the dense recursive factorisation
            # costs with every generator of the ring, present or not
            unused = [g for g, e in zip(poly.ring.gens, poly.degrees()) if not e]
            small = poly.drop(*unused) if unused and len(unused) < poly.ring.ngens else poly
            coeff, factors = small.factor_list()
            factors = [(f.set_ring(poly.ring), e) for f, e in factors]  # back, for levels
        except POLYNOMIAL_ERRORS:
            pass
        else:
            return (poly.ring.domain.to_sympy(coeff), sp.Mul(
                *[(_grouped(f, levels) if levels and len(f) > 2 else f.as_expr()) ** e
                  for f, e in factors]))
    number, monomial, rest = _common_factor(poly)
    return number, monomial * (_grouped(rest, levels) if levels else rest.as_expr())


def _common_factor(poly):
    """(content, gcd of the monomials, the rest): content * monomial * rest = poly."""
    content, primitive = poly.primitive()
    ring = poly.ring
    if ring.domain.is_negative(content):  # the sign is decided by the grouped terms
        content, primitive = -content, -primitive
    gcd_mon = tuple(min(m[i] for m in primitive.monoms()) for i in range(ring.ngens))
    if any(gcd_mon):
        primitive = ring.from_dict({tuple(a - b for a, b in zip(m, gcd_mon)): c
                                    for m, c in primitive.terms()})
    monomial = sp.Mul(*[g ** e for g, e in zip(ring.symbols, gcd_mon)])
    return ring.domain.to_sympy(content), monomial, primitive
