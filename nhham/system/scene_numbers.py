"""The numbers of a scene: what a scene accepts as a number, in its TOML and on the
command line (``--set``), and parameter values given when it loads.

A number is a TOML integer or float (not a boolean), finite, and within double
precision: ``1e-400``, which tomllib would read as 0 without a word, is refused.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from dataclasses import replace

from nhham.errors import InputError

__all__ = ["finite_number", "toml_float", "scene_number", "with_values", "type_name"]

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
