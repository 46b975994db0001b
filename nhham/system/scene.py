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

import dataclasses
import os
import tomllib
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping

import sympy as sp

from nhham.errors import InputError, ParseError, SceneError, key_of
from nhham.system.contacts import parse_contacts
from nhham.system.expressions import parse_expression
from nhham.system.initial import initial_residuals
from nhham.system.initial_solve import InitialData, complete_initial, parse_initial
from nhham.system.naming import TIME, velocity_symbol
from nhham.system.scene_numbers import (
    resolve_parameters,
    scene_number,
    toml_float,
    with_values,
)
from nhham.system.scene_structure import (
    BARE_KEY,
    MAX_FIXED_STEPS,
    MIN_RTOL,
    SceneSpec,
    SimulateOptions,
    scene_error,
    simulate_option_problem,
    simulate_options_at,
    split_unread,
    toml_string,
    validate_structure,
)
from nhham.system.steady import parse_steady
from nhham.system.symmetry import parse_symmetry

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
    "toml_string",
    "BARE_KEY",
    "UnreadTable",
]

#: Largest scene file accepted, checked before parsing.
MAX_SCENE_BYTES = 2 * 1024 * 1024

class UnreadTable:
    """A table of the scene with problems, in place of its content: reading it raises
    them (a :class:`~nhham.errors.SceneError` naming the key), so that only the commands
    that read the table refuse the scene (``[simulate]`` stops simulate, not classify).

    Examples
    --------
    >>> from nhham import loads_scene
    >>> scene = loads_scene('''
    ... coordinates = ["x"]
    ... lagrangian = "x_dot**2/2"
    ... [simulate]
    ... t_end = -1.0
    ... ''', source="s.toml")
    >>> scene.system.n                      # classify, derive... read the system
    1
    >>> scene.simulate.t_end                # simulate reads [simulate]
    Traceback (most recent call last):
    ...
    nhham.errors.SceneError: s.toml: simulate.t_end: must be positive, got -1.0
    """

    __slots__ = ("error",)

    def __init__(self, error: InputError):
        object.__setattr__(self, "error", error)

    def __getattr__(self, name):
        if name.startswith("__"):   # copy, pickle: not a read of the table
            raise AttributeError(name)
        raise self.error

    def _refuse(self, *args, **kwargs):
        raise self.error

    __bool__ = __iter__ = __len__ = __getitem__ = __contains__ = _refuse

    def __repr__(self):
        return f"UnreadTable({str(self.error)!r})"


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
    symmetry : nhham.system.symmetry.Symmetry or None
        The ``[symmetry]`` generator xi (its invariance is checked where it is used:
        ``nhham linearize``), or None.
    gauge : tuple of sympy.Expr
        The ``[gauge]`` conditions chi(q) = 0 of a singular Lagrangian (() without one).

    A table that only some commands read (``[initial]``, ``[simulate]``, ``[steady]``,
    ``[symmetry]``, ``[contacts]``, ``[control]``, ``[gauge]``) and that has problems is an
    :class:`UnreadTable` here: the problems are raised when it is read.

    Examples
    --------
    A bead on a line driven along y' = x': y' is left out of ``[initial]`` and solved.

    >>> from nhham import loads_scene
    >>> scene = loads_scene('''
    ... name = "bead"
    ... coordinates = ["x", "y"]
    ... lagrangian = "(x_dot**2 + y_dot**2)/2"
    ... constraints = ["y_dot - x_dot"]
    ... [initial]
    ... x = 0.0
    ... y = 0.0
    ... x_dot = 3.0
    ... ''')
    >>> scene.name, scene.source, scene.initial_solved, scene.initial["y_dot"]
    ('bead', '<string>', ('y_dot',), 3.0)
    >>> scene.simulate_options()["t_span"]
    (0.0, 10.0)
    """

    name: str
    description: str
    system: "System"
    initial: "Mapping[str, float] | UnreadTable | None"
    simulate: "SimulateOptions | UnreadTable"
    source: str
    steady: object = None
    contacts: tuple = ()
    control: "Mapping | UnreadTable" = field(default_factory=lambda: MappingProxyType({}))
    initial_given: object = None
    initial_solved: tuple = ()
    initial_problem: Exception | None = None
    values_set: Mapping = field(default_factory=lambda: MappingProxyType({}))
    symmetry: object = None
    gauge: object = ()

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
        assert isinstance(self.initial, Mapping)   # completed: an unread one raised above
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

    Examples
    --------
    >>> from nhham import load_scene
    >>> scene = load_scene("examples/rolling_disk.toml", values={"m": 2.0})
    >>> scene.name, scene.system.n, scene.system.m, scene.values_set
    ('vertical rolling disk', 4, 2, mappingproxy({'m': 2.0}))
    >>> load_scene("examples/no_such_scene.toml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.SceneError: examples/no_such_scene.toml: cannot read scene file: ...
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

    Examples
    --------
    >>> from nhham import loads_scene
    >>> scene = loads_scene('''
    ... coordinates = ["x"]
    ... parameters = { k = 4.0 }
    ... lagrangian = "x_dot**2/2 - k*x**2/2"
    ... ''')
    >>> scene.system, scene.system.parameter_values, scene.initial
    (System(n=1, m=0, holonomic=0), mappingproxy({k: 4.0}), None)
    >>> loads_scene('coordinates = ["x"]', source="bad.toml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.SceneError: bad.toml: ...
    """
    data = _parse_toml(text, source)
    spec = with_values(validate_structure(data, source), values)
    problems: list[str] = []
    spec = dataclasses.replace(spec, parameters=resolve_parameters(spec.parameters, problems))
    if problems:
        raise scene_error(source, problems)
    expressions, unparsed = _parse_expressions(spec)
    unread = dict(spec.unread)
    simulate, problems = simulate_options_at(spec.simulate, spec.parameters)
    if problems:
        unread["simulate"] = tuple(unread.get("simulate", ())) + tuple(problems)
    # a table's structure and its expressions are checked in turn: one kind of error each
    unread_tables = {t: UnreadTable(scene_error(source, list(ps))) for t, ps in unread.items()}
    unread_tables.update({t: UnreadTable(_parse_error(list(ps))) for t, ps in unparsed.items()})
    system = _build_system(spec, expressions, drop_redundant)
    given: InitialData | UnreadTable | None = expressions.get("[initial]")
    initial: Mapping | UnreadTable | None = None
    solved: tuple = ()
    problem: Exception | None = None
    if "initial" in unread_tables:
        given = initial = unread_tables["initial"]
        problem = unread_tables["initial"].error
    elif isinstance(given, InitialData) and system.regular_lagrangian:
        # a singular L's [initial] is completed on the chain's M_f, by simulate
        try:
            state, solved = complete_initial(system, given)
            initial = MappingProxyType(state)
        except InputError as exc:  # raised where the initial data are used
            problem = exc

    def table(name, key, default=None):
        return unread_tables.get(name, expressions.get(key, default))

    scene = Scene(
        name=spec.name,
        description=spec.description,
        system=system,
        initial=initial,
        simulate=unread_tables.get("simulate", simulate),
        source=source,
        steady=table("steady", "[steady]"),
        contacts=table("contacts", "[contacts]", ()),
        control=unread_tables.get("control",
                                  MappingProxyType(expressions.get("[control]", {}))),
        initial_given=given,
        initial_solved=solved,
        initial_problem=problem,
        values_set=MappingProxyType(dict(values or {})),
        symmetry=table("symmetry", "[symmetry]"),
        gauge=table("gauge", "[gauge]", ()),
    )
    if check_initial and given is not None and system.regular_lagrangian:
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


# ------------------------------------------------------------- expressions
def _symbol_table(spec: SceneSpec) -> dict:
    table = {}
    for q in spec.coordinates:
        sym = sp.Symbol(q)
        table[q] = sym
        table[velocity_symbol(sym).name] = velocity_symbol(sym)
    for p in spec.parameters:
        table[p] = sp.Symbol(p)
    return table


def _parse_expressions(spec: SceneSpec) -> tuple[dict, dict]:
    """Parse every expression; raise one ParseError listing every failure of what every
    command reads; return (parsed, {table: problems} of the tables only some read)."""
    table = _symbol_table(spec)
    items = [("lagrangian", spec.lagrangian)]
    items += [(f"constraints[{i}]", c) for i, c in enumerate(spec.constraints)]
    items += [(f"holonomic[{i}]", g) for i, g in enumerate(spec.holonomic)]
    parsed, problems = {}, []
    # the time t may appear in L and the constraints (DESIGN.md §2), unless a parameter
    # is named t
    scene_table = table if "t" in table else dict(table, t=TIME)
    for path, text in items:
        try:
            parsed[path] = parse_expression(text, scene_table, where=path)
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
    if spec.gauge is not None:
        gauge_table = {q: sp.Symbol(q) for q in spec.coordinates}
        gauge_table.update({p: sp.Symbol(p) for p in spec.parameters})
        conditions = []
        for i, text in enumerate(spec.gauge):
            try:
                conditions.append(parse_expression(text, gauge_table,
                                                   where=f"gauge.conditions[{i}]"))
            except ParseError as exc:
                problems.append(str(exc))
        parsed["[gauge]"] = tuple(conditions)
    symmetry, symmetry_problems = parse_symmetry(spec.symmetry, spec.coordinates,
                                                 spec.parameters)
    problems.extend(symmetry_problems)
    if symmetry is not None:
        parsed["[symmetry]"] = symmetry
    parsed["[contacts]"], contact_problems = parse_contacts(
        spec.contacts, lambda text, where: parse_expression(text, table, where=where),
        len(spec.constraints), len(spec.holonomic))
    problems.extend(contact_problems)
    problems, unread = split_unread(problems)
    if problems:
        raise _parse_error(problems)
    return parsed, unread


def _parse_error(problems: list) -> ParseError:
    """One ParseError listing every problem (its key: the first one's)."""
    if len(problems) == 1:
        error = ParseError(problems[0], key=key_of(problems[0]))
    else:
        error = ParseError(f"{len(problems)} problems:\n"
                           + "\n".join(f"  - {p}" for p in problems), key=key_of(problems[0]))
    error.problems = tuple(problems)
    return error


def _declare_hint(name: str | None, inputs=()) -> str:
    """Where an unknown name of a scene expression would be declared."""
    if name is None:
        return ""
    if name in inputs:
        return (" (an input may appear in the forces and the dissipation only, not in L or "
                "the constraints)")
    if name.endswith("_ddot"):
        return " (accelerations may not appear in L or the constraints)"
    return (f" (a parameter must be declared: parameters = {{ {name} = <value> }} or "
            f"symbolic_parameters = [\"{name}\"])")


def _build_system(spec: SceneSpec, parsed: dict, drop_redundant: bool):
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

