"""The structure of a scene file: keys, types and names, before any expression is read.

The second layer of loading a scene (:mod:`nhham.system.scene`): the TOML tables are
checked key by key (unknown keys with a hint, types, valid and distinct names, the
ranges of the ``[simulate]`` options) and every problem is collected and raised once as
a :class:`~nhham.errors.SceneError` naming its key path. The result,
:class:`SceneSpec`, holds the scene's content still unparsed; the expressions are
parsed next.
"""

from __future__ import annotations

import difflib
import math
import re
import unicodedata
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from functools import partial
from typing import Any, Mapping

import sympy as sp

from nhham.errors import InputError, SceneError, key_of
from nhham.system.contacts import contacts_structure
from nhham.system.expressions import RESERVED_NAMES
from nhham.system.initial_solve import initial_entry
from nhham.system.naming import acceleration_symbol, momentum_symbol, velocity_symbol
from nhham.system.scene_keys import EVERY_COMMAND, SCENE_KEYS, top_level_keys
from nhham.system.scene_numbers import (
    expression_value,
    finite_number,
    number_or_expression,
    type_name,
)
from nhham.system.steady import state_table, steady_structure
from nhham.system.symmetry import symmetry_structure

__all__ = ["SceneSpec", "SimulateOptions", "validate_structure", "scene_error",
           "simulate_option_problem", "simulate_options_at", "key_path", "check_keys",
           "toml_string", "table_of", "MIN_RTOL", "MAX_FIXED_STEPS", "BARE_KEY",
           "READ_BY_COMMANDS"]

#: Smallest relative tolerance the adaptive methods honour in float64 (scipy raises a
#: smaller one to this): 100 machine epsilons.
MIN_RTOL = 100 * 2.0 ** -52

#: Most steps a fixed-step run may take (t_end / step): every step is stored.
MAX_FIXED_STEPS = 10**8

# One home for the keys: the scene format's reference (docs/scene.rst is made from it).
_TOP_KEYS = top_level_keys()
_REQUIRED_KEYS = tuple(k.name for k in SCENE_KEYS if k.required)

#: The tables only some commands read (``[simulate]`` by simulate and bench, ``[steady]``
#: by linearize...): their problems are kept with the scene and raised when a command reads
#: the table, so that a command that does not read it runs (:class:`nhham.system.scene.
#: UnreadTable`). The others make the system: every command needs them.
READ_BY_COMMANDS = tuple(k.name for k in SCENE_KEYS
                         if k.name in _TOP_KEYS and k.read_by != EVERY_COMMAND)

# Names people reach for that difflib would not match (a hint, never applied).
_TOP_ALIASES = {
    "L": "lagrangian", "coords": "coordinates", "q": "coordinates",
    "params": "parameters", "initial_conditions": "initial", "ic": "initial",
    "nonholonomic": "constraints", "sim": "simulate", "simulation": "simulate",
    "force": "forces", "loads": "forces", "controls": "inputs", "feedback": "control",
    "rayleigh": "dissipation",
}
_SIMULATE_ALIASES = {"dt": "step", "h": "step", "t_final": "t_end", "tmax": "t_end",
                     "t_max": "t_end", "integrator": "method"}

# Names generated elsewhere in nhham for the i-th Lagrange multiplier.
_MULTIPLIER_NAME = re.compile(r"lambda_\d+")
BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class SimulateOptions:
    """Defaults for ``nhham simulate`` given in a scene's ``[simulate]`` table.

    Every attribute is ``None`` when the scene does not give it.

    Attributes
    ----------
    t_end : float or None
        Final time (> 0).
    method : str or None
        Integration method name (checked by the simulator, not here).
    rtol, atol : float or None
        Relative (:data:`MIN_RTOL` <= rtol < 1) and absolute (> 0) tolerances.
    step : float or None
        Fixed step size dt for fixed-step methods (0 < step <= t_end, at most
        :data:`MAX_FIXED_STEPS` steps).
    max_step : float or None
        Largest step an adaptive method may take (> 0).
    symmetry, then : tuple of str or None
        The reduction of method ``hamiltonized`` (coordinate names, as ``nhham
        hamiltonize --symmetry``, ``--then`` take them).

    :func:`simulate_option_problem` holds these ranges (the command's options too).
    """

    t_end: float | None = None
    method: str | None = None
    rtol: float | None = None
    atol: float | None = None
    step: float | None = None
    max_step: float | None = None
    symmetry: tuple | None = None
    then: tuple | None = None

    def given(self) -> dict:
        """The options the scene gave, as ``{key: value}``."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}


_SIMULATE_KEYS = tuple(f.name for f in fields(SimulateOptions))
#: Keys of ``[simulate]`` that name coordinates (the others are a method or numbers).
_NAME_LISTS = ("symmetry", "then")


# --------------------------------------------------------------- structure
@dataclass(frozen=True)
class SceneSpec:
    """The validated, still unparsed content of a scene."""

    source: str
    name: str
    description: str
    coordinates: tuple
    parameters: dict  # name -> float or None, numeric ones first
    lagrangian: str
    constraints: tuple
    holonomic: tuple
    initial: Mapping | None
    simulate: Mapping   # as given: numbers, expression strings and the method's name
    steady: Mapping | None = None
    contacts: Mapping | None = None
    forces: Mapping | str | None = None   # a table by coordinate, or a 1-form
    dissipation: str | None = None
    inputs: tuple = ()
    control: Mapping | None = None
    symmetry: Mapping | None = None
    gauge: tuple | None = None   # gauge conditions chi(q) = 0 of a singular L
    unread: Mapping = field(default_factory=dict)   # table -> its problems (READ_BY_COMMANDS)


def validate_structure(data: dict, source: str) -> SceneSpec:
    """Check keys, types and names; raise one SceneError listing every problem of the
    tables every command reads (the others' problems are kept in ``unread``)."""
    problems: list[str] = []
    check_keys(data, "", _TOP_KEYS, _TOP_ALIASES, problems)
    for key in _REQUIRED_KEYS:
        if key not in data:
            problems.append(f"{key}: required key is missing")

    name = _optional_string(data, "name", problems)
    description = _optional_string(data, "description", problems)
    coordinates = _name_list(data, "coordinates", problems, required=True)
    values = _parameter_table(data.get("parameters"), problems)
    symbolic = _name_list(data, "symbolic_parameters", problems)
    lagrangian = _optional_string(data, "lagrangian", problems) if "lagrangian" in data else ""
    constraints = _string_list(data, "constraints", problems)
    holonomic = _string_list(data, "holonomic", problems)

    parameters = dict(values)
    for i, p in enumerate(symbolic):
        if p in parameters:
            problems.append(f"symbolic_parameters[{i}]: {p!r} is also given a value in parameters")
        parameters.setdefault(p, None)
    _check_name_clashes(coordinates, values, symbolic, problems)

    inputs = _name_list(data, "inputs", problems)
    forces = (data["forces"] if isinstance(data.get("forces"), str)   # a 1-form
              else _string_table(data, "forces", problems))
    dissipation = _optional_string(data, "dissipation", problems) or None
    control = _string_table(data, "control", problems)
    for key in control or {}:
        if key not in inputs:
            problems.append(f"control.{key}: not an input (a control law gives an input, "
                            f"declared in inputs = [...], as an expression)")

    initial = _initial_table(data.get("initial"), coordinates, problems)
    simulate = _simulate_table(data.get("simulate"), problems)
    steady = steady_structure(data.get("steady"), coordinates, problems, inputs)
    contacts = contacts_structure(data.get("contacts"), problems)
    symmetry = symmetry_structure(data.get("symmetry"), coordinates, problems)
    gauge = _gauge_table(data.get("gauge"), problems)
    problems, unread = split_unread(problems)
    if problems:
        raise scene_error(source, problems)
    if "initial" in unread:
        initial = None
    tables: dict[str, Any] = dict(simulate=simulate, steady=steady, contacts=contacts,
                                  control=control, symmetry=symmetry, gauge=gauge)
    tables.update({t: ({} if t == "simulate" else None) for t in unread if t in tables})
    return SceneSpec(source, name, description, tuple(coordinates), parameters, lagrangian,
                     tuple(constraints), tuple(holonomic), initial, tables["simulate"] or {},
                     tables["steady"], tables["contacts"], forces, dissipation,
                     tuple(inputs), tables["control"], tables["symmetry"], tables["gauge"],
                     MappingProxyType(unread))


def table_of(problem: str) -> str | None:
    """The top-level key a problem names (``simulate`` for ``simulate.t_end: ...``)."""
    key = key_of(problem)
    return None if key is None else re.split(r"[.\[]", key, maxsplit=1)[0]


def split_unread(problems) -> tuple[list, dict]:
    """(problems of the tables every command reads, {table: its problems} for the tables
    of :data:`READ_BY_COMMANDS`)."""
    fatal: list = []
    unread: dict = {}
    for p in problems:
        table = table_of(p)
        if table in READ_BY_COMMANDS:
            unread.setdefault(table, []).append(p)
        else:
            fatal.append(p)
    return fatal, {t: tuple(ps) for t, ps in unread.items()}


def scene_error(source: str, problems: list[str]) -> SceneError:
    if len(problems) == 1:
        message = f"{source}: {problems[0]}"
    else:
        message = f"{source}: {len(problems)} problems:\n" + "\n".join(f"  - {p}" for p in problems)
    error = SceneError(message, key=key_of(problems[0]))
    error.problems = tuple(problems)
    return error


def key_path(prefix: str, key) -> str:
    """``prefix.key`` with the key quoted when it is not a bare TOML key."""
    text = key if isinstance(key, str) and BARE_KEY.fullmatch(key) else toml_string(str(key))
    return f"{prefix}.{text}" if prefix else text


def check_keys(table: dict, prefix: str, known, aliases, problems) -> None:
    for key in table:
        if key in known:
            continue
        hint = aliases.get(key) or next(iter(difflib.get_close_matches(key, known, n=1)), None)
        suggestion = f"; did you mean {hint!r}?" if hint else f" (known keys: {', '.join(known)})"
        problems.append(f"{key_path(prefix, key)}: unknown key{suggestion}")


# How a TOML value's type is called in messages; bool before int, which it subclasses.
def _optional_string(data, key, problems) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        problems.append(f"{key}: expected a string, got {type_name(value)}")
        return ""
    return value


def _gauge_table(value, problems) -> tuple | None:
    """A raw ``[gauge]`` table: ``conditions``, a non-empty array of expression strings
    (None without a table)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append("gauge: expected a table with conditions = [\"expression\", ...] "
                        "(gauge conditions chi(q) = 0)")
        return None
    check_keys(value, "gauge", ("conditions",), {}, problems)
    items = value.get("conditions")
    if not isinstance(items, list) or not items:
        problems.append("gauge.conditions: expected a non-empty array of expression strings "
                        "(each a gauge condition chi(q) = 0)")
        return None
    for i, item in enumerate(items):
        if not isinstance(item, str):
            problems.append(f"gauge.conditions[{i}]: expected a string, got {type_name(item)}")
    return tuple(items)


def _string_list(data, key, problems) -> list[str]:
    """An optional array of strings (empty when absent)."""
    value = data.get(key, [])
    if not isinstance(value, list):
        problems.append(f"{key}: expected an array of strings, got {type_name(value)}")
        return []
    good = []
    for i, item in enumerate(value):
        if isinstance(item, str):
            good.append(item)
        else:
            problems.append(f"{key}[{i}]: expected a string, got {type_name(item)}")
    return good


def _string_table(data, key, problems) -> dict | None:
    """An optional table of ``name = "expression"`` (None when absent)."""
    value = data.get(key)
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append(f"{key}: expected a table of name = \"expression\", got "
                        f"{type_name(value)}")
        return None
    good = {}
    for name, item in value.items():
        if isinstance(item, str):
            good[name] = item
        elif isinstance(item, (int, float)) and not isinstance(item, bool):
            good[name] = repr(item)
        else:
            problems.append(f"{key}.{name}: expected an expression string or a number, got "
                            f"{type_name(item)}")
    return good


def _name_list(data, key, problems, required=False) -> list[str]:
    """An array of distinct valid names."""
    if required and key in data and data[key] == []:
        problems.append(f"{key}: at least one name is needed")
    names = _string_list(data, key, problems)
    seen = set()
    good = []
    for i, name in enumerate(names):
        if not _check_name(name, f"{key}[{i}]", problems):
            continue
        if name in seen:
            problems.append(f"{key}[{i}]: duplicate name {name!r}")
            continue
        seen.add(name)
        good.append(name)
    return good


def _check_name(name: str, path: str, problems) -> bool:
    """Whether ``name`` can be a coordinate or parameter name; record why not."""
    if not name.isidentifier():
        problems.append(f"{path}: {name!r} is not a valid name (letters, digits, underscores; "
                        f"not starting with a digit)")
        return False
    if unicodedata.normalize("NFKC", name) != name:
        problems.append(f"{path}: {name!r} is not in Unicode normal form NFKC "
                        f"(write {unicodedata.normalize('NFKC', name)!r})")
        return False
    if name.startswith("__"):
        problems.append(f"{path}: {name!r} is not allowed (names may not start with '__')")
        return False
    if name in RESERVED_NAMES:
        problems.append(f"{path}: {name!r} is reserved (a function or constant)")
        return False
    if _MULTIPLIER_NAME.fullmatch(name):
        problems.append(f"{path}: {name!r} is reserved for Lagrange multipliers")
        return False
    return True


def _parameter_table(value, problems) -> dict:
    """``parameters = {name = number}`` -> {name: float}."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        hint = (" (for parameters without a value use symbolic_parameters = [...])"
                if isinstance(value, list) else "")
        problems.append(f"parameters: expected a table of name = number, got "
                        f"{type_name(value)}{hint}")
        return {}
    result = {}
    for key, item in value.items():
        path = key_path("parameters", key)
        if not _check_name(key, path, problems):
            continue
        if isinstance(item, str):   # an expression in the others, evaluated when loading
            number = number_or_expression(item, path, problems)
        else:
            number = finite_number(item, path, problems)
        if number is not None:
            result[key] = number
    return result


def _check_name_clashes(coordinates, values, symbolic, problems) -> None:
    """Coordinates, parameters and generated names must all be distinct."""
    generated = {}
    for q in coordinates:
        sym = sp.Symbol(q)
        generated[velocity_symbol(sym).name] = f"the velocity of coordinate {q!r}"
        generated[acceleration_symbol(sym).name] = f"the acceleration of coordinate {q!r}"
        generated[momentum_symbol(sym).name] = f"the momentum of coordinate {q!r}"
    for i, q in enumerate(coordinates):
        if q in generated:
            problems.append(f"coordinates[{i}]: {q!r} clashes with {generated[q]}")
    coordinate_set = set(coordinates)
    for path, p in [(key_path("parameters", p), p) for p in values] + [
        (f"symbolic_parameters[{i}]", p) for i, p in enumerate(symbolic)
    ]:
        if p in coordinate_set:
            problems.append(f"{path}: {p!r} is also a coordinate")
        elif p in generated:
            problems.append(f"{path}: {p!r} clashes with {generated[p]}")


def _initial_table(value, coordinates, problems):
    """``[initial]``: a finite number, an expression in the parameters or a coordinate's
    ``{ guess = number }`` for some coordinates and velocities (the others are solved:
    :mod:`nhham.system.initial_solve`)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append(f"initial: expected a table, got {type_name(value)}")
        return None
    return state_table(value, coordinates, initial_entry(), problems,
                       section="initial", path=partial(key_path, "initial"), required=False)


def _simulate_table(value, problems) -> dict:
    """``[simulate]`` as given: the method's name, and numbers or expression strings in
    the parameters for the others (evaluated and range-checked by
    :func:`simulate_options_at`)."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        problems.append(f"simulate: expected a table, got {type_name(value)}")
        return {}
    check_keys(value, "simulate", _SIMULATE_KEYS, _SIMULATE_ALIASES, problems)
    options = {}
    for key in _SIMULATE_KEYS:
        if key not in value:
            continue
        path = f"simulate.{key}"
        if key == "method":
            if isinstance(value[key], str) and value[key].strip():
                options[key] = value[key]
            else:
                problems.append(f"{path}: expected a method name, got {type_name(value[key])}"
                                if not isinstance(value[key], str) else f"{path}: empty method name")
            continue
        if key in _NAME_LISTS:
            names = value[key]
            if isinstance(names, list) and names and all(
                    isinstance(x, str) and x.strip() for x in names):
                options[key] = tuple(x.strip() for x in names)
            else:
                problems.append(f"{path}: expected a list of coordinate names, got "
                                f"{type_name(names)}")
            continue
        number = number_or_expression(value[key], path, problems)
        if number is not None:
            options[key] = number
    return options


def simulate_options_at(raw: Mapping, values: dict) -> tuple[SimulateOptions, list]:
    """The ``[simulate]`` options at the parameter values (``values``: name -> float or
    None), each expression evaluated and every value range-checked
    (:func:`simulate_option_problem`); returns (options, problems).

    >>> simulate_options_at({"t_end": "7*pi/Omega", "rtol": 1e-9}, {"Omega": 7.0})
    (SimulateOptions(t_end=3.141592653589793, method=None, rtol=1e-09, atol=None, step=None, max_step=None, symmetry=None, then=None), [])
    """
    options, problems = {}, []
    for key in _SIMULATE_KEYS:
        if key not in raw:
            continue
        if key == "method" or key in _NAME_LISTS:
            options[key] = raw[key]
            continue
        path = f"simulate.{key}"
        try:
            number = expression_value(raw[key], values, path)
        except InputError as exc:
            problems.append(str(exc))
            continue
        problem = simulate_option_problem(key, number, options.get("t_end"))
        if problem:
            written = f" (= {raw[key]})" if isinstance(raw[key], str) else ""
            problems.append(f"{path}: {problem}{written}")
            continue
        options[key] = number
    return SimulateOptions(**options), problems


def simulate_option_problem(key: str, value: float, t_end: float | None = None) -> str | None:
    """Why ``value`` cannot be the simulation option ``key``, or None.

    One home for the ranges of ``t_end``, ``rtol``, ``atol``, ``step`` and
    ``max_step``, shared by a scene's ``[simulate]`` table and the command's options.

    Parameters
    ----------
    key : str
        ``t_end``, ``rtol``, ``atol``, ``step`` or ``max_step``.
    value : float
    t_end : float, optional
        The final time, against which a ``step`` is checked when known.

    >>> simulate_option_problem("rtol", 1e-16)
    'must be at least 2.22e-14 (100 machine epsilons: float64 methods do not reach less), got 1e-16'
    >>> simulate_option_problem("step", 1e300, t_end=10.0) is not None
    True
    """
    if not math.isfinite(value):
        return f"expected a finite number, got {value!r}"
    if value <= 0:
        return f"must be positive, got {value!r}"
    if key == "rtol" and value < MIN_RTOL:
        return (f"must be at least {MIN_RTOL:.3g} (100 machine epsilons: float64 methods do "
                f"not reach less), got {value!r}")
    if key == "rtol" and value >= 1:
        return f"must be below 1 (a relative tolerance), got {value!r}"
    if key == "step" and t_end is not None:
        if value > t_end:
            return f"must not exceed the time span t_end = {t_end:g}, got {value!r}"
        if t_end / value > MAX_FIXED_STEPS:
            return (f"{value!r} makes {t_end / value:.3g} steps up to t_end = {t_end:g}; at most "
                    f"{MAX_FIXED_STEPS:.0e} (every step is stored)")
    return None


def toml_string(text: str) -> str:
    """A TOML basic string."""
    out = []
    for ch in text:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch in "\b\t\n\f\r":
            out.append({"\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


