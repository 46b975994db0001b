"""A state given in Python by any of the names a user has for it: nhham's (``"x"``,
``"x_dot"``), sympy's dynamicsymbols (``q1(t)``, ``q1(t).diff(t)``) or the generalized
speeds ``u(t)`` of a ``sympy.physics.mechanics`` model (through its kinematic differential
equations). Only the independent entries are needed: the others are solved as a scene's
``[initial]`` ones are (:func:`nhham.system.initial_solve.complete_initial`).

Examples
--------
>>> import sympy as sp
>>> from sympy.physics.mechanics import dynamicsymbols
>>> from nhham import System
>>> from nhham.system.state_keys import completed_state
>>> x, y = dynamicsymbols("x y")
>>> t = dynamicsymbols._t
>>> bead = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["y_dot - 2*x_dot"])
>>> completed_state(bead, {x: 0, y: 1, x.diff(t): 0.5})[0]
{'x': 0.0, 'y': 1.0, 'x_dot': 0.5, 'y_dot': 1.0}
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

import sympy as sp
from sympy.core.function import AppliedUndef

from nhham.errors import InputError
from nhham.system.expressions import parse_expression
from nhham.system.initial_solve import InitialData, complete_initial

__all__ = ["state_entries", "completed_state", "steady_table", "as_system"]


def state_entries(system, mapping: Mapping, *, speeds: Mapping | None = None,
                  where: str = "initial", inputs: bool = False) -> dict:
    """``{state name: value}`` from a mapping keyed by any of the user's names.

    Parameters
    ----------
    system : System
    mapping : mapping
        Keys: nhham's names (str or Symbol), dynamicsymbols ``q(t)`` and ``q(t).diff(t)``,
        or speeds ``u(t)`` (with ``speeds``); values: numbers, or expressions (strings or
        sympy) in the parameters.
    speeds : mapping, optional
        ``{u(t): expression in nhham's q, q_dot}`` (``System.speeds``): a speed's value
        is one equation on the velocities, solved with the others given.
    where : str
        The name of the table in messages.
    inputs : bool
        The inputs may be given too (a steady motion's).

    Raises
    ------
    InputError
        A key that names nothing of the system, a value in names that are not
        parameters, speeds that do not determine the velocities they involve.
    """
    names = {q.name for q in system.coordinates} | {v.name for v in system.velocities}
    if inputs:
        names |= {u.name for u in system.inputs}
    t = _time()
    by_function = {sp.Function(q.name)(t): q.name for q in system.coordinates}
    params = {p.name: p for p in system.parameters}
    out: dict = {}
    equations = []
    for key, value in mapping.items():
        expr = _value(value, params, f"{where}.{key}")
        if isinstance(key, (str, sp.Symbol)) and str(key) in names:
            out[str(key)] = expr
        elif isinstance(key, AppliedUndef) and key in by_function:
            out[by_function[key]] = expr
        elif isinstance(key, sp.Derivative) and key.derivative_count == 1 and \
                key.expr in by_function:
            out[by_function[key.expr] + "_dot"] = expr
        elif speeds and key in speeds:
            equations.append((key, speeds[key] - expr))
        else:
            raise InputError(f"{where}: {key} is not a coordinate, a velocity"
                             + (", an input" if inputs else "")
                             + (" or a speed" if speeds else "")
                             + f" of the system ({', '.join(sorted(names))})", key=where)
    if equations:
        out.update(_from_speeds(system, equations, out, where))
    return out


def completed_state(system, mapping: Mapping, *, speeds: Mapping | None = None,
                    where: str = "initial") -> tuple[dict, tuple]:
    """Every coordinate and velocity (floats, in state order) from the entries given,
    the others solved; returns (state, the names solved).

    Raises
    ------
    InputError
        As :func:`state_entries`, and where the constraints do not determine what was
        left out (named).
    """
    given = state_entries(system, mapping, speeds=speeds, where=where)
    return complete_initial(system, InitialData(MappingProxyType(given),
                                                MappingProxyType({})), where=where)


def steady_table(system, mapping: Mapping, *, speeds: Mapping | None = None):
    """A steady motion from its independent entries: a
    :class:`~nhham.system.steady.SteadyState` whose given entries keep their expressions
    in the parameters and whose other entries are solved at the parameter values, and
    solved again at any others (its ``solve``: a swept parameter moves the motion as the
    entries given say, not as the values solved at the first point would).

    Parameters
    ----------
    system : System
    mapping : mapping
        As for :func:`state_entries` (with the inputs' steady values).
    speeds : mapping, optional
        As for :func:`state_entries`.

    Returns
    -------
    SteadyState

    Raises
    ------
    InputError
        As :func:`completed_state`, naming the ``steady`` table.

    Examples
    --------
    A bead on the line y' = k x' moving at x' = c: y' = k c solved, and again at c = 2.

    >>> from nhham import System
    >>> bead = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["y_dot - k*x_dot"],
    ...               parameters={"k": 3.0, "c": 1.0})
    >>> steady = steady_table(bead, {"x": 0, "y": 0, "x_dot": "c"})
    >>> steady.values({"k": 3.0, "c": 1.0})["y_dot"], steady.values({"k": 3.0, "c": 2.0})["y_dot"]
    (3.0, 6.0)
    """
    from nhham.system.steady import SteadyState

    given = state_entries(system, mapping, speeds=speeds, where="steady", inputs=True)
    names = {u.name for u in system.inputs}
    state_given = {k: v for k, v in given.items() if k not in names}
    state, solved = completed_state(system, state_given, where="steady")
    exprs = {k: given.get(k, sp.Float(v)) for k, v in state.items()}
    exprs.update({k: v for k, v in given.items() if k in names})
    if not solved:
        return SteadyState(MappingProxyType(exprs))
    # Newton's method at other values starts from the point solved here
    data = InitialData(MappingProxyType(state_given),
                       MappingProxyType({n: state[n] for n in solved}))
    base = {p.name: float(v) for p, v in system.parameter_values.items()}

    def solve(parameters: Mapping[str, float]) -> Mapping[str, float]:
        if all(float(parameters.get(k, v)) == v for k, v in base.items()):
            return state
        return complete_initial(system, data, parameters, where="steady")[0]

    return SteadyState(MappingProxyType(exprs), solve=solve)


def as_system(thing, values=None) -> tuple:
    """(System, speeds): a ``sympy.physics.mechanics`` System brought in by
    :func:`~nhham.system.mechanics.from_mechanics` (its parameters' ``values``), a
    System as it is; the speeds those of the model it was made from (``System.speeds``)."""
    if type(thing).__module__.startswith("sympy.physics.mechanics"):
        from nhham.system.mechanics import from_mechanics

        thing = from_mechanics(thing, parameters=values)
    return thing, dict(getattr(thing, "speeds", {}))


# ------------------------------------------------------------------ helpers
def _time():
    from sympy.physics.mechanics import dynamicsymbols

    return dynamicsymbols._t


def _value(value, params, where):
    """A value as a sympy expression in the parameters."""
    if isinstance(value, str):
        return parse_expression(value, params, where=where)
    expr = sp.sympify(value)
    unknown = sorted(s.name for s in expr.free_symbols if s.name not in params)
    if unknown:
        raise InputError(f"{where}: {expr} uses {', '.join(unknown)}, which "
                         f"{'is not a parameter' if len(unknown) == 1 else 'are not parameters'}",
                         key=where)
    return expr.xreplace({s: params[s.name] for s in expr.free_symbols})


def _from_speeds(system, equations, given, where) -> dict:
    """The velocities the speed equations fix, with the coordinates given."""
    at = {sp.Symbol(k): v for k, v in given.items()}
    vels = [v for v in system.velocities if v.name not in given]
    eqs = [e.xreplace(at) for _, e in equations]
    unknown = [v for v in vels if any(v in e.free_symbols for e in eqs)]
    coords = sorted({s.name for e in eqs for s in e.free_symbols
                     if s in set(system.coordinates)})
    if coords:
        raise InputError(f"{where}: the speeds {', '.join(str(k) for k, _ in equations)} "
                         f"need the coordinates {', '.join(coords)} given", key=where)
    A = sp.Matrix([[sp.diff(e, v) for v in unknown] for e in eqs])
    if A.rows != A.cols or A.det() == 0:
        raise InputError(f"{where}: the speeds {', '.join(str(k) for k, _ in equations)} do "
                         f"not determine the velocities they involve "
                         f"({', '.join(v.name for v in unknown)}); give the velocities "
                         f"instead", key=where)
    rest = sp.Matrix([e.xreplace({v: 0 for v in unknown}) for e in eqs])
    solution = A.LUsolve(-rest)
    return {v.name: sp.nsimplify(s) if s.is_number else s for v, s in zip(unknown, solution)}
