"""A scene's ``[initial]`` table as the user gives it, completed from the constraints.

The user gives the independent values (numbers, or expressions in the parameters such as
``"v0/R"``) and leaves the dependent ones out:

- a velocity left out is solved from the velocity-level constraints (the affine ones and
  the time derivatives of the holonomic ones), which are linear in the velocities: exactly,
  by a least-squares solve that must leave no residual; a velocity that enters a
  nonlinear (Chetaev) constraint nonlinearly needs its value or a starting point
  ``y_dot = { guess = 1.0 }`` (the roots are branches: Newton's method from the guess
  picks one);
- a coordinate left out is solved from the holonomic constraints by Newton's method, from
  0 or from the value written ``z = { guess = 0.9 }`` (a curved M_1 has several branches:
  the guess picks one).

Nothing given is changed. A velocity left out that the constraints do not fix, or given
values that over-determine the ones left out inconsistently (the given ones are then not
independent), are refused with the names at fault.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping

import numpy as np
import sympy as sp

from nhham.errors import (
    InconsistentInitialDataError,
    InputError,
    MissingParameterValueError,
    ParseError,
)
from nhham.system.derivative import derivative
from nhham.system.expressions import parse_expression
from nhham.system.scene_numbers import finite_number

if TYPE_CHECKING:
    from nhham.system.description import System

__all__ = ["InitialData", "initial_entry", "parse_initial", "complete_initial",
           "solved_text"]

# Relative tolerance of the solves (residuals and rank), as the residual check's.
_TOL = 1e-9
_NEWTON_STEPS = 100


@dataclass(frozen=True)
class InitialData:
    """``[initial]`` as given.

    Attributes
    ----------
    given : mapping of str to sympy.Expr
        The values given, by state name (numbers, or expressions in the parameters).
    guesses : mapping of str to float
        Starting points of Newton's method for coordinates and velocities left out.
    """

    given: Mapping = field(default_factory=dict)
    guesses: Mapping = field(default_factory=dict)


def initial_entry():
    """The entry check of ``[initial]`` for :func:`nhham.system.steady.state_table`: a
    finite number, an expression (a string, parsed later) or ``{ guess = number }`` (a
    coordinate or a velocity left out, solved by Newton's method from it; the table's
    names are checked by ``state_table``)."""
    def entry(item, where, problems):
        if isinstance(item, str):
            return item
        if isinstance(item, dict):
            if set(item) != {"guess"}:
                problems.append(f"{where}: expected a number, an expression or "
                                f"{{ guess = number }}, got a table with "
                                f"{', '.join(map(repr, item)) or 'no keys'}")
                return None
            value = finite_number(item["guess"], f"{where}.guess", problems)
            return None if value is None else ("guess", value)
        return finite_number(item, where, problems)

    return entry


def parse_initial(table, parameters, problems) -> InitialData | None:
    """The checked raw table as :class:`InitialData` (expressions parsed against the
    parameter names; each failure appended to ``problems``)."""
    if table is None:
        return None
    symbols = {p: sp.Symbol(p) for p in parameters}
    given, guesses = {}, {}
    for name, item in table.items():
        if isinstance(item, tuple):
            guesses[name] = item[1]
        elif isinstance(item, str):
            try:
                given[name] = parse_expression(item, symbols, where=f"initial.{name}")
            except ParseError as exc:
                problems.append(str(exc) + " (an [initial] value may use the parameters)")
        else:
            given[name] = sp.Float(item)
    return InitialData(MappingProxyType(given), MappingProxyType(guesses))


def solved_text(values, solved) -> str:
    """``x_dot = 2, y_dot = 0``: the values nhham solved, for a warning."""
    return ", ".join(f"{n} = {values[n]:.10g}" for n in solved)


# ------------------------------------------------------------------ completion
def complete_initial(system: "System", data: InitialData,
                     values: Mapping | None = None, *, where: str = "initial"
                     ) -> tuple[dict, tuple]:
    """Every coordinate and velocity: the given values, the others solved.

    ``values`` (parameter name -> value) replace the system's parameter values (the
    start at another point of a study, as ``--set`` gives it). ``where`` names the table
    in messages and error keys (``"steady"`` for a steady motion given in Python).

    Returns
    -------
    (dict, tuple of str)
        The values in state order, and the names that were solved.

    Raises
    ------
    MissingParameterValueError
        A value uses a parameter without a value.
    InputError
        A value left out that the constraints do not determine (named).
    InconsistentInitialDataError
        Given values over-determine those left out and disagree (the constraint named).
    """
    params = {p: sp.Float(v) for p, v in system.parameter_values.items()}
    given_values = dict(values or {})
    params.update({p: sp.Float(given_values[p.name]) for p in system.parameters
                   if p.name in given_values})
    if system.time is not None:  # a scene's runs start at t = 0
        params.setdefault(system.time, sp.Float(0))
    values = {name: _number(name, expr, params, where)
              for name, expr in data.given.items()}
    q_names = [q.name for q in system.coordinates]
    v_names = [v.name for v in system.velocities]
    missing_q = [n for n in q_names if n not in values]
    missing_v = [n for n in v_names if n not in values]
    if missing_q:
        values.update(_coordinates(system, values, missing_q, data.guesses, params, where))
    if missing_v:
        values.update(_velocities(system, values, missing_v, params, data.guesses, where))
    order = q_names + v_names
    return {n: values[n] for n in order}, tuple(n for n in order
                                                if n in missing_q or n in missing_v)


def _number(name, expr, params, where) -> float:
    missing = sorted(s.name for s in expr.free_symbols if s not in params)
    if missing:
        raise MissingParameterValueError(
            f"{where}.{name}: no value for parameter {', '.join(map(repr, missing))} "
            f"(give it in parameters or with --set)", key=f"{where}.{name}")
    try:
        value = complex(expr.xreplace(params).evalf())
    except (TypeError, ValueError, OverflowError, ZeroDivisionError):
        value = complex(math.nan)
    if value.imag or not math.isfinite(value.real):
        raise InputError(f"{where}.{name}: {expr} is not a finite real number at the "
                         f"parameter values", key=f"{where}.{name}")
    return value.real


def _coordinates(system, values, missing, guesses, params, where) -> dict:
    """The coordinates left out, by Newton's method on the holonomic constraints."""
    names = ", ".join(missing)
    if not system.holonomic:
        raise InputError(f"{where}: no value for {names}: only coordinates that holonomic "
                         f"constraints determine may be left out, and the scene has none",
                         key=where)
    unknowns = [sp.Symbol(n) for n in missing]
    known = dict(params)
    known.update({sp.Symbol(n): sp.Float(v) for n, v in values.items()})
    labelled = [(f"holonomic[{i}]", sp.sympify(g).xreplace(known))
                for i, g in enumerate(system.holonomic)]
    eqs = [(lab, g) for lab, g in labelled if g.free_symbols & set(unknowns)]
    rest = sorted(s.name for _, g in eqs for s in g.free_symbols if s not in unknowns)
    if rest:  # a velocity cannot be in a holonomic constraint: a value is missing
        raise InputError(f"{where}: the holonomic constraints need {', '.join(rest)} to "
                         f"solve {names}", key=where)
    if len(eqs) < len(missing):
        raise InputError(f"{where}: {names} left out, but the holonomic constraints fix at "
                         f"most {len(eqs)} of them: give a value for the others",
                         key=where)
    x, r, jac = _newton([g for _, g in eqs], unknowns,
                        [guesses.get(n, 0.0) for n in missing])
    start = ", ".join(f"{n} = {guesses.get(n, 0.0):g}" for n in missing)
    if not np.all(np.isfinite(r)) or \
            np.max(np.abs(r)) > _TOL * max(1.0, float(np.max(np.abs(x)))):
        at = f" (residual {float(np.max(np.abs(r))):.3g})" if np.all(np.isfinite(r)) else ""
        raise InconsistentInitialDataError(
            f"{where}: Newton's method from {start} found no point of the holonomic "
            f"constraints for {names}{at}: give a starting point, e.g. "
            f"{missing[0]} = {{ guess = 1.0 }}, or the values", key=where)
    _require_determined(jac, missing, "the holonomic constraints", "the point found", where)
    return {n: float(v) for n, v in zip(missing, x)}


def _newton(exprs, unknowns, start) -> tuple:
    """(x, residual, Jacobian) after Gauss-Newton steps on exprs = 0 from ``start`` (least-
    squares steps: more equations than unknowns are fine); NaN where they cannot be
    evaluated at the point reached."""
    F = sp.lambdify(unknowns, list(exprs), "math")
    J = sp.lambdify(unknowns, sp.Matrix(list(exprs)).jacobian(unknowns).tolist(), "math")
    x = np.array(start, dtype=float)
    for _ in range(_NEWTON_STEPS):
        try:
            r = np.array(F(*x), dtype=float)
            step = np.linalg.lstsq(np.array(J(*x), dtype=float), -r, rcond=None)[0]
        except (ValueError, ZeroDivisionError, OverflowError):
            break
        x = x + step
        if np.max(np.abs(step)) <= 1e-15 * (1.0 + np.max(np.abs(x))):
            break
    try:
        return x, np.array(F(*x), dtype=float), np.array(J(*x), dtype=float)
    except (ValueError, ZeroDivisionError, OverflowError):
        return (x, np.full(len(exprs), np.nan),
                np.full((len(exprs), len(unknowns)), np.nan))


def _velocity_rows(system):
    """(label, expression) of every velocity-level constraint: the affine ones and the
    time derivatives of the holonomic ones."""
    from nhham.system.initial import labelled_constraints

    return [(lab, sp.sympify(e)) for lab, e in labelled_constraints(system)
            if lab.startswith("constraints[") or lab.endswith("(time derivative)")]


def _velocities(system, values, missing, params, guesses, where) -> dict:
    """The velocities left out, from the velocity-level constraints: exactly where they
    enter linearly, by Newton's method from the user's guesses where a nonlinear
    (Chetaev) constraint has them inside (its roots are branches: the guess picks one)."""
    unknowns = [sp.Symbol(n) for n in missing]
    known = dict(params)
    known.update({sp.Symbol(n): sp.Float(v) for n, v in values.items()})
    rows = _velocity_rows(system)
    at = [_at_initial(e, known, lab, where) for lab, e in rows]
    zero = {u: 0 for u in unknowns}
    guesses = dict(guesses or {})
    gradients = [[derivative(e, u) if u in fs else sp.S.Zero for u in unknowns]
                 for e, fs in ((e, e.free_symbols) for e in at)]   # d(phi_i)/d(u_j), once
    for (lab, _), grad in zip(rows, gradients):  # Chetaev: phi may have several roots in them
        inside_grad = set().union(*(g.free_symbols for g in grad))
        inside = sorted(u.name for u in unknowns if u in inside_grad)
        unguessed = [n for n in inside if n not in guesses]
        if unguessed:
            one = len(unguessed) == 1
            raise InputError(f"{where}: {', '.join(unguessed)} {'enters' if one else 'enter'} "
                             f"{lab} nonlinearly (a nonlinear constraint may have several "
                             f"roots): give {'its value' if one else 'their values'} or a "
                             f"starting point for Newton's method, e.g. "
                             f"{unguessed[0]} = {{ guess = 1.0 }}", key=where)
        if inside:
            return _velocities_by_newton(rows, at, missing, unknowns, guesses, where)
    A = np.array([[_real(g, lab, where) for g in grad] for (lab, _), grad in
                  zip(rows, gradients)], dtype=float).reshape(len(rows), len(unknowns))
    b = np.array([_real(e.xreplace(zero), lab, where) for (lab, _), e in zip(rows, at)],
                 dtype=float)
    scale = max(1.0, float(np.max(np.abs(A), initial=0.0)),
                float(np.max(np.abs(b), initial=0.0)))
    # a constraint without a velocity left out relates given ones: not independent
    given = {v for v in system.velocities if v.name not in missing}
    related = [(lab, sorted(s.name for s in e.free_symbols & given))
               for (lab, e), row in zip(rows, A) if not np.any(np.abs(row) > _TOL * scale)]
    _, sv, vt = np.linalg.svd(A) if len(rows) else (None, np.zeros(0), np.eye(len(missing)))
    rank = int(np.sum(sv > _TOL * scale))
    if rank < len(missing):
        free = [n for j, n in enumerate(missing) if np.any(np.abs(vt[rank:, j]) > 1e-8)]
        one = len(free) == 1
        raise InputError(
            f"{where}: {', '.join(free)} {'is' if one else 'are'} not fixed by the "
            f"constraints and the velocities given: give "
            + ("its value" if one else f"values for {len(missing) - rank} of them")
            + _related(related), key=where)
    # LU where A is square (full rank here): a velocity that the constraints fix at 0 comes
    # out as 0 (the roller racer's y_dot = 0 at theta = 0 was 2.7e-17 from the SVD of lstsq)
    x = (np.linalg.solve(A, -b) if A.shape[0] == A.shape[1]
         else np.linalg.lstsq(A, -b, rcond=None)[0])
    residual = A @ x + b
    bad = [(lab, float(r)) for (lab, _), r in zip(rows, residual) if abs(r) > _TOL * scale]
    if bad:
        raise InconsistentInitialDataError(
            f"{where}: the velocities given over-determine {', '.join(missing)}: "
            + "; ".join(f"{lab} = {r:.6g}" for lab, r in bad) + " with them solved"
            + (_related(related) or "; leave one more velocity out"), key=where)
    return {n: float(v) + 0.0 for n, v in zip(missing, x)}   # + 0.0: no "-0"


def _at_initial(expr, known, label, where):
    """``expr`` (``label``'s row) at the known initial values, or the InputError that it
    is not defined there: sympy's atan2 of 1/0 compares NaN and raises a TypeError."""
    try:
        return expr.xreplace(known)
    except TypeError:
        raise _not_finite(label, "undefined", where) from None


def _not_finite(label, value, where) -> InconsistentInitialDataError:
    return InconsistentInitialDataError(
        f"{where}: {label} is not a finite real number at the {where} state (one of its "
        f"coefficients is {value}); give [{where}] values where it is defined", key=where)


def _real(value, label, where) -> float:
    """A coefficient of ``label``'s row at the initial state as a float, or the
    InputError that it is not a finite real number there (sqrt(x) at x = -2)."""
    try:
        number = complex(sp.sympify(value).evalf())
    except (TypeError, ValueError):   # zoo, nan: no complex number
        number = complex(math.nan)
    if not (math.isfinite(number.real) and number.imag == 0.0):
        raise _not_finite(label, sp.sstr(sp.sympify(value).evalf(6)), where)
    return number.real


def _velocities_by_newton(rows, at, missing, unknowns, guesses, where) -> dict:
    names = ", ".join(missing)
    x, r, jac = _newton(at, unknowns, [guesses.get(n, 0.0) for n in missing])
    start = ", ".join(f"{n} = {guesses.get(n, 0.0):g}" for n in missing)
    scale = max(1.0, float(np.max(np.abs(x), initial=0.0)))
    if not np.all(np.isfinite(r)) or np.max(np.abs(r), initial=0.0) > _TOL * scale:
        worst = int(np.nanargmax(np.abs(r))) if np.any(np.isfinite(r)) else 0
        raise InconsistentInitialDataError(
            f"{where}: Newton's method from {start} found no velocities {names} on the "
            f"constraints ({rows[worst][0]} not met): give another guess or the values",
            key=where)
    _require_determined(jac, missing, "the constraints", "the velocities found", where)
    return {n: float(v) for n, v in zip(missing, x)}


def _require_determined(jac, missing, which, at, where) -> None:
    """Refuse values Newton's method found where the equations' Jacobian in them is
    singular (they are not determined there)."""
    if np.linalg.matrix_rank(jac, tol=_TOL * max(1.0, float(np.max(np.abs(jac))))) < \
            len(missing):
        raise InputError(f"{where}: {which} do not determine {', '.join(missing)} at "
                         f"{at} (their Jacobian in them is singular there): give a "
                         f"value for one of them", key=where)


def _related(related) -> str:
    parts = [f"{lab} relates {', '.join(names)}" for lab, names in related if len(names) > 1]
    if not parts:
        return ""
    return ("; the velocities given are not independent (" + "; ".join(parts)
            + "): leave one of each out")
