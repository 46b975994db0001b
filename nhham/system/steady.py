"""Steady motions stated in a scene: the ``[steady]`` table.

A scene may give a steady motion (an equilibrium or a relative equilibrium,
e.g. a bicycle rolling upright at speed v) about which ``nhham linearize``
linearises::

    [steady]
    x = 0.0
    phi = 0
    x_dot = "v"              # an expression in the parameters
    thetaR_dot = "v/rR"
    ...

Every coordinate and every velocity needs a value: a number, or a string
parsed (never evaluated as Python) against a symbol table holding only the
parameters, ``pi`` and the usual functions. Because the entries are
expressions in the parameters, a parameter sweep moves the steady motion with
the parameter. Whether the state lies on M_1 and is steady is checked where it
is used (:func:`nhham.numerics.linearization.linearize`), with the residuals in
the message.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Callable, Mapping

import numpy as np
import sympy as sp

from nhham.errors import MissingParameterValueError, ParseError
from nhham.system.expressions import parse_expression
from nhham.system.naming import velocity_symbol

__all__ = ["SteadyState", "state_table", "steady_structure", "parse_steady"]


@dataclass(frozen=True)
class SteadyState:
    """A steady motion: each coordinate and velocity as an expression in the parameters.

    Attributes
    ----------
    expressions : mapping of str to sympy.Expr
        State name -> value, in the order coordinates, velocities.
    solve : callable or None
        For a table whose entries were partly solved (a steady motion given in Python by
        its independent entries, :func:`nhham.system.state_keys.steady_table`):
        ``{parameter: value} -> {state name: float}``, the given entries evaluated and
        the others solved again at those values, so that the motion moves with a swept
        parameter as the user's entries say (``expressions`` then holds the solved
        entries' values at the system's parameter values). Its family's tangents are
        not formed (:meth:`family` is empty): a neighbouring steady motion the chart
        does not remove stays a zero eigenvalue.
    """

    expressions: Mapping[str, sp.Expr]
    solve: Callable[[Mapping[str, float]], Mapping[str, float]] | None = field(
        default=None, compare=False, repr=False)

    def values(self, parameters: Mapping[str, float]) -> dict:
        """The state as ``{name: float}`` at the given parameter values.

        Parameters
        ----------
        parameters : mapping of str to float
            A value for every parameter the expressions use.

        Raises
        ------
        MissingParameterValueError
            A parameter used has no value (the key is named).
        ParseError
            An entry is not a finite real number at these values.
        """
        solved = {} if self.solve is None else self.solve(parameters)
        out = {}
        for name, expr in self.expressions.items():
            if name in solved:
                out[name] = float(solved[name])
                continue
            if name in self._numbers:  # a number: the same at every parameter value
                out[name] = self._numbers[name]
                continue
            missing = sorted(s.name for s in expr.free_symbols if s.name not in parameters)
            if missing:
                raise MissingParameterValueError(
                    f"steady.{name}: no numeric value for parameter {', '.join(missing)}")
            out[name] = _at(name, expr, self._compiled[name], parameters)
        return out

    def arrays(self, parameters: Mapping) -> dict:
        """The state at many parameter values at once: ``{name: ndarray}``.

        Parameters
        ----------
        parameters : mapping of str to float or ndarray
            A value (or an array of values, all of one shape) for every parameter the
            expressions use.

        Returns
        -------
        dict of str to ndarray
            Each entry at every point, of the arrays' shape; NaN where it is not a finite
            real number there (the caller says which points those are).
        """
        shapes = {np.shape(v) for v in parameters.values()}
        shape = np.broadcast_shapes(*shapes) if shapes else ()
        if self.solve is not None:
            return self._arrays_by_point(parameters, shape)
        out = {}
        for name, expr in self.expressions.items():
            if name in self._numbers:
                out[name] = np.full(shape, self._numbers[name])
                continue
            names, f = self._vectorized[name]
            missing = [s for s in names if s not in parameters]
            if missing:
                raise MissingParameterValueError(
                    f"steady.{name}: no numeric value for parameter {', '.join(missing)}")
            with np.errstate(all="ignore"):
                value = np.asarray(f(*(np.asarray(parameters[s], dtype=float)
                                       for s in names)))
            if np.iscomplexobj(value):
                value = np.where(np.abs(value.imag) <= 1e-12 * np.maximum(1, np.abs(value.real)),
                                 value.real, np.nan)
            out[name] = np.broadcast_to(value.astype(float), shape).copy()
        return out

    @cached_property
    def _vectorized(self) -> dict:
        return {name: (sorted(s.name for s in e.free_symbols),
                       sp.lambdify(sorted(e.free_symbols, key=lambda s: s.name), e,
                                   modules="numpy"))
                for name, e in self.expressions.items() if e.free_symbols}

    def _arrays_by_point(self, parameters: Mapping, shape) -> dict:
        """:meth:`arrays` of a table with solved entries: :meth:`values` at each point."""
        from nhham.errors import NhhamError

        every = {k: np.broadcast_to(np.asarray(v, dtype=float), shape)
                 for k, v in parameters.items()}
        out = {name: np.full(shape, np.nan) for name in self.expressions}
        for index in np.ndindex(shape):
            try:
                point = self.values({k: float(v[index]) for k, v in every.items()})
            except NhhamError:   # NaN: the caller says which points those are
                continue
            for name, value in point.items():
                out[name][index] = value
        return out

    def family(self, parameters: Mapping[str, float]) -> dict:
        """Tangents of the steady family: ``{p: {name: d value / d p}}`` for every
        parameter p the entries use, at the given parameter values (exact
        derivatives, evaluated); empty for a table with solved entries (``solve``)."""
        if self.solve is not None:
            return {}
        return {p: {name: 0.0 if d == 0 else _at(name, d, f, parameters)
                    for name, (d, f) in tangent.items()}
                for p, tangent in self._derivatives.items()}

    # Formed once per steady state: a parameter sweep evaluates the state and its
    # family at every value.
    @cached_property
    def _numbers(self) -> dict:
        point: dict = {}
        return {name: _real(name, e, point) for name, e in self.expressions.items()
                if not e.free_symbols}

    @cached_property
    def _compiled(self) -> dict:
        return {name: _compile(e) for name, e in self.expressions.items() if e.free_symbols}

    @cached_property
    def _derivatives(self) -> dict:
        used = sorted({s.name for e in self.expressions.values() for s in e.free_symbols})
        out: dict = {}
        for p in used:
            out[p] = {}
            for name, e in self.expressions.items():
                d = sp.diff(e, sp.Symbol(p))
                out[p][name] = (d, _compile(d) if d.free_symbols else None)
        return out

    def to_toml_table(self) -> dict:
        """``{name: float or str}`` as a scene's ``[steady]`` table would hold it."""
        return {k: float(v) if v.is_number else str(v) for k, v in self.expressions.items()}


def _compile(expr):
    """(parameter names, a float64 function of them) for an expression in the parameters."""
    names = sorted(s.name for s in expr.free_symbols)
    return names, sp.lambdify([sp.Symbol(s) for s in names], expr, modules="math")


def _at(name, expr, compiled, parameters) -> float:
    """An entry at the parameter values, in float64 (a constant: ``compiled`` None)."""
    if compiled is None:
        return _real(name, expr, {})
    names, f = compiled
    try:
        value = float(f(*(float(parameters[s]) for s in names)))
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        value = math.nan
    if not math.isfinite(value):
        raise ParseError(f"steady.{name}: {expr} is not a finite real number at the "
                         f"parameter values")
    return value


def _real(name, expr, point) -> float:
    """``expr`` at ``point`` (20 digits, then rounded), checked finite and real."""
    try:
        z = complex(expr.xreplace(point).evalf(20))
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        z = complex(math.nan)
    if not (math.isfinite(z.real) and abs(z.imag) <= 1e-12 * max(1.0, abs(z.real))):
        raise ParseError(f"steady.{name}: {expr} is not a finite real number at the "
                         f"parameter values")
    return z.real


def state_names(coordinates) -> list:
    """Coordinates then their velocities, as names."""
    return list(coordinates) + [velocity_symbol(sp.Symbol(q)).name for q in coordinates]


def state_table(table: Mapping, coordinates, entry: Callable, problems: list, *,
                section: str, path: Callable[[object], str], inputs=(),
                required: bool = True) -> Mapping:
    """The entries of a scene table that gives a value for exactly every state name.

    The one check behind ``[initial]`` and ``[steady]``: an unknown key (with the
    closest state name as a hint) and the state names without a value are problems.

    Parameters
    ----------
    table : mapping
        The raw table.
    coordinates : sequence of str
        The scene's coordinates; the state names are these and their velocities.
    entry : callable
        ``entry(item, path, problems)``: the value kept for one entry, or None once it
        has appended the entry's problem.
    problems : list of str
        Where the problems are appended.
    section : str
        The table's name, which the missing values' problem starts with.
    path : callable
        ``path(key)``: how a problem names an entry.
    inputs : sequence of str, optional
        Input names that need a value too (after the state names).
    required : bool, optional
        False: names may be left out (``[initial]``: the dependent ones are solved).

    Returns
    -------
    mapping of str
        The values kept, in state order (read-only).
    """
    wanted = state_names(coordinates) + list(inputs)
    kept = {}
    for key, item in table.items():
        where = path(key)
        if key not in wanted:
            close = difflib.get_close_matches(str(key), wanted, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            what = "a coordinate, velocity or input" if inputs else "a coordinate or velocity"
            problems.append(f"{where}: unknown name (not {what}){hint}")
            continue
        value = entry(item, where, problems)
        if value is not None:
            kept[key] = value
    missing = [name for name in wanted if name not in table]
    if missing and required:
        every = "coordinate, velocity and input" if inputs else "coordinate and velocity"
        problems.append(f"{section}: missing value for {', '.join(map(repr, missing))} "
                        f"(every {every} needs one)")
    return MappingProxyType({name: kept[name] for name in wanted if name in kept})


def steady_structure(value, coordinates, problems, inputs=()) -> Mapping | None:
    """Check a raw ``[steady]`` table: a number or string for exactly every state name
    and every input (the inputs' steady values, about which ``linearize`` forms B).

    Problems are appended to ``problems`` (each naming ``steady.<key>``); the
    raw values are returned (or None when there is no table).
    """
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append("steady: expected a table of name = number or expression")
        return None
    return state_table(value, coordinates, _steady_entry, problems,
                       section="steady", path="steady.{}".format, inputs=inputs)


def _steady_entry(item, path, problems):
    """A ``[steady]`` value as given: a finite number or an expression string."""
    if isinstance(item, bool) or not isinstance(item, (int, float, str)):
        problems.append(f"{path}: expected a number or an expression string")
        return None
    if isinstance(item, float) and not math.isfinite(item):
        problems.append(f"{path}: expected a finite number, got {item!r}")
        return None
    return item


def parse_steady(raw: Mapping | None, parameters) -> tuple[SteadyState | None, list]:
    """Parse the entries of a checked ``[steady]`` table against the parameters.

    Returns
    -------
    (SteadyState or None, list of str)
        The steady state and the problems found (each naming its key).
    """
    if raw is None:
        return None, []
    table = {p: sp.Symbol(p) for p in parameters}
    exprs, problems = {}, []
    for name, item in raw.items():
        path = f"steady.{name}"
        if isinstance(item, str):
            try:
                exprs[name] = parse_expression(item, table, where=path)
            except ParseError as exc:
                problems.append(str(exc))
        else:
            exprs[name] = sp.Float(float(item)) if isinstance(item, float) else sp.Integer(item)
    if problems:
        return None, problems
    return SteadyState(MappingProxyType(exprs)), []
