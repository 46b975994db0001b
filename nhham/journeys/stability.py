"""Linearise a scene's steady motion: ``nhham linearize``.

The scene's ``[steady]`` motion (an equilibrium or a steady motion, its entries
expressions in the parameters) is checked to lie on M_1 and to be steady, and the
constrained dynamics is linearised there in independent coordinates on M_1, neutral
directions divided out (:mod:`nhham.numerics.linearization`): state matrix, eigenvalues,
verdict. With ``[control]`` laws the loop they close is linearised (each law checked to
give its input's ``[steady]`` value there), and the open loop's (A, B) beside it. Small
systems (n <= :data:`EXACT_MAX_N`) get the exact Jacobian
(:mod:`nhham.lagrangian.jacobian`) in the same chart, eigenvalues at :data:`EXACT_DIGITS`
digits; larger ones, and every point of a sweep or a study, the complex-step Jacobian. A
sweep moves one parameter (the steady motion with it) and locates where an eigenvalue
crosses the imaginary axis (:func:`~nhham.numerics.crossings.crossings_many`).

A study (``nhham sweep --what linearize``) linearises its points with
:func:`steady_states` and :func:`law_mismatch` of this module, as the command's sweep
does.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any

import numpy as np

from nhham.errors import InputError, NhhamWarning
from nhham.journeys.answer import Answer, as_scene, capture_warnings, quiet_steps
from nhham.lagrangian.jacobian import EXACT_DIGITS

__all__ = ["linearize", "linearize_scene", "steady_linearization", "open_loop",
           "check_steady_table", "symmetry_generator", "relative_generator",
           "steady_states", "law_mismatch", "METHODS", "EXACT_MAX_N", "EXACT_DIGITS"]

#: How the Jacobian is formed: ``auto`` (exact for n <= :data:`EXACT_MAX_N`),
#: ``exact`` (symbolic, implicit differentiation), ``complex-step``.
METHODS = ("auto", "exact", "complex-step")

#: Relative distance of a ``[control]`` law's value from its input's ``[steady]`` value
#: above which the motion is not a steady motion of the closed loop (one point and many).
LAW_TOL = 1e-9

#: Largest number of coordinates for which ``auto`` uses the exact Jacobian.
EXACT_MAX_N = 4



def linearize(scene, *args, method: str = "auto", sweep=None, model=None, steps=None,
              steady=None, **kwargs) -> Any:
    """The stability of a scene's ``[steady]`` motion (``nhham linearize``).

    Parameters
    ----------
    scene : Scene or str
        With a ``[steady]`` table.
    method : {"auto", "exact", "complex-step"}
    sweep : (str, array) or None
        A parameter's name and its values: the eigenvalues along it and the crossings of
        the imaginary axis.
    model : NumericModel, optional
        A model of ``scene.steady_system()`` to reuse.
    steps : Steps, optional
    steady : mapping, optional
        The ``[steady]`` table, replacing the scene's (a System's: its only one), keyed by
        nhham's names, dynamicsymbols ``q(t)``, ``q(t).diff(t)`` or the speeds of the
        mechanics model it came from; only the independent entries, the others solved at
        the parameter values, and again at each value of a ``sweep``
        (:func:`~nhham.system.state_keys.steady_table`).

    Returns
    -------
    Answer
        (A :class:`~nhham.numerics.linearization.Linearization` for the deprecated form
        ``linearize(model, state, ...)``.) ``data``: the ``result`` of ``nhham linearize
        --json`` (``matrix``,
        ``eigenvalues``, ``stable``, ``chart``, ``loop``, ``open_loop``, ``sweep``...);
        ``payload``: ``linearization``, ``open_loop`` and ``sweep`` (a
        :class:`~nhham.numerics.steady_sweep.Sweep` or None).

    Raises
    ------
    InputError
        No ``[steady]`` table; a motion that is not steady or not on M_1; a ``[control]``
        law that does not give its input's ``[steady]`` value there (key ``control``).

    Examples
    --------
    >>> from nhham import loads_scene
    >>> from nhham.journeys import linearize
    >>> scene = loads_scene(\'\'\'
    ... coordinates = ["x"]
    ... parameters = { m = 2.0, k = 8.0 }
    ... lagrangian = "m*x_dot**2/2 - k*x**2/2"
    ... constraints = []
    ... [steady]
    ... x = 0.0
    ... x_dot = 0.0
    ... \'\'\')
    >>> answer = linearize(scene)
    >>> sorted((round(re, 12), round(im, 12)) for re, im in answer.data["eigenvalues"])
    [(0.0, -2.0), (0.0, 2.0)]
    >>> answer.data["stable"], answer.data["method"]   # a centre: not decided by A alone
    (None, 'exact')
    """
    from nhham.numerics.codegen import numeric_model
    from nhham.numerics.model import NumericModel
    from nhham.numerics.steady_sweep import sweep_steady
    from nhham.render.linearize import linearize_data, linearize_text

    if isinstance(scene, NumericModel):   # the model-level function, renamed
        from nhham.numerics.linearization import linearize as at_state

        warnings.warn("nhham.linearize(model, state) is now "
                      "nhham.numerics.linearization.linearize; nhham.linearize takes a scene "
                      "(the old form goes in the next release)", DeprecationWarning,
                      stacklevel=2)
        return at_state(scene, *args, **kwargs)
    scene = as_scene(scene, steady=steady, check_initial=False)
    steps = quiet_steps(steps)
    if method not in METHODS:
        raise InputError(f"linearize: method {method!r} is not one of {', '.join(METHODS)}",
                         key="method")
    with capture_warnings() as caught:
        with steps.step("numeric model (generated kernels)"):
            # a law in t has no steady motion: said before a missing [steady] table
            system = scene.steady_system()
            check_steady_table(scene)
            model = numeric_model(system) if model is None else model
        with steps.step(f"linearise ({method})"
                        + (" the closed loop ([control])" if scene.control else "")
                        + (f", sweep over {sweep[0]}" if sweep is not None else "")):
            generator = symmetry_generator(scene, system, model)
            lin = steady_linearization(scene, system, model, method, generator=generator)
            swept = None
            if sweep is not None:
                name, values = sweep
                swept = sweep_steady(model, scene.steady.values, name, values,
                                     independent=lin.chart, family_of=scene.steady.family,
                                     generator=generator)
        for u in () if swept is None else swept.unlocated:
            warnings.warn(f"--sweep: between {u.low:.10g} and {u.high:.10g}: {u.reason}; no "
                          f"crossing reported there", NhhamWarning)
        opened = None
        if scene.control:
            with steps.step(f"linearise ({method}) the open loop"):
                opened = open_loop(scene, method, independent=lin.chart)
    data = linearize_data(scene, lin, opened, swept)
    title = scene.name or str(scene.source)
    return Answer("linearize", data,
                  functools.partial(linearize_text, title, scene, lin, swept, opened),
                  warnings=tuple(caught),
                  payload={"linearization": lin, "open_loop": opened, "sweep": swept},
                  system=scene.system)


def open_loop(scene, method: str = "auto", model=None, independent=None):
    """The open loop of a scene: its system with the inputs held at their ``[steady]``
    values, (A, B) of x' = A x + B u, whatever ``[control]`` says.

    Parameters
    ----------
    scene, method : as for :func:`linearize`
    model : NumericModel, optional
        A model of ``scene.system``.
    independent : sequence of str, optional
        The chart (default: chosen at the state).

    Returns
    -------
    Linearization

    Examples
    --------
    A torque u holds a damped pendulum at x0 = asin(u0): x'' = -sin(x) + u - c x', so
    A = [[0, 1], [-cos(x0), -c]] and B = [[0], [1]]:

    >>> from nhham import loads_scene, open_loop
    >>> scene = loads_scene('''
    ... coordinates = ["x"]
    ... parameters = { u0 = 0.5, c = 0.1 }
    ... lagrangian = "x_dot**2/2 + cos(x)"
    ... inputs = ["u"]
    ... forces = { x = "u" }
    ... dissipation = "c*x_dot**2/2"
    ... [steady]
    ... u = "u0"
    ... x = "asin(u0)"
    ... x_dot = 0.0
    ... ''')
    >>> lin = open_loop(scene)
    >>> lin.matrix.round(6).tolist(), lin.input_matrix.tolist()
    ([[0.0, 1.0], [-0.866025, -0.1]], [[0.0], [1.0]])
    """
    from nhham.numerics.codegen import numeric_model

    check_steady_table(scene)
    model = numeric_model(scene.system) if model is None else model
    return steady_linearization(scene, scene.system, model, method, independent,
                                generator=symmetry_generator(scene, scene.system, model))


def check_steady_table(scene) -> None:
    if scene.steady is None:
        raise InputError(f"{scene.source}: linearize needs a [steady] table with a value (or an "
                         f"expression in the parameters) for every coordinate and velocity",
                         key="steady")


def symmetry_generator(scene, system, model, check: bool = True):
    """The scene's ``[symmetry]`` generator, checked to leave L, the constraints and the
    forces of ``system`` invariant, for the numeric layer (None without the table).

    Parameters
    ----------
    scene : Scene
    system : System
        The system linearised (``scene.steady_system()``).
    model : NumericModel
        Of ``system`` (the parameters' order of its kernels).
    check : bool, optional
        False: the checks were made by the caller (a study's preparation; its workers
        build the generator again from the scene).

    Returns
    -------
    nhham.numerics.relative.Generator or None

    Raises
    ------
    InputError
        (key ``symmetry``) the generator does not leave them invariant.

    Examples
    --------
    >>> from nhham import loads_scene, numeric_model
    >>> from nhham.journeys.stability import symmetry_generator
    >>> scene = loads_scene('''
    ... coordinates = ["x", "y", "theta"]
    ... lagrangian = "(x_dot**2 + y_dot**2 + theta_dot**2)/2"
    ... constraints = ["y_dot*cos(theta) - x_dot*sin(theta)"]
    ... [symmetry]
    ... x = "-y"
    ... y = "x"
    ... theta = "1"
    ... ''')
    >>> symmetry_generator(scene, scene.system, numeric_model(scene.system)).text()
    '(-y) d/dx + (x) d/dy + (1) d/dtheta'
    """
    if scene.symmetry is None:
        return None
    return relative_generator(system, model, scene.symmetry, check=check)


def relative_generator(system, model, symmetry, check: bool = True):
    """A symmetry's generator for :func:`nhham.numerics.linearization.linearize` (its
    ``generator``): how Python code declares what a scene's ``[symmetry]`` does.

    Parameters
    ----------
    system : System
    model : NumericModel
        Of ``system``.
    symmetry : Symmetry or mapping of str to (str or sympy.Expr)
        xi by coordinate name (strings go through the safe parser, in the coordinates
        and parameters).
    check : bool, optional
        Check the invariance of L, the constraints and the forces (default).

    Returns
    -------
    nhham.numerics.relative.Generator

    Raises
    ------
    InputError
        (key ``symmetry``) not invariant, or an entry that is not a coordinate.

    Examples
    --------
    The vertical rolling disk rolling in a circle about the origin (radius R phi'/w at the
    turning rate w = 0.5; R = 1): a relative equilibrium of the rotation about the
    vertical, the wheel angle moving besides (cyclic); every direction is neutral:

    >>> from nhham import models, numeric_model
    >>> from nhham.journeys.stability import relative_generator
    >>> from nhham.numerics.linearization import linearize
    >>> disk = models.rolling_disk()
    >>> model = numeric_model(disk, backend="numpy")
    >>> turn = relative_generator(disk, model, {"x": "-y", "y": "x", "theta": "1"})
    >>> state = dict(x=0.0, y=-4.0, theta=0.0, phi=0.0, x_dot=2.0, y_dot=0.0,
    ...              theta_dot=0.5, phi_dot=2.0)
    >>> lin = linearize(model, state, generator=turn)
    >>> lin.relative["rate"], lin.relative["group"], lin.coordinates
    (0.5, ('x', 'y', 'theta'), ())
    """
    import sympy as sp

    from nhham.numerics.relative import Generator
    from nhham.system.symmetry import Symmetry, parse_symmetry

    if not isinstance(symmetry, Symmetry):
        names = [q.name for q in system.coordinates]
        raw = {k: v if isinstance(v, str) else str(sp.sympify(v)) for k, v in symmetry.items()}
        unknown = [k for k in raw if k not in names]
        if unknown:
            raise InputError(f"symmetry.{unknown[0]}: not a coordinate ({', '.join(names)})",
                             key="symmetry")
        parsed, problems = parse_symmetry(raw, names, [p.name for p in system.parameters])
        if problems:
            raise InputError(problems[0], key="symmetry")
        symmetry = parsed
    checked = _checked(system, symmetry) if check else None
    parameters = dict(zip(model.parameter_names, model.parameter_values))
    coordinates = set(system.coordinates)
    constant = not any(e.free_symbols & coordinates for e in symmetry.field(system.coordinates))
    return Generator(tuple(symmetry.to_toml_table().items()),
                     symmetry.numeric([q.name for q in system.coordinates], parameters),
                     tuple(parameters.values()), constant,
                     () if checked is None else tuple((label, d.method)
                                                      for label, d in checked.decisions))


@functools.lru_cache(maxsize=8)
def _checked(system, symmetry):
    """The invariance checks of ``symmetry`` on ``system`` (a System is hashed by identity),
    once per pair: a study or a sweep asks at every point."""
    from nhham.lagrangian.relative_symmetry import check_symmetry

    return check_symmetry(system, symmetry)


def steady_linearization(scene, system, model, method: str = "auto", independent=None,
                         generator=None):
    """The linearisation of ``system`` (``model``) about the scene's ``[steady]`` motion at
    the model's parameter values: its ``[control]`` laws checked there, the forces
    checked to be defined, the dependent coordinates and velocities solved, and the
    Jacobian exact where ``method`` says (``auto``: n <= :data:`EXACT_MAX_N`).

    Parameters
    ----------
    scene : Scene
    system : System
        ``scene.steady_system()`` (the closed loop) or ``scene.system`` (the open loop).
    model : NumericModel
        Of ``system``, at the parameter values wanted.
    method : {"auto", "exact", "complex-step"}
    independent : sequence of str, optional
        The chart (default: chosen at the state).
    generator : nhham.numerics.relative.Generator, optional
        The scene's checked ``[symmetry]`` (:func:`symmetry_generator`): a motion along
        it is linearised in co-moving variables (the complex-step Jacobian of X - w Xi).

    Returns
    -------
    Linearization
    """
    from nhham.numerics.linearization import linearize
    from nhham.numerics.steady_sweep import steady_state
    from nhham.system.force_checks import check_forces_at

    values = scene.steady.values(model.parameters)
    _check_laws_at(scene, system, model, values)
    check_forces_at(system, values, where="the [steady] motion")
    model, state = steady_state(model, values, independent)
    lin = linearize(model, state, family=scene.steady.family(model.parameters),
                    independent=independent, generator=generator)
    turning = lin.relative is not None and lin.relative["turning"]
    if turning and method == "exact":
        raise InputError("method exact (--exact): the [steady] motion is a relative "
                         "equilibrium (it moves along the [symmetry] generator), whose state "
                         "matrix (of X - w Xi) is formed by the complex step only; leave the "
                         "method to auto or use --numeric", key="method")
    if not turning and (method == "exact" or (method == "auto" and system.n <= EXACT_MAX_N)):
        lin = _exact(scene, system, model, lin)
    return lin


def _check_laws_at(scene, system, model, values) -> None:
    """Each [control] law closed in ``system`` gives its input's [steady] value (when the
    table gives one) at the steady state: else the motion is not one of the closed loop."""
    import sympy as sp

    closed = {u: law for u, law in scene.control.items() if u not in model.input_names
              and u in values}
    if not closed or system is scene.system:
        return
    point = {sp.Symbol(k): sp.Float(v) for k, v in {**model.parameters, **values}.items()}
    for u, law in sorted(closed.items()):
        value = complex(sp.sympify(law).xreplace(point).evalf())
        want = values[u]
        if abs(value - want) > LAW_TOL * max(1.0, abs(want)):
            raise InputError(f"control.{u}: the law gives {value.real:.10g} at the [steady] "
                             f"motion, where [steady] gives {u} = {want:.10g}: the motion is "
                             f"not a steady motion of the closed loop", key="control")


def _exact(scene, system, model, lin):
    """The same linearisation with the exact Jacobian in the numeric chart."""
    import mpmath
    import numpy as np
    import sympy as sp

    from nhham.lagrangian.jacobian import exact_jacobian, exact_number
    from nhham.numerics.linearization import linearization_result

    params = {p.name: exact_number(v) for p, v in system.parameter_values.items()}
    params.update({u: exact_number(model.parameters[u]) for u in model.input_names})
    point = {sp.Symbol(k): v for k, v in params.items()}
    state = {}
    for name, expr in scene.steady.expressions.items():
        if name not in model.names:   # an input's steady value
            continue
        value = sp.sympify(expr).xreplace(point)
        state[name] = value if value.is_number else exact_number(float(value.evalf()))
    ej = exact_jacobian(system, state, params, lin.chart)
    keep = [i for i, s in enumerate(ej.chart) if s not in lin.neutral]
    A = ej.matrix.extract(keep, keep)
    names = [ej.chart[i] for i in keep]
    for label in lin.neutral:
        if not label.startswith("d/d"):
            continue
        p = sp.Symbol(label[3:])   # a tangent of the steady family, divided out exactly
        t = sp.Matrix([sp.diff(scene.steady.expressions[s], p).xreplace(point) for s in names])
        j = max(range(len(names)), key=lambda i: abs(float(t[i])))
        T = sp.eye(len(names))
        T[:, j] = t
        B = T.LUsolve(A * T)
        rest = [i for i in range(len(names)) if i != j]
        A, names = B.extract(rest, rest), [names[i] for i in rest]
    with mpmath.workdps(EXACT_DIGITS + 10):
        M = mpmath.matrix([[mpmath.mpmathify(sp.N(e, EXACT_DIGITS + 10)) for e in A.row(i)]
                           for i in range(A.rows)]) if A.rows else None
        ev = []
        if A.rows:
            E = mpmath.eig(M, left=False, right=False)
            # mpmath returns (E, ER, EL) for a 1 x 1 matrix
            ev = [complex(z) for z in (E[0] if isinstance(E, tuple) else E)]
    Af = np.array([[float(sp.N(e, 20)) for e in A.row(i)] for i in range(A.rows)]).reshape(
        A.rows, A.rows)
    scale = max(1.0, float(np.abs(Af).max(initial=0.0)))
    return linearization_result(
        Af, tuple(names), "exact",
        f"exact symbolic Jacobian (implicit differentiation of the saddle-point system, "
        f"exact arithmetic on the parameter values as decimals), eigenvalues by mpmath at "
        f"{EXACT_DIGITS} digits", ej.chart,
        np.array([[float(sp.N(e, 20)) for e in ej.matrix.row(i)] for i in range(ej.matrix.rows)]),
        lin.neutral, lin.dependent, dict(lin.state), dict(lin.residuals),
        lin.acceleration_residual, tol=10.0 ** (-EXACT_DIGITS + 5) * scale, eigenvalues=ev,
        exact_matrix=A, inputs=lin.inputs, B=lin.input_matrix,
        relative=None if lin.relative is None else dict(lin.relative))


def steady_states(scene, model, points) -> tuple:
    """The ``[steady]`` states at many parameter points, as a study linearises them.

    Parameters
    ----------
    scene : Scene
    model : NumericModel
        Of ``scene.steady_system()``.
    points : mapping of str to ndarray, shape (N,)
        Swept parameter -> its values (the others at the model's values).

    Returns
    -------
    (Y, P, bad, missed)
        ``Y`` (N, 2n) the steady states, ``P`` (N, parameters) every parameter's value
        (inputs at their ``[steady]`` values), ``bad`` (N,) where an entry of ``[steady]``
        is not a finite real number, ``missed`` (N,) where a ``[control]`` law does not
        give its input's ``[steady]`` value (:func:`law_mismatch`): no steady motion of the
        closed loop there, which ``nhham linearize`` refuses.
    """
    names = model.parameter_names
    N = len(next(iter(points.values()))) if points else 1
    P = np.tile(np.asarray(model.parameter_values, dtype=float), (N, 1))
    for k, v in points.items():
        P[:, names.index(k)] = v
    params = {k: P[:, i] for i, k in enumerate(names)}
    steady = scene.steady.arrays(params)
    for u in model.input_names:
        if u in steady:
            P[:, names.index(u)] = steady[u]
    Y = np.column_stack([steady[s] for s in model.names])
    bad = ~np.isfinite(Y).all(axis=1) | ~np.isfinite(P).all(axis=1)
    missed = law_mismatch(scene, model, Y, P, steady) & ~bad
    Y[bad] = 0.0
    P[bad] = np.where(np.isfinite(P[bad]), P[bad], 0.0)
    return Y, P, bad, missed


def law_mismatch(scene, model, Y, P, steady) -> np.ndarray:
    """Where a ``[control]`` law closed in ``model`` does not give its input's ``[steady]``
    value (relative :data:`LAW_TOL`, as :func:`steady_linearization` checks one point).

    Parameters
    ----------
    Y : ndarray, shape (N, 2n)
    P : ndarray, shape (N, parameters)
    steady : mapping of str to ndarray, shape (N,)
        The ``[steady]`` entries at the points.

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    import sympy as sp

    closed = {u: law for u, law in scene.control.items() if u not in model.input_names
              and u in steady}
    out = np.zeros(len(Y), dtype=bool)
    if not closed:
        return out
    names = list(model.parameter_names) + list(model.names)
    columns = np.column_stack([P, Y])
    for u, law in sorted(closed.items()):
        f = sp.lambdify([sp.Symbol(n) for n in names], sp.sympify(law), modules="numpy")
        with np.errstate(all="ignore"):
            value = np.broadcast_to(np.asarray(f(*columns.T), dtype=complex), out.shape)
        want = np.asarray(steady[u], dtype=float)
        out |= ~(np.abs(value - want) <= LAW_TOL * np.maximum(1.0, np.abs(want)))
    return out


def linearize_scene(scene, method: str = "auto", sweep=None, model=None) -> tuple:
    """Deprecated: ``(linearization, sweep)`` of :func:`linearize`'s payload.

    Use ``nhham.linearize(scene, ...)``; its ``payload`` holds both (this name goes in the
    next release).

    Examples
    --------
    >>> import warnings
    >>> from nhham import loads_scene, linearize_scene
    >>> scene = loads_scene('coordinates = ["x"]\\nlagrangian = "x_dot**2/2 - x**2/2"\\n'
    ...                     '[steady]\\nx = 0.0\\nx_dot = 0.0\\n')
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", DeprecationWarning)
    ...     lin, swept = linearize_scene(scene)
    >>> sorted(float(round(z.imag, 12)) for z in lin.eigenvalues), swept
    ([-1.0, 1.0], None)
    """
    warnings.warn("nhham.linearize_scene is deprecated: use nhham.linearize(scene) (its "
                  "payload['linearization'] and payload['sweep'])", DeprecationWarning,
                  stacklevel=2)
    answer = linearize(scene, method=method, sweep=sweep, model=model)
    return answer.payload["linearization"], answer.payload["sweep"]
