"""Scene files: a system, its parameters and optional initial data, in TOML.

A scene (``DESIGN.md`` §3) looks like::

    name = "vertical rolling disk"
    description = "optional free text"
    coordinates = ["x", "y", "theta", "phi"]
    parameters = { m = 1.0, I1 = 0.5, I2 = 0.25, R = 1.0 }
    symbolic_parameters = []            # parameters without a numeric value
    lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"
    constraints = ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"]
    holonomic = []
    [initial]        # optional: a value for every coordinate and velocity
    x = 0.0
    ...
    [simulate]       # optional defaults: t_end, method, rtol, atol, step, max_step
    t_end = 10.0

Loading happens in layers, each of which reports every problem it finds at
once: the file itself (size, encoding, TOML syntax), the structure (keys,
types, names), the expressions (parsed with
:func:`nhham.system.expressions.parse_expression`, never evaluated as Python), the
system (:class:`nhham.system.System` checks the mechanics) and finally the
initial data against the constraints. Every message names the key path
(``parameters.m``, ``constraints[1]``, ``initial.x_dot``). Nothing the user
gave is silently changed.
"""

from __future__ import annotations

import difflib
import math
import os
import re
import tomllib
import unicodedata
from dataclasses import dataclass, field, fields
from functools import partial
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping

import sympy as sp

from nhham.autonomy import nonautonomous
from nhham.errors import InputError, ParseError, SceneError, key_of
from nhham.system.contacts import contacts_structure, parse_contacts
from nhham.system.expressions import RESERVED_NAMES, parse_expression
from nhham.system.initial import initial_residuals
from nhham.system.initial_solve import complete_initial, initial_entry, parse_initial
from nhham.system.scene_numbers import (
    finite_number,
    scene_number,
    toml_float,
    type_name,
    with_values,
)
from nhham.system.naming import TIME, acceleration_symbol, momentum_symbol, velocity_symbol
from nhham.system.steady import parse_steady, state_table, steady_structure

if TYPE_CHECKING:
    from nhham.system.description import System

__all__ = [
    "Scene",
    "SimulateOptions",
    "load_scene",
    "loads_scene",
    "MAX_SCENE_BYTES",
    "MIN_RTOL",
    "MAX_FIXED_STEPS",
    "simulate_option_problem",
    "scene_number",
]

#: Largest scene file accepted, checked before parsing.
MAX_SCENE_BYTES = 2 * 1024 * 1024

#: Smallest relative tolerance the adaptive methods honour in float64 (scipy raises a
#: smaller one to this): 100 machine epsilons.
MIN_RTOL = 100 * 2.0 ** -52

#: Most steps a fixed-step run may take (t_end / step): every step is stored.
MAX_FIXED_STEPS = 10**8

_TOP_KEYS = (
    "name", "description", "coordinates", "parameters", "symbolic_parameters",
    "lagrangian", "constraints", "holonomic", "initial", "simulate", "steady", "contacts",
    "forces", "dissipation", "inputs", "control",
)
_REQUIRED_KEYS = ("coordinates", "lagrangian")

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

    :func:`simulate_option_problem` holds these ranges (the command's options too).
    """

    t_end: float | None = None
    method: str | None = None
    rtol: float | None = None
    atol: float | None = None
    step: float | None = None
    max_step: float | None = None

    def given(self) -> dict:
        """The options the scene gave, as ``{key: value}``."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}


_SIMULATE_KEYS = tuple(f.name for f in fields(SimulateOptions))


@dataclass(frozen=True)
class Scene:
    """A loaded scene.

    Attributes
    ----------
    name : str
        The scene's ``name`` ("" if not given).
    description : str
        The scene's ``description`` ("" if not given).
    system : nhham.system.System
        The validated system.
    initial : mapping of str to float, or None
        Initial value of every coordinate and velocity (those left out of ``[initial]``
        solved from the constraints), or None: no ``[initial]``, or one that could not be
        completed (:meth:`checked_initial` raises why).
    simulate : SimulateOptions
        Simulation defaults (all None if the scene has no ``[simulate]``).
    source : str
        Where the scene came from (a path or ``"<string>"``).
    steady : nhham.system.steady.SteadyState or None
        The ``[steady]`` motion (expressions in the parameters), or None.
    contacts : tuple of nhham.system.contacts.ContactPoint
        The ``[contacts]`` points, where the constraints' forces act.
    control : mapping of str to sympy.Expr
        The ``[control]`` laws: each input as an expression in ``t``, the coordinates,
        velocities and parameters (empty when the scene gives none). ``simulate`` closes
        the loop with them (:meth:`System.closed_loop`).
    initial_given : nhham.system.initial_solve.InitialData or None
        ``[initial]`` as written (values by name, Newton's starting points).
    initial_solved : tuple of str
        The names left out of ``[initial]`` and solved from the constraints.
    initial_problem : InputError or None
        Why ``[initial]`` could not be completed (raised by :meth:`checked_initial`).
    values_set : mapping of str to float
        The parameter values given when loading (``values=``, ``--set``), replacing the
        scene's.
    """

    name: str
    description: str
    system: "System"
    initial: Mapping[str, float] | None
    simulate: SimulateOptions
    source: str
    steady: object = None
    contacts: tuple = ()
    control: Mapping = field(default_factory=lambda: MappingProxyType({}))
    initial_given: object = None
    initial_solved: tuple = ()
    initial_problem: Exception | None = None
    values_set: Mapping = field(default_factory=lambda: MappingProxyType({}))

    def checked_initial(self, project: bool = False) -> Mapping:
        """The initial state, completed and checked against the constraints.

        Parameters
        ----------
        project : bool, optional
            The state will be projected onto M_1 (``--project-initial``): given values
            off the constraints are not refused here.

        Raises
        ------
        SceneError
            The scene has no ``[initial]`` table.
        InputError
            A value left out could not be solved (see :mod:`nhham.system.initial_solve`),
            or the state violates the constraints (``InconsistentInitialDataError``,
            naming each and its residual).
        """
        if self.initial_given is None:
            raise SceneError(f"{self.source}: needs an [initial] table (the independent "
                             f"coordinates and velocities; the others are solved)")
        if self.initial_problem is not None:
            raise self.initial_problem
        if not project:
            initial_residuals(self)
        assert self.initial is not None
        return self.initial

    def steady_system(self) -> "System":
        """The system whose ``[steady]`` motion is linearised: the loop closed by the
        ``[control]`` laws (the system the scene's runs integrate), else its own.

        Raises
        ------
        InputError
            A law uses ``t`` (key ``control``): the closed loop then has no steady
            motion.
        """
        if not self.control:
            return self.system
        timed = sorted(u for u, law in self.control.items()
                       if TIME in sp.sympify(law).free_symbols)
        if timed:
            raise InputError(f"control.{timed[0]}: the law uses t, so the closed loop has no "
                             f"steady motion to linearise about (the open loop's (A, B): "
                             f"nhham.open_loop)", key="control")
        return self.system.closed_loop(dict(self.control))

    def simulate_options(self, **overrides) -> dict:
        """Keyword arguments for :func:`nhham.simulate` from the scene.

        ``t_span`` runs from 0 to the ``[simulate]`` table's ``t_end`` (10 if
        it gives none), ``y0`` is the ``[initial]`` table, and the table's
        ``method``, ``rtol``, ``atol``, ``step``, ``max_step`` follow; any
        keyword given here (``t_end`` too) replaces the scene's value; a ``method``
        other than the table's leaves out the table's ``rtol``, ``atol``, ``step`` and
        ``max_step`` (chosen for its method; ``simulate`` refuses the options a method
        does not take).

        >>> scene = load_scene("examples/rolling_disk.toml")       # doctest: +SKIP
        >>> result = nhham.simulate(scene.system, **scene.simulate_options(rtol=1e-6))
        ...                                                         # doctest: +SKIP

        Raises
        ------
        SceneError
            If the scene has no ``[initial]`` table.
        """
        y0 = self.checked_initial(project=bool(overrides.get("project_initial")))
        opts = self.simulate.given()
        if overrides.get("method", opts.get("method")) != opts.get("method"):
            opts = {k: v for k, v in opts.items()
                    if k not in ("rtol", "atol", "step", "max_step")}
        opts |= overrides
        t_end = float(opts.pop("t_end", 10.0))
        return {"t_span": (0.0, t_end), "y0": dict(y0), **opts}


# -------------------------------------------------------------------- load
def load_scene(path, *, check_initial: bool = True, drop_redundant: bool = False,
               values: Mapping | None = None) -> Scene:
    """Load a scene file.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (UTF-8, at most :data:`MAX_SCENE_BYTES` bytes; a UTF-8
        byte-order mark is accepted).
    check_initial : bool, optional
        Check that the initial data satisfy the constraints (default True).
    drop_redundant : bool, optional
        Passed to :class:`~nhham.system.System`: drop affine constraints that
        are combinations of the others instead of raising (default False).
    values : mapping of str to float, optional
        Parameter values replacing the scene's (a symbolic parameter gets one); a name
        that is not a parameter raises InputError (key ``values``).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file cannot be read, is too large, is not UTF-8 text, is empty,
        is not valid TOML, or has structural problems (all listed at once).
    ParseError
        An expression cannot be parsed (all such problems listed at once).
    ValidationError
        The system is mechanically invalid (raised by :class:`System`).
    InconsistentInitialDataError, MissingParameterValueError
        From the initial-data check, see :func:`check_initial`.
    """
    source = os.fspath(path)
    try:
        with open(path, "rb") as handle:
            # Read one byte past the limit rather than trusting the size on
            # disk (special files report 0).
            data = handle.read(MAX_SCENE_BYTES + 1)
    except OSError as exc:
        raise SceneError(f"{source}: cannot read scene file: {exc.strerror or exc}") from None
    if len(data) > MAX_SCENE_BYTES:
        raise SceneError(f"{source}: scene file too large (more than {MAX_SCENE_BYTES} bytes)")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(
            f"{source}: not a UTF-8 text file (invalid byte at offset {exc.start}); "
            f"is it a binary file?"
        ) from None
    return loads_scene(text, source=source, check_initial=check_initial,
                       drop_redundant=drop_redundant, values=values)


def loads_scene(text: str, source: str = "<string>", *, check_initial: bool = True,
                drop_redundant: bool = False, values: Mapping | None = None) -> Scene:
    """Load a scene from TOML text.

    Parameters
    ----------
    text : str
        The scene.
    source : str, optional
        Name used in error messages.
    check_initial : bool, optional
        Check that the initial data satisfy the constraints (default True).
    drop_redundant : bool, optional
        Passed to :class:`~nhham.system.System` (default False).
    values : mapping of str to float, optional
        As for :func:`load_scene`.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError, ParseError, ValidationError, InconsistentInitialDataError, MissingParameterValueError
        As for :func:`load_scene`.
    """
    data = _parse_toml(text, source)
    spec = with_values(_validate_structure(data, source), values)
    expressions = _parse_expressions(spec)
    system = _build_system(spec, expressions, drop_redundant)
    data = expressions.get("[initial]")
    initial, solved, problem = None, (), None
    if data is not None:
        try:
            state, solved = complete_initial(system, data)
            initial = MappingProxyType(state)
        except InputError as exc:  # raised where the initial data are used
            problem = exc
    scene = Scene(
        name=spec.name,
        description=spec.description,
        system=system,
        initial=initial,
        simulate=spec.simulate,
        source=source,
        steady=expressions.get("[steady]"),
        contacts=expressions.get("[contacts]", ()),
        control=MappingProxyType(expressions.get("[control]", {})),
        initial_given=data,
        initial_solved=solved,
        initial_problem=problem,
        values_set=MappingProxyType(dict(values or {})),
    )
    if check_initial and data is not None:
        scene.checked_initial()
    return scene


def _parse_toml(text, source) -> dict:
    """TOML text -> dict, with every failure as a SceneError."""
    if not isinstance(text, str):
        raise SceneError(f"{source}: expected scene text, got {type(text).__name__}")
    if len(text) > MAX_SCENE_BYTES:
        raise SceneError(f"{source}: scene too large (more than {MAX_SCENE_BYTES} characters)")
    if not text.strip():
        raise SceneError(f"empty scene: {source} contains no data")
    if "\x00" in text:
        raise SceneError(f"{source}: contains NUL bytes; is it a binary file?")
    try:
        data = tomllib.loads(text, parse_float=toml_float)
    except tomllib.TOMLDecodeError as exc:
        # The message carries tomllib's "(at line L, column C)".
        raise SceneError(f"{source}: TOML syntax error: {exc}") from None
    except (RecursionError, MemoryError):
        raise SceneError(f"{source}: TOML nested too deeply to read") from None
    except ValueError as exc:  # e.g. an integer with too many digits
        raise SceneError(f"{source}: TOML value cannot be read: {exc}") from None
    if not data:
        raise SceneError(f"empty scene: {source} contains only comments or blank lines")
    return data


# --------------------------------------------------------------- structure
@dataclass(frozen=True)
class _Spec:
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
    simulate: SimulateOptions
    steady: Mapping | None = None
    contacts: Mapping | None = None
    forces: Mapping | str | None = None   # a table by coordinate, or a 1-form
    dissipation: str | None = None
    inputs: tuple = ()
    control: Mapping | None = None


def _validate_structure(data: dict, source: str) -> _Spec:
    """Check keys, types and names; raise one SceneError listing every problem."""
    problems: list[str] = []
    _check_keys(data, "", _TOP_KEYS, _TOP_ALIASES, problems)
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
    if problems:
        raise _scene_error(source, problems)
    return _Spec(source, name, description, tuple(coordinates), parameters, lagrangian,
                 tuple(constraints), tuple(holonomic), initial, simulate, steady, contacts,
                 forces, dissipation, tuple(inputs), control)


def _scene_error(source: str, problems: list[str]) -> SceneError:
    if len(problems) == 1:
        message = f"{source}: {problems[0]}"
    else:
        message = f"{source}: {len(problems)} problems:\n" + "\n".join(f"  - {p}" for p in problems)
    error = SceneError(message, key=key_of(problems[0]))
    error.problems = tuple(problems)
    return error


def _key_path(prefix: str, key) -> str:
    """``prefix.key`` with the key quoted when it is not a bare TOML key."""
    text = key if isinstance(key, str) and BARE_KEY.fullmatch(key) else toml_string(str(key))
    return f"{prefix}.{text}" if prefix else text


def _check_keys(table: dict, prefix: str, known, aliases, problems) -> None:
    for key in table:
        if key in known:
            continue
        hint = aliases.get(key) or next(iter(difflib.get_close_matches(key, known, n=1)), None)
        suggestion = f"; did you mean {hint!r}?" if hint else f" (known keys: {', '.join(known)})"
        problems.append(f"{_key_path(prefix, key)}: unknown key{suggestion}")


# How a TOML value's type is called in messages; bool before int, which it subclasses.
def _optional_string(data, key, problems) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        problems.append(f"{key}: expected a string, got {type_name(value)}")
        return ""
    return value


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
        path = _key_path("parameters", key)
        if not _check_name(key, path, problems):
            continue
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
    for path, p in [(_key_path("parameters", p), p) for p in values] + [
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
    return state_table(value, coordinates, initial_entry(coordinates), problems,
                       section="initial", path=partial(_key_path, "initial"), required=False)


def _simulate_table(value, problems) -> SimulateOptions:
    if value is None:
        return SimulateOptions()
    if not isinstance(value, dict):
        problems.append(f"simulate: expected a table, got {type_name(value)}")
        return SimulateOptions()
    _check_keys(value, "simulate", _SIMULATE_KEYS, _SIMULATE_ALIASES, problems)
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
        number = finite_number(value[key], path, problems)
        if number is None:
            continue
        problem = simulate_option_problem(key, number, options.get("t_end"))
        if problem:
            problems.append(f"{path}: {problem}")
            continue
        options[key] = number
    return SimulateOptions(**options)


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


# ------------------------------------------------------------- expressions
def _symbol_table(spec: _Spec) -> dict:
    table = {}
    for q in spec.coordinates:
        sym = sp.Symbol(q)
        table[q] = sym
        table[velocity_symbol(sym).name] = velocity_symbol(sym)
    for p in spec.parameters:
        table[p] = sp.Symbol(p)
    return table


def _parse_expressions(spec: _Spec) -> dict:
    """Parse every expression; raise one ParseError listing every failure."""
    table = _symbol_table(spec)
    items = [("lagrangian", spec.lagrangian)]
    items += [(f"constraints[{i}]", c) for i, c in enumerate(spec.constraints)]
    items += [(f"holonomic[{i}]", g) for i, g in enumerate(spec.holonomic)]
    parsed, problems = {}, []
    for path, text in items:
        try:
            parsed[path] = parse_expression(text, table, where=path)
        except ParseError as exc:
            problems.append(str(exc) + _declare_hint(getattr(exc, "unknown_name", None),
                                                     spec.inputs))
    # an input named t is refused by System ("already the time"), not here
    timed = {**table, **{u: sp.Symbol(u) for u in spec.inputs}, "t": TIME}
    for name, text in (spec.control or {}).items():
        try:
            law = parse_expression(text, dict(table, t=TIME), where=f"control.{name}")
        except ParseError as exc:
            problems.append(str(exc))
        else:
            parsed.setdefault("[control]", {})[name] = law
    if isinstance(spec.forces, str):   # the 1-form Q_A dq^A in the differentials d<q>
        from nhham.system.description import differential_symbols

        ds = differential_symbols([sp.Symbol(q) for q in spec.coordinates])
        clash = sorted(d for d in ds if d in timed)
        try:
            if clash:
                raise ParseError(f"forces: {', '.join(clash)} is a name of the scene, not "
                                 f"only a differential; give forces as a table by "
                                 f"coordinate", key="forces")
            parsed["forces"] = parse_expression(spec.forces, {**timed, **ds}, where="forces")
        except ParseError as exc:
            problems.append(str(exc))
    for name, text in (spec.forces if isinstance(spec.forces, dict) else {}).items():
        try:
            parsed[f"forces.{name}"] = parse_expression(text, timed, where=f"forces.{name}")
        except ParseError as exc:
            problems.append(str(exc))
    if spec.dissipation is not None:
        try:
            parsed["dissipation"] = parse_expression(spec.dissipation, timed,
                                                     where="dissipation")
        except ParseError as exc:
            problems.append(str(exc))
    parsed["[initial]"] = parse_initial(spec.initial, spec.parameters, problems)
    steady, steady_problems = parse_steady(spec.steady, spec.parameters)
    problems.extend(steady_problems)
    if steady is not None:
        parsed["[steady]"] = steady
    parsed["[contacts]"], contact_problems = parse_contacts(
        spec.contacts, lambda text, where: parse_expression(text, table, where=where),
        len(spec.constraints), len(spec.holonomic))
    problems.extend(contact_problems)
    if problems:
        if len(problems) == 1:
            error = ParseError(problems[0], key=key_of(problems[0]))
        else:
            error = ParseError(f"{len(problems)} problems:\n"
                               + "\n".join(f"  - {p}" for p in problems), key=key_of(problems[0]))
        error.problems = tuple(problems)
        raise error
    return parsed


def _declare_hint(name: str | None, inputs=()) -> str:
    """Where an unknown name of a scene expression would be declared."""
    if name is None:
        return ""
    if name in inputs:
        return (" (an input may appear in the forces and the dissipation only, not in L or "
                "the constraints)")
    if name == "t":
        return nonautonomous("scene")
    if name.endswith("_ddot"):
        return " (accelerations may not appear in L or the constraints)"
    return (f" (a parameter must be declared: parameters = {{ {name} = <value> }} or "
            f"symbolic_parameters = [\"{name}\"])")


def _build_system(spec: _Spec, parsed: dict, drop_redundant: bool):
    # Imported here: system.py imports the expression parser, and a scene is
    # the only place that needs both.
    from nhham.system.description import System

    return System(
        coordinates=list(spec.coordinates),
        lagrangian=parsed["lagrangian"],
        constraints=[parsed[f"constraints[{i}]"] for i in range(len(spec.constraints))],
        holonomic=[parsed[f"holonomic[{i}]"] for i in range(len(spec.holonomic))],
        parameters=dict(spec.parameters),
        name=spec.name,
        drop_redundant=drop_redundant,
        forces=(parsed["forces"] if isinstance(spec.forces, str)
                else {q: parsed[f"forces.{q}"] for q in spec.forces or {}}),
        dissipation=parsed.get("dissipation"),
        inputs=list(spec.inputs),
    )


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


