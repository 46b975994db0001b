"""From dynamicsymbols to nhham's plain symbols, for :mod:`nhham.system.mechanics`.

A coordinate ``q1(t)`` becomes the symbol ``q1`` and its derivative ``q1_dot``
(:func:`plain_map`); generalized speeds u are replaced by the q' they stand for through
the kinematic differential equations (:func:`speed_substitution`); sympy's time is
nhham's ``t`` (``System.time``); a term that cannot be part of a system on TQ (a second
derivative, an unknown function of time) is named in a problem (:func:`convert`). Every check appends to
the caller's list of problems, so that the user sees them all at once.
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics import mechanics as me

from nhham.errors import InputError, ValidationError
from nhham.system.expressions import short
from nhham.system.naming import velocity_symbol

__all__ = ["QUOTE", "speed_substitution", "check_affine", "coordinate_functions",
           "plain_map", "as_expr", "convert", "inexpressible", "remaining_symbols"]

#: Longest expression quoted in an error message.
QUOTE = 80


def speed_substitution(coords, u, kd_eqs, t, problems, kd="kd_eqs") -> dict:
    """{u_k: expression in q, q'} from the kinematic differential equations (``kd``: their
    name in messages)."""
    if not kd_eqs:
        if u:
            problems.append(f"{kd}: speeds u were given but no kinematic differential "
                            f"equations define them")
        return {}
    qset = set(coords) | {f.diff(t) for f in coords}
    eqs = [as_expr(f"{kd}[{i}]", e) for i, e in enumerate(kd_eqs)]
    if u is None:
        found = set()
        for e in eqs:
            found |= {f for f in e.atoms(AppliedUndef) if f.args == (t,) and f not in qset}
        u = sorted(found, key=lambda f: f.func.__name__)
    u = list(u)
    bad = [f for f in u if not (isinstance(f, AppliedUndef) and f.args == (t,))]
    for f in bad:
        problems.append(f"u: {f} is not a dynamicsymbol")
    if bad:
        return {}
    if len(eqs) != len(u):
        problems.append(f"{kd}: {len(eqs)} kinematic differential equations for {len(u)} "
                        f"speeds {', '.join(map(str, u))}; one per speed is needed")
        return {}
    for i, e in enumerate(eqs):
        check_affine(f"{kd}[{i}]", e, tuple(u), problems)
    if problems:
        return {}
    B = sp.Matrix([[sp.diff(e, s) for s in u] for e in eqs])
    rest = sp.Matrix([e.xreplace({s: 0 for s in u}) for e in eqs])
    try:
        sol = B.LUsolve(-rest)
    except (ValueError, ZeroDivisionError, sp.matrices.exceptions.NonInvertibleMatrixError):
        problems.append(f"{kd}: cannot be solved for the speeds {', '.join(map(str, u))} "
                        f"(the coefficient matrix of u is singular)")
        return {}
    return {s: sp.simplify(x) if B != -sp.eye(len(u)) else sp.expand(x) for s, x in zip(u, sol)}


def check_affine(label, expr, speeds, problems) -> None:
    """Record the terms of ``expr`` that are not affine in the speeds."""
    if not speeds:
        return
    sset = set(speeds)
    for term in sp.Add.make_args(sp.expand(expr)):
        for s in speeds:
            d = sp.diff(term, s)
            if d.atoms(AppliedUndef) & sset:
                problems.append(f"{label}: the term {short(term, QUOTE)} is not affine in the "
                                f"speeds ({s} appears nonlinearly); nhham needs constraints "
                                f"affine in u")
                return


def coordinate_functions(q):
    """Check that every coordinate is a distinct function of time alone."""
    t = me.dynamicsymbols._t
    coords, problems = [], []
    for i, f in enumerate(q):
        if not (isinstance(f, AppliedUndef) and f.args == (t,)):
            problems.append(f"q[{i}]: {f} is not a dynamicsymbol (an undefined function of "
                            f"{t} alone, e.g. dynamicsymbols('x'))")
        else:
            coords.append(f)
    names = [f.func.__name__ for f in coords]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        problems.append(f"q: duplicate coordinate names {', '.join(dupes)}")
    if problems:
        raise ValidationError(problems)
    return coords


def plain_map(coords, t):
    """q(t) -> q and q'(t) -> q_dot (coordinates first, then velocities)."""
    plain = {}
    for f in coords:
        plain[f] = sp.Symbol(f.func.__name__)
    for f in coords:
        plain[f.diff(t)] = velocity_symbol(plain[f])
    return plain


def as_expr(label, expr):
    if isinstance(expr, sp.Equality):
        return expr.lhs - expr.rhs
    if isinstance(expr, sp.MatrixBase) and expr.shape == (1, 1):
        return expr[0, 0]
    try:
        return sp.sympify(expr, strict=True)
    except (sp.SympifyError, TypeError):
        raise InputError(f"{label}: expected a sympy expression, got "
                         f"{type(expr).__name__} {expr!r}") from None


def convert(label, expr, to_plain, reserved, t, problems):
    """Replace dynamicsymbols by plain symbols; record what cannot be expressed."""
    clash = sorted(s.name for s in expr.free_symbols if s != t and s.name in reserved)
    if clash:
        problems.append(f"{label}: plain symbol(s) {', '.join(clash)} have the name of a "
                        f"coordinate or velocity; rename them")
    for term in sp.Add.make_args(expr):
        reason = inexpressible(term, to_plain, t)
        if reason:
            problems.append(f"{label}: the term {short(term, QUOTE)} {reason}")
    # xreplace replaces a Derivative node before looking inside it, so
    # q'(t) becomes q_dot rather than d(q)/dt.
    return expr.xreplace(to_plain)


def inexpressible(term, to_plain, t):
    """Why a term cannot be part of a system on TQ (an explicit t is the time), or ''."""
    derivs = [d for d in term.atoms(sp.Derivative) if d not in to_plain]
    if derivs:
        return (f"contains {short(derivs[0], QUOTE)}: only coordinates and their first "
                f"derivatives may appear")
    funcs = [f for f in term.xreplace(to_plain).atoms(AppliedUndef)]
    if funcs:
        return (f"contains {short(funcs[0], QUOTE)}, a function of time that is not one of the "
                f"coordinates q")
    return ""  # an explicit t is the time (System.time)


def remaining_symbols(exprs, reserved):
    names = sorted({s.name for e in exprs for s in e.free_symbols} - reserved)
    return names

