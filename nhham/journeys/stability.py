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
:func:`~nhham.journeys.steady.sweep_reference` and
:func:`~nhham.journeys.steady.steady_batch`, as the command's sweep
(:func:`sweep_scene`) does.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any

import numpy as np

from nhham.errors import InputError, NhhamWarning
from nhham.journeys.answer import Answer, as_scene, capture_warnings, quiet_steps
from nhham.journeys.steady import (EXACT_MAX_N, law_mismatch, steady_batch,
                                   steady_linearization, steady_states, sweep_reference)
from nhham.lagrangian.jacobian import EXACT_DIGITS

__all__ = ["linearize", "linearize_scene", "steady_linearization", "open_loop",
           "check_steady_table", "symmetry_generator", "relative_generator",
           "steady_states", "law_mismatch", "sweep_reference", "steady_batch", "sweep_scene",
           "METHODS", "EXACT_MAX_N", "EXACT_DIGITS"]

#: How the Jacobian is formed: ``auto`` (exact for n <= :data:`EXACT_MAX_N`),
#: ``exact`` (symbolic, implicit differentiation), ``complex-step``.
METHODS = ("auto", "exact", "complex-step")


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
    if not scene.system.regular_lagrangian:   # the chain's motion on M_f in T*Q
        from nhham.journeys.singular_motion import linearize_singular

        if sweep is not None or method == "complex-step" or model is not None:
            what = ("sweep" if sweep is not None else "model" if model is not None
                    else "method complex-step (--numeric)")
            raise InputError(f"{what}: not built for a singular Lagrangian (linearize takes "
                             f"its equilibrium on M_f, exactly)", key=what.split()[0])
        return linearize_singular(scene, steps=steps)
    if method not in METHODS:
        raise InputError(f"linearize: method {method!r} is not one of {', '.join(METHODS)}",
                         key="method")
    with capture_warnings() as caught:
        with steps.step("numeric model (generated kernels)"):
            # a law in t has no steady motion: said before a missing [steady] table
            system = scene.steady_system()
            check_steady_table(scene)
            # numpy answers a linearisation sooner than the compiler: the library is
            # built in the background (and handed over at exit) for later runs
            model = numeric_model(system, background=True) if model is None else model
        with steps.step(f"linearise ({method})"
                        + (" the closed loop ([control])" if scene.control else "")
                        + (f", sweep over {sweep[0]}" if sweep is not None else "")):
            generator = symmetry_generator(scene, system, model)
            lin = steady_linearization(scene, system, model, method, generator=generator)
            swept = None
            if sweep is not None:
                name, values = sweep
                swept = sweep_scene(scene, system, model, name, values, generator=generator)
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
    model = numeric_model(scene.system, background=True) if model is None else model
    return steady_linearization(scene, scene.system, model, method, independent,
                                generator=symmetry_generator(scene, scene.system, model))


def check_steady_table(scene) -> None:
    if scene.steady is None:
        raise InputError(f"{scene.source}: linearize needs a [steady] table with a value (or an "
                         f"expression in the parameters) for every coordinate and velocity",
                         key="steady")


def symmetry_generator(scene, system, model, check: bool = True, conserved: bool = False):
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
    conserved : bool, optional
        With ``check=False``: the caller found the symmetry's momentum conserved
        (``Generator.momentum`` not None).

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
    return relative_generator(system, model, scene.symmetry, check=check, conserved=conserved)


def relative_generator(system, model, symmetry, check: bool = True,
                       conserved: bool = False):
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
        Check the invariance of L, the constraints and the forces (default), and whether
        the symmetry's momentum is conserved.
    conserved : bool, optional
        Without the checks: whether the momentum is conserved (decided by the caller).

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
    field = symmetry.field(system.coordinates)
    constant = not any(e.free_symbols & coordinates for e in field)
    if checked is not None:
        momentum = checked.momentum
    else:   # the caller decided whether it is conserved (a study's preparation)
        momentum = sum((sp.diff(system.lagrangian, v) * e
                        for v, e in zip(system.velocities, field)), sp.S.Zero) \
            if conserved else None
    return Generator(tuple(symmetry.to_toml_table().items()),
                     symmetry.numeric([q.name for q in system.coordinates], parameters),
                     tuple(parameters.values()), constant,
                     () if checked is None else tuple((label, d.method)
                                                      for label, d in checked.decisions),
                     _momentum_function(system, momentum, parameters))


def _momentum_function(system, momentum, parameters):
    """``J(Q, V, P) -> (K,)`` in numpy (complex welcome) from the conserved momentum's
    expression, None without one."""
    if momentum is None:
        return None
    import sympy as sp

    q, v = list(system.coordinates), list(system.velocities)
    p = [sp.Symbol(k) for k in parameters]
    f = sp.lambdify([q, v, p], momentum, modules="numpy")
    values = np.array([np.nan if x is None else float(x) for x in parameters.values()])

    def J(Q, V, P=None):
        K = np.atleast_2d(Q).shape[0]
        rows = np.broadcast_to(values if P is None else np.atleast_2d(P), (K, values.size))
        return np.broadcast_to(f(list(np.atleast_2d(Q).T), list(np.atleast_2d(V).T),
                                 list(rows.T)), (K,))

    return J


@functools.lru_cache(maxsize=8)
def _checked(system, symmetry):
    """The invariance checks of ``symmetry`` on ``system`` (a System is hashed by identity),
    once per pair: a study or a sweep asks at every point."""
    from nhham.lagrangian.relative_symmetry import check_symmetry

    return check_symmetry(system, symmetry)


def sweep_scene(scene, system, model, name, values, generator=None):
    """``nhham linearize --sweep``: the scene's ``[steady]`` motion along one parameter,
    the reference decided at the first, middle and last values and every value (and
    every value the crossing finder asks for) linearised as a study's points are
    (:func:`sweep_reference`, :func:`steady_batch`).

    Returns
    -------
    nhham.numerics.steady_sweep.Sweep
    """
    from nhham.numerics.steady_sweep import check_swept, probe_values, sweep_batches

    check_swept(model, name)
    grid = np.asarray(values, dtype=float)
    if grid.size == 0:
        raise InputError(f"--sweep: no values of {name!r} to sweep", key="--sweep")
    choice, _ = sweep_reference(scene, system, model,
                                [{name: v} for v in probe_values(grid)], generator)

    def batch_at(vals):
        return steady_batch(scene, model, choice, {name: np.asarray(vals, dtype=float)},
                            generator, build=False)[0]

    return sweep_batches(name, grid, batch_at, choice.coordinates)


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
