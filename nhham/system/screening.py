"""What a system's expressions may contain, checked before any geometry.

:class:`~nhham.system.System` screens its Lagrangian and constraints here, each
problem one line starting with the key path (``lagrangian``, ``constraints[1]``):

- plain symbols only: a ``sympy.physics.mechanics`` dynamicsymbol ``x(t)`` or its
  derivative is pointed to :func:`nhham.from_mechanics`, an unknown symbol to the
  ``parameters`` (the time ``t`` is known to :class:`~nhham.system.System` itself);
- real data (:func:`nhham.system.numbers.number_problems`): ``asin(2)`` or
  ``sympy.I`` would otherwise lose their imaginary part in the numbers;
- smooth functions of the state: ``Abs``, ``sign`` and other kinks or jumps of the
  coordinates or velocities have no derivative nhham can use;
- a bounded size: the expansion that the exact steps form must stay within
  :data:`MAX_EXPANDED_TERMS` terms, so that no input keeps them busy for hours and
  gigabytes (``(x + y + theta + phi + 1)**60`` expands to 635 376 terms).
"""

from __future__ import annotations

import math
import unicodedata

import sympy as sp
from sympy.core.function import AppliedUndef

from nhham.system.expressions import short, to_text
from nhham.system.naming import as_symbol
from nhham.system.numbers import number_problems

__all__ = ["MAX_EXPANDED_TERMS", "expanded_size", "coordinate_symbols", "expression_problems"]

#: Most terms an expression may have once expanded (an upper bound is estimated). The
#: largest bundled model, the Whipple bicycle, has about 700.
MAX_EXPANDED_TERMS = 10_000

# Functions with a kink or a jump: no derivative where their argument crosses 0.
_NOT_SMOOTH = (sp.Abs, sp.sign, sp.Heaviside, sp.DiracDelta, sp.floor, sp.ceiling, sp.frac,
               sp.Max, sp.Min)

_FROM_MECHANICS = ("System takes plain symbols: build it with nhham.from_mechanics(L, q, ...), "
                   "which reads dynamicsymbols")


def coordinate_symbols(coordinates, problems: list) -> tuple:
    """Plain symbols for the coordinates (names or Symbols); record what is not one."""
    coords = []
    for i, q in enumerate(coordinates):
        if isinstance(q, (AppliedUndef, sp.Derivative)):
            problems.append(f"coordinates[{i}]: {q} is a function of time (a "
                            f"sympy.physics.mechanics dynamicsymbol); {_FROM_MECHANICS}")
            continue
        try:
            sym = as_symbol(q)
        except TypeError as exc:
            problems.append(f"coordinates[{i}]: {exc}")
            continue
        if not unicodedata.is_normalized("NFKC", sym.name):
            problems.append(f"coordinates[{i}]: {sym.name!r} is not in Unicode normal form NFKC "
                            f"(write {unicodedata.normalize('NFKC', sym.name)!r}): an expression "
                            f"could not name it")
            continue
        coords.append(sym)
    return tuple(coords)


def expression_problems(label: str, expr: sp.Expr, state, known) -> list[str]:
    """Every reason ``expr`` (under key path ``label``) cannot be part of a System.

    Parameters
    ----------
    label : str
        Key path for the messages.
    expr : sympy.Expr
    state : iterable of sympy.Symbol
        Coordinates and velocities (where smoothness matters).
    known : set of sympy.Symbol
        Every symbol the expression may use (state and parameters).
    """
    functions = sorted({str(f) for f in expr.atoms(AppliedUndef)})
    if functions:
        return [f"{label}: contains {', '.join(functions[:3])}, a function of time (a "
                f"sympy.physics.mechanics dynamicsymbol); {_FROM_MECHANICS}"]
    problems = []
    unknown = sorted(s.name for s in expr.free_symbols - set(known))
    if unknown:
        problems.append(f"{label}: unknown symbol(s) {', '.join(unknown)} in {short(expr)}"
                        + _unknown_advice(unknown))
    problems += [f"{label}: {p}" for p in number_problems(expr)]
    state = set(state)
    kinks = sorted({to_text(f) for f in expr.atoms(*_NOT_SMOOTH) if f.free_symbols & state})
    if kinks:
        problems.append(f"{label}: {', '.join(kinks[:3])} is not smooth (a kink or jump where "
                        f"its argument crosses 0); L and the constraints must be smooth in the "
                        f"coordinates and velocities (and the time t): write the branch that "
                        f"holds (x for Abs(x) where x > 0)")
    size, part = expanded_size(expr)
    if size > MAX_EXPANDED_TERMS:
        problems.append(f"{label}: expands to about {size:.3g} terms (the largest part: "
                        f"{short(to_text(part), 60)}), more than the {MAX_EXPANDED_TERMS} that "
                        f"nhham's exact steps handle in bounded time and memory")
    return problems


def _unknown_advice(unknown) -> str:
    return "; declare parameters in parameters"


def expanded_size(expr) -> tuple[float, sp.Expr]:
    """An upper bound of the terms the full expansion of a part of ``expr`` has.

    Sums add, products multiply, and an integer power k of a sum of t terms has at
    most C(t + k - 1, k) (every monomial of degree k); function arguments and
    denominators are expanded on their own. Nothing is expanded.

    Returns
    -------
    size : float
        The largest bound over ``expr`` and its parts (function arguments, bases).
    part : sympy.Expr
        The product or power with the largest bound (where a blow-up comes from).

    >>> x, y = sp.symbols("x y")
    >>> expanded_size((x + y + 1)**3 * (x + 2) + 1)
    (21.0, (x + 2)*(x + y + 1)**3)
    """
    memo: dict = {}
    worst = [0.0, expr]  # the largest product or power
    largest = [0.0]

    def terms(e) -> float:
        hit = memo.get(e)
        if hit is not None:
            return hit
        if e.is_Add:
            t = sum(terms(a) for a in e.args)
        elif e.is_Mul:
            t = math.prod(terms(a) for a in e.args)
        elif e.is_Pow:
            base = terms(e.base)
            terms(e.exp)
            k = e.exp
            if k.is_Integer and base > 1:
                inner = _monomials(base, abs(int(k)))  # a denominator is expanded too
                if inner > worst[0]:
                    worst[:] = [inner, e]
                largest[0] = max(largest[0], inner)
                t = inner if k > 0 else 1.0
            else:
                t = 1.0
        else:
            for a in e.args:
                terms(a)
            t = 1.0
        if t > worst[0] and (e.is_Mul or e.is_Pow):
            worst[:] = [t, e]
        largest[0] = max(largest[0], t)
        memo[e] = t
        return t

    terms(sp.sympify(expr))
    return largest[0], worst[1]


def _monomials(t: float, k: int) -> float:
    """C(t + k - 1, k), the monomials of degree k in t variables (as a float, maybe inf)."""
    if math.isinf(t):
        return math.inf
    log = math.lgamma(t + k) - math.lgamma(k + 1) - math.lgamma(t)
    return float(round(math.exp(log))) if log < 700 else math.inf
