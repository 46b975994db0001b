"""Parameter conditions substituted into a system: branches, composition, rebuilding."""

from __future__ import annotations

import sympy as sp

from nhham.errors import BudgetExceeded, NhhamError
from nhham.system.description import System
from nhham.verdict.results import Verdict

__all__ = ["branches", "compose", "canonical", "rebuild"]


def branches(eqs, params, signs) -> list:
    """Substitutions {parameter: expression} solving ``eqs``, one per branch."""
    found: list[dict] = [{}]
    for e in eqs:
        nxt = []
        for sub in found:
            f = sp.expand(sp.sympify(e).xreplace(sub))
            if f == 0:
                nxt.append(sub)
                continue
            if f.is_number:
                continue
            for p, val in _solve_one(f, [p for p in params if p not in sub]):
                nxt.append(compose(sub, {p: val}))
        found = nxt
    return found


def _solve_one(f, params):
    """[(parameter, value)] solving f = 0: linear with constant coefficient first,
    then linear, then the real roots in the parameter of lowest degree."""
    present = [p for p in params if p in f.free_symbols]
    if not present:
        return []
    linear = []
    for p in present:
        poly = sp.Poly(f, p)
        if poly.degree() == 1:
            a, b = poly.all_coeffs()
            linear.append((bool(a.free_symbols), p, sp.factor(-b / a)))
    if linear:
        linear.sort(key=lambda t: t[0])
        _, p, val = linear[0]
        return [(p, val)]
    p = min(present, key=lambda s: sp.Poly(f, s).degree())
    roots = sp.solve(f, p)
    return [(p, r) for r in roots if r.is_real is not False]


def compose(sub, new) -> dict:
    out = {k: sp.simplify(sp.sympify(v).xreplace(new)) for k, v in sub.items()}
    out.update(new)
    return out


def canonical(sub) -> tuple:
    return tuple(sorted((p.name, sp.srepr(sp.simplify(v))) for p, v in sub.items()))


# ======================================================== systems and order
def rebuild(system, sub, values):
    """The system with ``sub`` substituted (a Verdict "invalid" when it is not valid).

    ``values`` gives the remaining parameters their values (None: all symbolic).
    """
    remaining = [p for p in system.declared_parameters if p not in sub]
    params = {p.name: (values.get(p) if values else None) for p in remaining}
    x = (lambda e: sp.sympify(e).xreplace(sub)) if sub else sp.sympify
    try:
        # the forces, substituted as L is (the inputs and t stay what they are)
        rebuilt = System(system.coordinates, x(system.lagrangian),
                      [x(c) for c in system.constraints], [x(g) for g in system.holonomic],
                      parameters=params, name=system.name, drop_redundant=True,
                      forces=[x(f) for f in system.forces], dissipation=x(system.dissipation),
                      inputs=[u for u in system.inputs if u not in sub])
        if rebuilt.regular_lagrangian:
            return rebuilt
        why = ("the Lagrangian is singular (det W = 0) there: classify a scene with these "
               "values for its Dirac-Bergmann chain")
    except BudgetExceeded:  # an expiry says nothing about the system's validity
        raise
    except NhhamError as exc:
        why = f"the system is not valid there: {exc}"
    return Verdict(status="invalid", regular=None, rank_C=None, stages=0, free_multipliers=0,
                   integrable=None, first_class=None, second_class=None, note=why)

