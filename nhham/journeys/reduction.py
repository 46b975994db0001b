"""Reduce a Chaplygin scene to its shape space and look for Chaplygin's multiplier:
``nhham reduce`` and ``nhham hamiltonize``.

:func:`reduce` gives the reduced data of an abelian Chaplygin system
(:mod:`nhham.lagrangian.chaplygin`) with the check that the reduced field lifted back is
P(xi_L); :func:`hamiltonize` decides whether a conformal factor makes the reduced system
Hamiltonian (:mod:`nhham.hamiltonian.hamiltonization`).
"""

from __future__ import annotations

import functools

from nhham.journeys.answer import Answer, as_scene, quiet_steps

__all__ = ["reduce", "hamiltonize", "reduction_of", "connection_warnings"]


def reduction_of(system, *, symmetry=None, then=None, level=None, steps=None):
    """The first Chaplygin step, and a second one when ``then`` or ``level`` is given.

    Parameters
    ----------
    system : System
    symmetry : sequence of str, optional
        The first step's symmetry coordinates.
    then : sequence of str, optional
        Shape coordinates to reduce next, by the constraints left on the shape space, or by
        their momentum level when ``level`` names them.
    level : mapping of str to str or number, optional
        Momentum levels p_c = value (only 0); its names are reduced when ``then`` is None.
    steps : Steps, optional

    Returns
    -------
    ChaplyginReduction or ChaplyginStage

    Examples
    --------
    >>> from nhham import System
    >>> red = reduction_of(System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...                           ["z_dot - y*x_dot", "x_dot - y_dot"]), symmetry=["z"],
    ...                    then=["x"])
    >>> red.shape, red.symmetry
    ((y,), (z, x))
    """
    from nhham.lagrangian.chaplygin import chaplygin_reduction
    from nhham.lagrangian.chaplygin_stages import reduce_again

    steps = quiet_steps(steps)
    with steps.step("Chaplygin reduction, and its check against P(xi_L)"):
        red = chaplygin_reduction(system, symmetry)
    if then is None and level:
        then = list(level)
    if then:
        what = f"on the level {', '.join(f'p_{c} = {v}' for c, v in level.items())}" \
            if level else "by the constraints left on the shape space"
        with steps.step(f"second step: {', '.join(then)} {what}, and its check"):
            red = reduce_again(red, list(then), level=level)
    return red


def reduce(scene, *, symmetry=None, then=None, level=None, steps=None) -> Answer:
    """The Chaplygin reduction of a scene (``nhham reduce``).

    Parameters
    ----------
    scene : Scene, System or str
    symmetry : sequence of str, optional
        The symmetry coordinates (default: found among the cyclic ones).
    then, level : optional
        A second step (:func:`reduction_of`): its coordinates, and their momentum levels.
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: ``shape_coordinates``, ``symmetry_coordinates``, ``connection`` (A with
        s' = -A r'), ``reduced_lagrangian``, ``momenta`` (J), ``curvature`` (B^a),
        ``gyroscopic`` (J B r'), ``accelerations``, ``reconstruction``, ``check``,
        ``forces``, ``shape_constraints``, ``level`` and ``stages`` (every step; the other
        keys describe the last);
        ``failure`` when the lifted field is not P(xi_L) (a defect to report).

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys.reduction import reduce
    >>> answer = reduce(models.nonholonomic_particle())
    >>> answer.data["symmetry_coordinates"], answer.data["check"]["agrees"]
    (['z'], True)
    """
    from nhham.render.reduction import reduce_latex, reduce_text

    scene = as_scene(scene)
    red = reduction_of(scene.system, symmetry=symmetry, then=then, level=level, steps=steps)
    data = red.to_dict()
    failure = None if red.check.value else (
        "the reduced field lifted back differs from P(xi_L); please report this scene as a bug")
    title = scene.name or str(scene.source)
    return Answer("reduce", data, lambda: reduce_text(title, data),
                  latex=functools.partial(reduce_latex, title, data), failure=failure,
                  warnings=connection_warnings(scene, red),
                  payload={"reduction": red}, system=scene.system)


def connection_warnings(scene, red) -> tuple:
    """A warning where the scene's own motion ([steady], [initial]) lies where the
    connection is singular (a factor of A's denominators vanishes there: the reduced data
    do not describe that motion), naming the factor and the other symmetry coordinates.

    Examples
    --------
    >>> from nhham import loads_scene
    >>> scene = loads_scene('''
    ... coordinates = ["x", "y", "z"]
    ... lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
    ... constraints = ["sin(x)*z_dot - y_dot"]
    ... [initial]
    ... x = 0.0
    ... y = 0.0
    ... z = 0.0
    ... x_dot = 1.0
    ... y_dot = 0.0
    ... z_dot = 0.0
    ... ''')
    >>> print(reduce(scene, symmetry=["z"]).warnings[0])    # doctest: +NORMALIZE_WHITESPACE
    the connection is singular at the [initial] state: sin(x) = 0 there (z' = -A r' is not
    solved there); the reduction does not describe that motion: choose other symmetry
    coordinates with --symmetry (the constraints also solve for: y)
    """
    import sympy as sp

    from nhham.lagrangian.chaplygin import singular_factors, symmetry_choices

    factors = singular_factors(red.connection, red.shape)
    if not factors:
        return ()
    values = {p.name: v for p, v in scene.system.parameter_values.items()}
    states = []
    try:
        if scene.steady is not None:
            states.append(("[steady] motion", scene.steady.values(values)))
    except Exception:  # noqa: BLE001 - an unreadable table is the reading command's to report
        pass
    try:
        if scene.initial is not None:
            states.append(("[initial] state", dict(scene.initial)))
    except Exception:  # noqa: BLE001
        pass
    out = []
    for where, state in states:
        point = {sp.Symbol(k): v for k, v in {**values, **state}.items()}
        zero = [f for f in factors if abs(complex(f.xreplace(point).evalf())) <= 1e-9]
        if not zero:
            continue
        names = ", ".join(str(s) for s in red.symmetry)
        others = [", ".join(g) for g in symmetry_choices(scene.system)
                  if set(g) != {str(s) for s in red.symmetry}]
        out.append(f"the connection is singular at the {where}: "
                   f"{', '.join(f'{f} = 0' for f in zero)} there ({names}' = -A r' is not "
                   f"solved there); the reduction does not describe that motion: choose "
                   f"other symmetry coordinates with --symmetry"
                   + (f" (the constraints also solve for: {'; '.join(others)})" if others
                      else ""))
    return tuple(out)


def hamiltonize(scene, *, symmetry=None, then=None, level=None, steps=None) -> Answer:
    """Whether a Chaplygin scene is Hamiltonian after a change of time
    (``nhham hamiltonize``).

    Parameters
    ----------
    scene : Scene, System or str
    symmetry : sequence of str, optional
    then, level : optional
        A second step (:func:`reduction_of`); on a momentum level the answer is about the
        motion on that level only.
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: ``hamiltonizable``, ``conformal_factor`` (f with d(f Omega_nh) = 0),
        ``invariant_measure_density`` (f^(k-1)), ``divergence``, ``theta``,
        ``jacobiator_before``, ``jacobiator_after``, ``obstruction``,
        ``shape_coordinates``, ``symmetry_coordinates``, ``variables``, ``hamiltonian``,
        the reduction's ``reduction_check``, ``level`` and ``stages``.

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys.reduction import hamiltonize
    >>> answer = hamiltonize(models.nonholonomic_particle())
    >>> answer.data["hamiltonizable"], answer.data["conformal_factor"]
    (True, '1/sqrt(y**2 + 1)')
    """
    from nhham.errors import InputError
    from nhham.hamiltonian.hamiltonization import hamiltonize as find
    from nhham.render.reduction import hamiltonize_latex, hamiltonize_text

    scene = as_scene(scene)
    steps = quiet_steps(steps)
    red = reduction_of(scene.system, symmetry=symmetry, then=then, level=level, steps=steps)
    if red.constraints.rows:
        # Omega_nh on T*S has no room for them: the reduced motion is not the one of L_c
        raise InputError("hamiltonize: constraints are left on the shape space ("
                         + ", ".join(red.to_dict()["shape_constraints"]) + " = 0); reduce "
                         "by them with then (--then)", key="then")
    with steps.step("theta ^ Omega_nh = -d Omega_nh, the factor and the Jacobiators"):
        found = find(red, part=steps.part)
    data = found.to_dict()
    reduced = red.to_dict()
    data["reduction_check"] = reduced["check"]
    data["level"], data["stages"] = reduced["level"], reduced["stages"]
    warnings = connection_warnings(scene, red) + (() if found.divergence in (None, 0) else (
        f"div(f^(k-1) X) = {found.divergence} is not zero: the measure is not invariant "
        f"(please report this scene)",))
    title = scene.name or str(scene.source)
    return Answer("hamiltonize", data, lambda: hamiltonize_text(title, data),
                  latex=functools.partial(hamiltonize_latex, title, data), warnings=warnings, payload={"hamiltonization": found, "reduction": red},
                  system=scene.system)
