"""The components of an exceptional set: where the values of a datum vanish together.

A datum of :mod:`nhham.lagrangian.exceptional` is a list of values in Q(p), the
parameters symbolic; where its numerators vanish together is a union of components. Those
of codimension 1 are the irreducible factors of the numerators' gcd (a gcd and a
factorisation); the rest, where the numerators divided by it vanish together, has
codimension > 1 and is found by a lex Gröbner basis and a solve, which can take long:
:func:`split_components` gives it unsolved (:class:`LowerDimensional`), so that a search
within a budget can take the quick components first.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import reduce

import sympy as sp

from nhham.errors import BudgetExceeded
from nhham.progress import SLOW, part
from nhham.system.expressions import short

__all__ = ["Condition", "LowerDimensional", "exceptional_components", "split_components"]


@dataclass(frozen=True)
class Condition:
    """One component of an exceptional set: polynomial equations in the parameters.

    Attributes
    ----------
    equations : tuple of sympy.Expr
        Each = 0, factored, in the scene's parameter names.
    reasons : tuple of str
        Which generic decisions fail there.
    """

    equations: tuple
    reasons: tuple

    def describe(self) -> str:
        return ", ".join(f"{short(e)} = 0" for e in self.equations)



def exceptional_components(data, params) -> tuple:
    """Components of the union of the exceptional sets of every datum, deduplicated."""
    found: dict = {}
    for reason, values in data:
        for eqs in _components(values, params):
            key = tuple(sp.srepr(e) for e in eqs)
            found.setdefault(key, (eqs, []))[1].append(reason)
    return tuple(Condition(eqs, tuple(dict.fromkeys(reasons)))
                 for eqs, reasons in found.values())


def split_components(data, params) -> tuple:
    """The components of codimension 1 of every datum's exceptional set, and the rest of
    each, not yet solved.

    Parameters
    ----------
    data : list of (str, list)
        ``(reason, values)`` pairs (:meth:`ExceptionalData.symbolic`).
    params : tuple of sympy.Symbol

    Returns
    -------
    conditions : tuple of Condition
        The irreducible factors of the gcd of each datum's numerators, deduplicated
        (their reasons merged): found at the cost of a gcd and a factorisation.
    lower : tuple of LowerDimensional
        Where the numerators beyond that gcd vanish together (codimension > 1): a lex
        Gröbner basis and a solve each, which can take long
        (:meth:`LowerDimensional.solve`).

    Examples
    --------
    >>> import sympy as sp
    >>> K = sp.QQ.frac_field(*sp.symbols("a b"))
    >>> a, b = K.gens
    >>> found, lower = split_components([("C singular", [a * (b - 1), a * (b - 2)])],
    ...                                 sp.symbols("a b"))
    >>> [c.equations for c in found], [c.polynomials for c in lower]
    ([(a,)], [(b - 1, b - 2)])
    >>> lower[0].solve()       # b = 1 and b = 2 at once: nowhere
    ()
    """
    found: dict = {}
    lower: dict = {}
    for reason, values in data:
        with part(f"where {reason}: common factors", after=SLOW):
            codim_one, rest = _codimension_one(values, params)
        for eqs in codim_one:
            key = tuple(sp.srepr(e) for e in eqs)
            found.setdefault(key, (eqs, []))[1].append(reason)
        if rest:
            key = tuple(sp.srepr(e) for e in rest)
            lower.setdefault(key, (rest, []))[1].append(reason)
    return (tuple(Condition(eqs, tuple(dict.fromkeys(reasons)))
                  for eqs, reasons in found.values()),
            tuple(LowerDimensional(tuple(rest), tuple(params), tuple(dict.fromkeys(reasons)))
                  for rest, reasons in lower.values()))


@dataclass(frozen=True)
class LowerDimensional:
    """Where the values of one datum vanish together beyond their common factors: the
    components of codimension > 1 of its exceptional set, not yet solved.

    Attributes
    ----------
    polynomials : tuple of sympy.Expr
        The numerators divided by their gcd (no common factor left).
    parameters : tuple of sympy.Symbol
    reasons : tuple of str
        The data whose rest these are.
    """

    polynomials: tuple
    parameters: tuple
    reasons: tuple

    def describe(self) -> str:
        """Its size, for an estimate: "3 polynomials of degree <= 12, 840 terms, in 6
        parameters"."""
        polys = [sp.Poly(e, *self.parameters) for e in self.polynomials]
        return (f"{len(polys)} polynomial{'s' if len(polys) != 1 else ''} of degree <= "
                f"{max(p.total_degree() for p in polys)}, {sum(len(p.terms()) for p in polys)}"
                f" terms, in {len(self.parameters)} parameters")

    def solve(self) -> tuple:
        """The components (a lex Gröbner basis, then sympy's solve), as Conditions."""
        return tuple(Condition(eqs, self.reasons)
                     for eqs in _lower_dimensional(list(self.polynomials), self.parameters))


def _components(values, params) -> list:
    """Components of the common zero set of the numerators of ``values``."""
    out, rest = _codimension_one(values, params)
    return out + (_lower_dimensional(rest, params) if rest else [])


def _codimension_one(values, params) -> tuple:
    """(the irreducible factors of the gcd of the numerators of ``values``, each a
    component, the numerators divided by that gcd when they are not all constants)."""
    nums = [v.numer for v in values if v]
    if not nums or not params:
        return [], []
    g = reduce(lambda a, b: a.gcd(b), nums)
    out = []
    if not g.is_ground:
        _, factors = sp.factor_list(g.as_expr(), *params)
        for f, _ in factors:
            if f.free_symbols:
                out.append((_normal(f),))
    rest = [a.exquo(g) for a in nums]
    if all(r.is_ground for r in rest):
        return out, []
    return out, list(dict.fromkeys(r.as_expr() for r in rest))


def _lower_dimensional(exprs, params) -> list:
    """The components of the common zeros of ``exprs`` (polynomials without a common
    factor): a lex Gröbner basis, then its solutions (the basis itself when sympy cannot
    solve it)."""
    try:
        basis = sp.groebner(exprs, *params, order="lex")
    except BudgetExceeded:  # an expiry is not a sympy failure: it must reach the command
        raise
    except Exception:  # pragma: no cover - sympy failure
        return []
    if list(basis.exprs) == [1]:
        return []
    try:
        sols = sp.solve(list(basis.exprs), list(params), dict=True)
    except BudgetExceeded:
        raise
    except Exception:  # pragma: no cover - sympy cannot solve: carry the relations
        sols = None
    if not sols:
        return [tuple(_normal(e) for e in basis.exprs)]
    out = []
    for sol in sols:
        eqs = tuple(_normal(sp.numer(sp.together(p - v))) for p, v in sol.items())
        out.append(tuple(sorted(eqs, key=sp.default_sort_key)))
    return out


def _normal(expr):
    """A factored polynomial with a positive leading coefficient, content removed."""
    expr = sp.factor(sp.expand(expr))
    c, rest = expr.as_coeff_Mul()
    out = rest if c.is_number and c != 0 else expr
    syms = sorted(out.free_symbols, key=sp.default_sort_key)
    if syms:
        try:
            if sp.Poly(out, *syms).LC() < 0:
                out = sp.factor(-out)
        except sp.PolynomialError:  # pragma: no cover
            pass
    return out
