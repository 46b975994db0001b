"""Bridges to :mod:`sympy.physics.mechanics`.

:func:`from_mechanics` and :func:`from_lagranges_method` turn a Lagrangian
and constraints written in dynamicsymbols q(t), q(t).diff(t) into an
:class:`nhham.System`; :func:`to_lagranges_method` goes the other way, so
that tests and benchmarks can run ``LagrangesMethod`` on exactly the system
nhham sees.

Names: the dynamicsymbol ``q1(t)`` becomes the coordinate ``q1`` and its
derivative the velocity ``q1_dot``.

Multipliers: ``LagrangesMethod.eom`` is d/dt(dL/dq') - dL/dq - lam_coeffs^T lam
with lam_coeffs = -d(coneqs)/dq', i.e. d/dt(dL/dv) - dL/dq + mu^T lam = 0,
nhham's convention (``DESIGN.md`` §2); its constraint order (time
derivatives of the holonomic constraints first, then the nonholonomic ones)
is nhham's order of :attr:`System.phi`. So ``lam<i>(t)`` in ``lm.eom``
corresponds to ``lambda_<i>``. Beware: sympy 1.14's ``mass_matrix`` appends
``lam_coeffs.T`` itself, so the multipliers solved from
``mass_matrix_full``/``rhs()`` are the negatives of those in ``lm.eom``.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping, NamedTuple, Sequence

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics import mechanics as me

from nhham.errors import InputError, ValidationError
from nhham.system.expressions import short
from nhham.system.naming import acceleration_symbol, multiplier_symbol, velocity_symbol
from nhham.system.description import System

__all__ = [
    "from_mechanics",
    "from_lagranges_method",
    "to_lagranges_method",
    "MechanicsForm",
    "Substitutions",
]

# Longest expression quoted in an error message.
_QUOTE = 80


@dataclass(frozen=True)
class Substitutions:
    """Maps between nhham's plain symbols and dynamicsymbols.

    Attributes
    ----------
    to_mechanics : mapping
        ``q -> q(t)``, ``q_dot -> q(t).diff(t)`` for every coordinate.
    from_mechanics : mapping
        ``q(t) -> q``, ``q'(t) -> q_dot``, ``q''(t) -> q_ddot`` and the
        multipliers ``lam<i>(t) -> lambda_<i>``. Use with ``xreplace`` (not
        ``subs``: a derivative must be replaced as a whole).
    """

    to_mechanics: Mapping[sp.Symbol, sp.Expr]
    from_mechanics: Mapping[sp.Expr, sp.Symbol]


class MechanicsForm(NamedTuple):
    """What :func:`to_lagranges_method` returns (unpacks as a 3-tuple)."""

    lm: me.LagrangesMethod
    q: tuple
    maps: Substitutions


# ------------------------------------------------------------------- into
def from_mechanics(lagrangian, q: Sequence, hol_coneqs: Sequence = (),
                   nonhol_coneqs: Sequence = (), parameters=None, name: str = "") -> System:
    """Build a :class:`System` from a ``sympy.physics.mechanics`` description.

    Parameters
    ----------
    lagrangian : sympy.Expr
        L in the dynamicsymbols ``q`` and their first time derivatives.
    q : sequence of dynamicsymbols
        Generalized coordinates, each an undefined function of time
        (``dynamicsymbols('x')``); ``x(t)`` becomes coordinate ``x`` with
        velocity ``x_dot``.
    hol_coneqs : sequence of sympy.Expr, optional
        Holonomic constraints g(q(t)) = 0 (as for ``LagrangesMethod``).
    nonhol_coneqs : sequence of sympy.Expr, optional
        Constraints affine in q'(t) (each = 0). ``Eq`` objects are read as
        lhs - rhs.
    parameters : mapping or sequence, optional
        Passed to :class:`System`. Default: every remaining free symbol
        except time, sorted by name, without values.
    name : str, optional

    Returns
    -------
    System

    Raises
    ------
    ValidationError
        (an :class:`InputError`) naming each term nhham cannot express:
        explicit time dependence, accelerations, functions of time that are
        not coordinates, plain symbols named like a coordinate or velocity;
        then whatever :class:`System` finds (non-affine constraints...).
    """
    coords = _coordinate_functions(q)
    t = me.dynamicsymbols._t
    to_plain = _plain_map(coords, t)
    reserved = {s.name for s in to_plain.values()}
    items = [("lagrangian", lagrangian)]
    items += [(f"hol_coneqs[{i}]", g) for i, g in enumerate(hol_coneqs)]
    items += [(f"nonhol_coneqs[{i}]", c) for i, c in enumerate(nonhol_coneqs)]
    problems, converted = [], {}
    for label, expr in items:
        converted[label] = _convert(label, _as_expr(label, expr), to_plain, reserved, t, problems)
    if problems:
        raise ValidationError(problems)
    if parameters is None:
        parameters = _remaining_symbols(converted.values(), reserved)
    return System(
        [to_plain[f] for f in coords],
        converted["lagrangian"],
        constraints=[converted[f"nonhol_coneqs[{i}]"] for i in range(len(nonhol_coneqs))],
        holonomic=[converted[f"hol_coneqs[{i}]"] for i in range(len(hol_coneqs))],
        parameters=parameters,
        name=name,
    )


def from_lagranges_method(lm: me.LagrangesMethod, parameters=None, name: str = "") -> System:
    """Build a :class:`System` from a ``LagrangesMethod`` object.

    Uses the Lagrangian ``lm._L``, the coordinates ``lm.q`` and the
    constraints the object was built with: ``lm._hol_coneqs`` (holonomic)
    and the rest of ``lm.coneqs`` (whose first entries are the time
    derivatives of the holonomic ones; sympy 1.14 stores no other copy of
    ``nonhol_coneqs``).

    Parameters
    ----------
    lm : sympy.physics.mechanics.LagrangesMethod
    parameters : mapping or sequence, optional
        As for :func:`from_mechanics`.
    name : str, optional

    Raises
    ------
    InputError
        If ``lm`` carries applied forces (nhham has no force terms) or is
        not a ``LagrangesMethod``; otherwise as :func:`from_mechanics`.
    """
    if not isinstance(lm, me.LagrangesMethod):
        raise InputError(f"from_lagranges_method: expected a LagrangesMethod, got "
                         f"{type(lm).__name__}")
    if lm.forcelist:
        raise InputError("from_lagranges_method: the LagrangesMethod has a forcelist; nhham "
                         "takes conservative forces through the Lagrangian only (write them "
                         "as a potential)")
    hol = list(lm._hol_coneqs)
    nonhol = list(lm.coneqs)[len(hol):]
    return from_mechanics(lm._L[0], list(lm.q), hol, nonhol, parameters=parameters, name=name)


def _coordinate_functions(q):
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


def _plain_map(coords, t):
    """q(t) -> q and q'(t) -> q_dot (coordinates first, then velocities)."""
    plain = {}
    for f in coords:
        plain[f] = sp.Symbol(f.func.__name__)
    for f in coords:
        plain[f.diff(t)] = velocity_symbol(plain[f])
    return plain


def _as_expr(label, expr):
    if isinstance(expr, sp.Equality):
        return expr.lhs - expr.rhs
    if isinstance(expr, sp.MatrixBase) and expr.shape == (1, 1):
        return expr[0, 0]
    try:
        return sp.sympify(expr, strict=True)
    except (sp.SympifyError, TypeError):
        raise InputError(f"{label}: expected a sympy expression, got "
                         f"{type(expr).__name__} {expr!r}") from None


def _convert(label, expr, to_plain, reserved, t, problems):
    """Replace dynamicsymbols by plain symbols; record what cannot be expressed."""
    clash = sorted(s.name for s in expr.free_symbols if s != t and s.name in reserved)
    if clash:
        problems.append(f"{label}: plain symbol(s) {', '.join(clash)} have the name of a "
                        f"coordinate or velocity; rename them")
    for term in sp.Add.make_args(expr):
        reason = _inexpressible(term, to_plain, t)
        if reason:
            problems.append(f"{label}: the term {short(term, _QUOTE)} {reason}")
    # xreplace replaces a Derivative node before looking inside it, so
    # q'(t) becomes q_dot rather than d(q)/dt.
    return expr.xreplace(to_plain)


def _inexpressible(term, to_plain, t):
    """Why a term cannot be part of an autonomous system on TQ, or ''."""
    derivs = [d for d in term.atoms(sp.Derivative) if d not in to_plain]
    if derivs:
        return (f"contains {short(derivs[0], _QUOTE)}: only coordinates and their first "
                f"derivatives may appear")
    funcs = [f for f in term.xreplace(to_plain).atoms(AppliedUndef)]
    if funcs:
        return (f"contains {short(funcs[0], _QUOTE)}, a function of time that is not one of the "
                f"coordinates q")
    if t in term.xreplace(to_plain).free_symbols:
        return f"depends explicitly on time {t}; nhham handles autonomous systems only"
    return ""


def _remaining_symbols(exprs, reserved):
    names = sorted({s.name for e in exprs for s in e.free_symbols} - reserved)
    return names


# ------------------------------------------------------------------- out of
def to_lagranges_method(system: System) -> MechanicsForm:
    """The same system as a ``sympy.physics.mechanics.LagrangesMethod``.

    Holonomic constraints go in as ``hol_coneqs`` (LagrangesMethod
    differentiates them itself), affine constraints as ``nonhol_coneqs``.
    Parameters stay symbols; substitute ``system.parameter_values`` for
    numbers. ``form_lagranges_equations`` is not called.

    Parameters
    ----------
    system : System

    Returns
    -------
    MechanicsForm
        ``(lm, q, maps)``: the LagrangesMethod, the coordinate dynamicsymbols
        (in ``system.coordinates`` order) and the :class:`Substitutions`.
    """
    t = me.dynamicsymbols._t
    # Function(name)(t) equals dynamicsymbols(name) but does not run the
    # name through symbols()' range and comma syntax.
    qs = tuple(sp.Function(q.name)(t) for q in system.coordinates)
    to_mech = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        to_mech[q] = f
        to_mech[v] = f.diff(t)
    back = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        back[f] = q
        back[f.diff(t)] = v
        back[f.diff(t, 2)] = acceleration_symbol(q)
    for i in range(1, system.m + 1):
        back[sp.Function(f"lam{i}")(t)] = multiplier_symbol(i)
    lm = me.LagrangesMethod(
        system.lagrangian.xreplace(to_mech), list(qs),
        hol_coneqs=[g.xreplace(to_mech) for g in system.holonomic] or None,
        nonhol_coneqs=[c.xreplace(to_mech) for c in system.constraints] or None,
    )
    maps = Substitutions(MappingProxyType(to_mech), MappingProxyType(back))
    return MechanicsForm(lm, qs, maps)
