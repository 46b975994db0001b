"""Integrate a scene's constrained dynamics: ``nhham simulate``.

The run starts from the scene's ``[initial]`` state (the values it leaves out solved from
the constraints, each named in a warning; checked on M_1 unless projected) and closes the
loop of every input with its ``[control]`` law (laws given here replace the scene's).
"""

from __future__ import annotations

from typing import Mapping

from nhham.errors import BudgetExceeded, InputError
from nhham.journeys.answer import Answer, as_scene, capture_warnings, quiet_steps

__all__ = ["simulate", "closed_loop", "initial_state", "initial_at"]


def simulate(scene, *, t_end: float | None = None, options: Mapping | None = None,
             project_initial: bool = False, control: Mapping | None = None,
             initial: Mapping | None = None, steps=None) -> Answer:
    """A run of the scene's constrained dynamics (``nhham simulate``).

    A singular Lagrangian runs the motion of its Dirac-Bergmann chain on M_f in T*Q
    (:func:`~nhham.journeys.singular_motion.simulate_singular`).

    Parameters
    ----------
    scene : Scene or str
        With an ``[initial]`` table.
    t_end : float, optional
        The run's end (default: the scene's ``[simulate]`` table, else 10).
    options : mapping, optional
        The run's settings (``method``, ``rtol``, ``atol``, ``step``, ``max_step``,
        ``save_every``, ``max_points``, ``projection``...), over the scene's
        ``[simulate]`` table; see :func:`nhham.simulate`.
    project_initial : bool
        Project ``[initial]`` onto M_1 (in the kinetic metric) instead of refusing a
        state off it.
    control : mapping of str to str, optional
        Laws of inputs (``{"u": "-k*x"}``), replacing the scene's ``[control]`` ones.
    initial : mapping, optional
        The ``[initial]`` table, replacing the scene's: keyed by nhham's names,
        dynamicsymbols or a mechanics model's speeds, the dependent entries solved
        (:func:`~nhham.journeys.answer.as_scene`).
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham simulate --json`` (``t_final``, ``y_final``,
        ``success``, diagnostics, ``contact_forces``...); ``payload["result"]``: the
        :class:`~nhham.numerics.integrate.SimulationResult`; ``failure`` when the run
        stopped early.

    Examples
    --------
    >>> from nhham import loads_scene
    >>> from nhham.journeys import simulate
    >>> scene = loads_scene(\'\'\'
    ... coordinates = ["x"]
    ... parameters = { k = 4.0 }
    ... lagrangian = "x_dot**2/2 - k*x**2/2"
    ... constraints = []
    ... [initial]
    ... x = 1.0
    ... x_dot = 0.0
    ... \'\'\')
    >>> answer = simulate(scene, t_end=1.0, options={"rtol": 1e-12, "atol": 1e-12})
    >>> answer.succeeded, round(answer.data["y_final"][0], 9)   # cos(2 t) at t = 1
    (True, -0.416146837)
    """
    from nhham.numerics.integrate import simulate as integrate, storage_plan
    from nhham.numerics.methods import lookup
    from nhham.render.results import simulation_data, simulation_failure

    scene = as_scene(scene, initial=initial, check_initial=False)
    steps = quiet_steps(steps)
    if not scene.system.regular_lagrangian:   # the chain's motion on M_f in T*Q
        from nhham.journeys.singular_motion import simulate_singular

        if project_initial or control:
            raise InputError(f"{'project_initial' if project_initial else 'control'}: not "
                             f"built for a singular Lagrangian (its state is on M_f in T*Q)",
                             key="--project-initial" if project_initial else "--control")
        return simulate_singular(scene, t_end=t_end, options=options, steps=steps)
    opts = dict(options or {})
    y0, solved = initial_state(scene, project_initial, steps)
    t_end = float(t_end if t_end is not None else (scene.simulate.t_end or 10.0))
    system = closed_loop(scene, control)
    t_span = (0.0, t_end)
    if not project_initial:   # a force undefined there: say which (exactly)
        from nhham.system.force_checks import check_forces_at

        check_forces_at(system, scene.initial, where="the initial state")
    method = opts.setdefault("method", "auto")   # the command's default: chosen from the system
    reduction = {key: opts.pop(key) for key in ("symmetry", "then") if key in opts}
    if method == "auto" or lookup(method, key="simulate.method").needs_reduction:
        # the scene's Hamiltonized reduction, as numeric functions (auto: tried on demand)
        from nhham.journeys.hamiltonized_motion import hamiltonized_field

        def reduce():
            return hamiltonized_field(system, steps=steps, **reduction)[0]

        opts["reduced"] = reduce if method == "auto" else reduce()
    elif reduction:
        raise InputError(f"{', '.join(reduction)}: read by method hamiltonized only, not "
                         f"{method}", key="--" + next(iter(reduction)))
    with capture_warnings() as caught:
        plan = storage_plan(scene.system.n, method, opts.get("save_every", 1),
                            opts.get("max_points"))
        with steps.step(f"simulate with {method} ({plan})"):
            result = integrate(system, t_span=t_span, y0=y0, project_initial=project_initial,
                               progress=steps.progress, contacts=scene.contacts, **opts)
    data = simulation_data(result, t_span)
    data["contact_forces"] = _contact_forces(result, caught)
    warnings = solved + [w for w in list(result.warnings) + caught
                         if not w.startswith("run stopped")]
    failure = None
    if not result.success:
        free = ()
        found = result.singularity
        if found.part == "C" if found is not None else int(result.status) == -3:
            free = _free_multipliers(system)
        failure = simulation_failure(result, str(scene.source), free)

    def text():  # the warnings go to stderr, one line each
        return "\n".join(line for line in result.describe().splitlines()
                         if not line.lstrip().startswith("warning:"))

    return Answer("simulate", data, text, warnings=tuple(warnings), failure=failure,
                  payload={"result": result}, system=system)


def initial_state(scene, project: bool = False, steps=None) -> tuple:
    """(initial state by name, warnings): ``[initial]`` completed (the values left out
    solved, named in a warning) and checked against the constraints, unless ``project``
    (it will be projected onto M_1).

    Raises
    ------
    InputError
        No ``[initial]``, or one off M_1 (without ``project``), naming the residuals.
    """
    steps = quiet_steps(steps)
    with steps.step("initial state: [initial] completed and checked"):
        y0 = scene.checked_initial(project=project)
    if not scene.initial_solved:
        return dict(y0), []
    from nhham.system.initial_solve import solved_text

    return dict(y0), [f"initial: solved from the constraints: "
                      f"{solved_text(y0, scene.initial_solved)}"]


def initial_at(scene, values: Mapping, given: Mapping | None = None) -> tuple:
    """``[initial]`` completed at other parameter values, as ``nhham simulate --set`` starts.

    Parameters
    ----------
    scene : Scene
        With an ``[initial]`` table.
    values : mapping of str to float
        Parameter values replacing the scene's (its expressions use them).
    given : mapping of str to float, optional
        Values of coordinates or velocities replacing (or added to) ``[initial]``'s.

    Returns
    -------
    (dict, tuple of str)
        Every coordinate and velocity by name, and the names solved from the
        constraints.

    Raises
    ------
    InputError
        A value left out that the constraints do not determine there, or given values
        that over-determine it and disagree (as the command refuses them).
    """
    import dataclasses

    import sympy as sp

    from nhham.system.initial_solve import complete_initial

    data = scene.initial_given
    if given:
        data = dataclasses.replace(data, given={
            **data.given, **{k: sp.Float(v) for k, v in given.items()}})
    return complete_initial(scene.system, data, values)


def closed_loop(scene, control: Mapping | None = None):
    """The scene's system with its inputs given by its ``[control]`` laws, ``control``'s
    replacing them (key ``--control`` in an error about those).

    Raises
    ------
    InputError
        A law that is not valid (an unknown name, an input of its own...).
    """
    laws = dict(scene.control)
    laws.update(control or {})
    if not laws:
        return scene.system
    try:
        return scene.system.closed_loop(laws)
    except InputError as exc:
        raise InputError(str(exc), key="--control" if control else "control") from None


def _contact_forces(result, warnings):
    """The scene's contact forces along the run (None without ``[contacts]``)."""
    forces = result.contact_forces
    if forces is None:
        return None
    warnings.extend(forces.warnings)
    out = forces.to_dict()
    out.pop("warnings", None)
    return {"t": [float(t) for t in result.t], **out}


def _free_multipliers(system) -> tuple:
    """Names of the free multipliers (for the failure message), or () if unknown."""
    try:
        from nhham.lagrangian.analysis import analyze_constraints

        return tuple(s.name for s in analyze_constraints(system).free_multiplier_symbols)
    except BudgetExceeded:
        raise
    except Exception:  # the message is a hint; never fail while writing it
        return ()
