"""The numbers of a scene: what a scene accepts as a number, in its TOML and on the
command line (``--set``), and parameter values given when it loads.

A number is a TOML integer or float (not a boolean), finite, and within double
precision: ``1e-400``, which tomllib would read as 0 without a word, is refused. Where a
scene reads a number it also takes an expression string in the parameters
(``t_end = "7*pi/Omega"``, ``I = "m*R**2/2"``): :func:`number_or_expression` keeps it,
:func:`resolve_parameters` gives the parameters theirs (in the order they depend on each
other) and :func:`expression_value` evaluates one at the parameters' values.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from dataclasses import replace

from nhham.errors import InputError

__all__ = ["finite_number", "toml_float", "scene_number", "with_values", "type_name",
           "number_or_expression", "expression_value", "resolve_parameters"]

_TYPE_NAMES = ((bool, "a boolean"), (int, "an integer"), (float, "a float"),
               (str, "a string"), (list, "an array"), (dict, "a table"))


def type_name(value) -> str:
    """How a TOML value's type is called in messages (the only other TOML type: date/time)."""
    return next((name for kind, name in _TYPE_NAMES if isinstance(value, kind)), "a date/time")


def finite_number(value, path, problems) -> float | None:
    """A finite real number (TOML integer or float, not boolean) as float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        hint = (" (for a parameter without a value use symbolic_parameters)"
                if path.startswith("parameters.") and isinstance(value, str) else "")
        problems.append(f"{path}: expected a number, got {type_name(value)}{hint}")
        return None
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        problems.append(f"{path}: expected a finite number, got {value!r}")
        return None
    return number


def number_or_expression(value, path, problems) -> float | str | None:
    """A finite number (as float) or an expression string (kept, evaluated once the
    parameters have their values); anything else is a problem naming ``path``."""
    if isinstance(value, str):
        if not value.strip():
            problems.append(f"{path}: empty expression")
            return None
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        problems.append(f"{path}: expected a number or an expression string, got "
                        f"{type_name(value)}")
        return None
    return finite_number(value, path, problems)


def expression_value(value, values: dict, path: str) -> float:
    """``value`` (a number, or an expression string in the parameters) at the parameter
    values ``values`` (name -> float; None: a parameter without a value).

    Raises
    ------
    InputError
        The expression cannot be parsed, uses a name that is not a parameter or a
        parameter without a value, or is not a finite real number there (naming
        ``path``).

    Examples
    --------
    >>> expression_value("7*pi/Omega", {"Omega": 2.0}, "simulate.t_end")
    10.995574287564276
    >>> expression_value(3, {}, "simulate.t_end")
    3.0
    """
    import sympy as sp

    from nhham.errors import ParseError
    from nhham.system.expressions import parse_expression

    if not isinstance(value, str):
        return float(value)
    symbols = {p: sp.Symbol(p) for p in values}
    try:
        expr = parse_expression(value, symbols, where=path)
    except ParseError as exc:
        raise InputError(f"{exc} (a number here may be an expression in the parameters)",
                         key=path) from None
    unset = sorted(s.name for s in expr.free_symbols if values.get(s.name) is None)
    if unset:
        raise InputError(f"{path}: {value!r} uses {', '.join(unset)}, which "
                         f"{'has' if len(unset) == 1 else 'have'} no value (a number here is "
                         f"an expression in parameters with values)", key=path)
    number = expr.xreplace({sp.Symbol(k): sp.Float(v) for k, v in values.items()
                            if v is not None}).evalf(17)
    if not number.is_real or not number.is_finite:
        raise InputError(f"{path}: {value!r} is {number} at the parameter values, not a "
                         f"finite real number", key=path)
    return float(number)


def resolve_parameters(parameters: dict, problems: list) -> dict:
    """The parameters with every expression value evaluated, in the order the
    expressions depend on each other (name -> float, or None for a symbolic one).

    A cycle, an expression in a symbolic parameter or one that cannot be evaluated is a
    problem naming ``parameters.<name>`` (the parameter is then left without a value).

    Examples
    --------
    >>> resolve_parameters({"m": 2.0, "R": 0.5, "I": "m*R**2/2"}, [])
    {'m': 2.0, 'R': 0.5, 'I': 0.25}
    >>> problems = []
    >>> _ = resolve_parameters({"a": "b", "b": "2*a"}, problems); problems[0]
    "parameters.a: 'b' depends on itself (through b)"
    """
    import sympy as sp

    from nhham.system.expressions import parse_expression

    pending = {k: v for k, v in parameters.items() if isinstance(v, str)}
    if not pending:
        return dict(parameters)
    out = {k: v for k, v in parameters.items() if not isinstance(v, str)}
    needs: dict[str, set | None] = {}
    symbols = {p: sp.Symbol(p) for p in parameters}
    for name, text in pending.items():
        try:
            needs[name] = {s.name for s in parse_expression(
                text, symbols, where=f"parameters.{name}").free_symbols}
        except InputError as exc:
            problems.append(f"{exc} (a parameter's value may be an expression in the others)")
            needs[name] = None
    while pending:
        ready = [n for n in pending if (need := needs[n]) is not None and not need & set(pending)]
        if not ready:
            for name in pending:
                need = needs[name]
                if need is not None:
                    cycle = ", ".join(sorted(need & set(pending)))
                    problems.append(f"parameters.{name}: {pending[name]!r} depends on itself "
                                    f"(through {cycle})")
                out[name] = None
            break
        for name in ready:
            try:
                out[name] = expression_value(pending.pop(name), out, f"parameters.{name}")
            except InputError as exc:
                problems.append(str(exc))
                out[name] = None
        for name in [n for n in pending if needs[n] is None]:
            pending.pop(name)
            out[name] = None
    return {k: out[k] for k in parameters}


def toml_float(literal: str) -> float:
    """A TOML float literal as a float; ValueError for one that double precision cannot
    hold (``1e-400`` would become 0 without a word; ``1e400`` inf, refused later as not
    finite)."""
    value = float(literal)
    mantissa = re.split("[eE]", literal)[0]
    if value == 0.0 and any(c in "123456789" for c in mantissa):
        raise ValueError(f"the number {literal} is outside the range of double precision "
                         f"(about 1e-308 to 1e308)")
    return value


def scene_number(text: str, where: str) -> float:
    """A number written as in a scene (TOML: ``2``, ``0.5``, ``1e-3``, ``1_000``), checked
    as a scene's parameter value is.

    Raises
    ------
    InputError
        Not a number, not finite, or outside double precision (naming ``where``).
    """
    try:
        value = tomllib.loads(f"v = {text.strip()}", parse_float=toml_float).get("v")
    except (tomllib.TOMLDecodeError, ValueError) as exc:
        why = str(exc) if "double precision" in str(exc) else \
            f"expected a number as a scene writes one (2, 0.5, 1e-3), got {text.strip()!r}"
        raise InputError(f"{where}: {why}", key=where) from None
    problems: list[str] = []
    number = finite_number(value, where, problems)
    if number is None:
        raise InputError(problems[0], key=where)
    return number


def with_values(spec, values):
    """``spec`` (a scene's checked structure) with parameter values replaced
    (``load_scene(values=...)``, the command's ``--set``); a name that is not a parameter
    raises, with the closest one."""
    if not values:
        return spec
    params = dict(spec.parameters)
    for name, value in values.items():
        if name not in params:
            close = difflib.get_close_matches(str(name), list(params), n=1)
            raise InputError(f"values: {name!r} is not a parameter of the scene"
                             + (f"; did you mean {close[0]!r}?" if close else
                                f" (parameters: {', '.join(params) or 'none'})"),
                             key="values")
        params[name] = float(value)
    # numeric ones first, as the structure check orders them
    ordered = {k: v for k, v in params.items() if v is not None}
    ordered.update({k: v for k, v in params.items() if v is None})
    return replace(spec, parameters=ordered)
