"""``--what simulate``: a run from every point, its end state and diagnostics.

A point sets parameters and initial values (swept names of the scene's state, and
``--initial-perturbation`` draws added to them); the rest of the initial state is the
scene's ``[initial]`` table and the rest of the options its ``[simulate]`` table (or the
study's). An initial state off M_1 there (a point changed it, or its parameters moved M_1)
is projected onto M_1 (the kinetic-metric projection of
:meth:`~nhham.numerics.model.NumericModel.project`; ``projection_distance`` says by how
much it moved, and the command warns). The runs are those of
:func:`~nhham.numerics.ensemble.simulate_many`: each end state is what a single
``simulate`` gives, to rounding.

Variables: ``final_state`` and ``initial_state`` (dimension ``state``), ``t_final``,
``status`` (:class:`~nhham.numerics.status.Status`, 0 success), ``success``,
``nfev``, ``nsteps``, ``wall_time``, ``constraint_residual`` (the largest scaled residual
at the end), ``energy_error`` (E(t_final) - E(0) - the work of the forces: 0 up to the
integration error, whether energy is conserved or not) and ``projection_distance``.
"""

from __future__ import annotations

import numpy as np

from nhham.errors import BudgetExceeded, InputError
from nhham.numerics.ensemble import simulate_many
from nhham.numerics.methods import DEFAULT_METHOD
from nhham.numerics.status import Status
from nhham.study.kinds import SIMULATE_METHODS as METHODS
from nhham.study.stop import chunk_deadline

__all__ = ["prepare", "variables", "evaluate", "OPTIONS", "METHODS"]

#: Run options a study takes (the scene's [simulate] table gives the defaults).
OPTIONS = ("t_end", "method", "rtol", "atol", "max_step", "projection")

#: Largest scaled residual of an initial state taken as on M_1 (``simulate``'s default).
INITIAL_TOL = 1e-10

_DEFAULTS = {"t_end": 10.0, "method": DEFAULT_METHOD, "rtol": 1e-9, "atol": 1e-12,
             "max_step": None, "projection": False}


def prepare(scene, model, design, run_options=None) -> dict:
    """The options of a simulate study: the run's settings, where each swept name goes.

    Raises
    ------
    InputError
        No ``[initial]`` table, a swept or perturbed name that is neither a parameter nor
        a state name, an input without a control law, a fixed-step method.
    """
    if scene.initial is None:
        raise InputError(f"{scene.source}: --what simulate needs an [initial] table (the "
                         f"state that points change)", key="initial")
    states, params = list(model.names), list(model.parameter_names)
    for name in design.names:
        if name in model.input_names:
            raise InputError(f"--over: {name!r} is an input (given by a control law); sweep "
                             f"a parameter its law uses", key="--over")
        if name not in states and name not in params:
            raise InputError(f"--over: {name!r} is neither a parameter nor a coordinate or "
                             f"velocity of the scene", key="--over")
    for name in design.perturbed:
        if name not in states:
            raise InputError(f"--initial-perturbation: {name!r} is not a coordinate or "
                             f"velocity of the scene", key="--initial-perturbation")
    unset = model.unset_inputs()
    if unset:
        raise InputError(f"inputs: no control law for {', '.join(unset)} (give [control] "
                         f"in the scene)", key="inputs")
    opts = dict(_DEFAULTS)
    opts.update({k: v for k, v in scene.simulate.given().items() if k in OPTIONS})
    opts.update({k: v for k, v in (run_options or {}).items() if v is not None})
    if opts["method"] not in METHODS:
        raise InputError(f"--method: a study runs the adaptive methods ({', '.join(METHODS)}), "
                         f"not {opts['method']!r}", key="--method")
    y0 = model.state(dict(scene.initial))
    return {**opts, "initial": [float(x) for x in y0], "state_names": states,
            "parameters": [n for n in design.names if n in params]}


def variables(design, options) -> dict:
    """``{"point": {name: (extra dims, dtype, fill)}, "line": {}, "coords": {...}}``."""
    point = {
        "final_state": (("state",), float, np.nan),
        "initial_state": (("state",), float, np.nan),
        "t_final": ((), float, np.nan),
        "status": ((), np.int8, -100),
        "success": ((), bool, False),
        "nfev": ((), np.int64, -1),
        "nsteps": ((), np.int64, -1),
        "wall_time": ((), float, np.nan),
        "constraint_residual": ((), float, np.nan),
        "energy_error": ((), float, np.nan),
        "projection_distance": ((), float, np.nan),
    }
    return {"point": point, "line": {}, "coords": {"state": list(options["state_names"])}}


def evaluate(study, ctx, region, until: float | None = None) -> dict:
    """Every variable on ``region`` (see the module docstring).

    ``until``: a ``time.time()`` at which the runs stop (inside a run: the compiled loop
    looks at its deadline every few milliseconds); a chunk not finished by then raises
    :class:`~nhham.errors.BudgetExceeded` (a run cut short is not a result to keep).
    """
    model, opts = ctx.model, study.options
    values = study.design.values(region)
    shape = next(iter(values.values())).shape if values else \
        tuple(len(range(*s.indices(n))) for s, n in zip(region, study.design.shape))
    N = int(np.prod(shape))
    states, params = list(model.names), list(model.parameter_names)
    Y0 = np.tile(np.asarray(opts["initial"], dtype=float), (N, 1))
    P = None
    for name, v in values.items():
        if name in states:
            Y0[:, states.index(name)] = v.ravel()
        elif P is None:
            P = np.tile(np.asarray(model.parameter_values, dtype=float), (N, 1))
    if P is not None:
        for name in opts["parameters"]:
            P[:, params.index(name)] = values[name].ravel()
    if study.design.perturbed:
        noise = study.design.perturbation(region).reshape(N, -1)
        for j, name in enumerate(study.design.perturbed):
            Y0[:, states.index(name)] += noise[:, j]
    distance = np.zeros(N)
    off = np.flatnonzero(_off_manifold(model, P, Y0))
    if P is None:   # one model: the starts projected in one batch
        if off.size:
            Y0[off], distance[off] = model.project_many(Y0[off])
    else:
        for i in off:
            m = model.with_parameters(**dict(zip(params, P[i])))
            outcome = m.project(Y0[i])
            distance[i] = np.linalg.norm(outcome.y - Y0[i])
            Y0[i] = outcome.y
    deadline = chunk_deadline(until)
    runs = simulate_many(model, Y0, (0.0, float(opts["t_end"])), parameters=P,
                         method=opts["method"], rtol=opts["rtol"], atol=opts["atol"],
                         max_step=np.inf if opts["max_step"] is None else opts["max_step"],
                         projection=bool(opts["projection"]), deadline=deadline)
    if (runs.status == int(Status.TIME_LIMIT)).any():
        raise BudgetExceeded("the study's --budget ran out during a chunk's runs")
    E0, E1, residual = _ends(model, P, Y0, runs.y_final)
    work = np.where(np.isnan(runs.work), 0.0, runs.work)
    out = {
        "final_state": runs.y_final, "initial_state": Y0, "t_final": runs.t_final,
        "status": runs.status, "success": runs.status >= 0, "nfev": runs.nfev,
        "nsteps": runs.nsteps, "wall_time": runs.wall_time_s,
        "constraint_residual": residual, "energy_error": E1 - E0 - work,
        "projection_distance": distance,
    }
    return {k: np.asarray(v).reshape(shape + np.asarray(v).shape[1:]) for k, v in out.items()}


def _off_manifold(model, P, Y0) -> np.ndarray:
    """Which initial states are not on M_1 (scaled residual above 1e-10, as ``simulate``
    checks): a point that changed them, or whose parameters moved M_1."""
    if P is None:
        return model.scaled_residuals(Y0).max(axis=1, initial=0.0) > INITIAL_TOL
    return np.array([float(np.max(model.with_parameters(
        **dict(zip(model.parameter_names, p))).scaled_residuals(y), initial=0.0)) > INITIAL_TOL
        for p, y in zip(P, Y0)])


def _ends(model, P, Y0, Y1) -> tuple:
    """(E at the start, E at the end, largest scaled residual at the end), one per run."""
    if P is None:
        return model.energy(Y0), model.energy(Y1), model.scaled_residuals(Y1).max(
            axis=1, initial=0.0)
    E0, E1, res = np.empty(len(Y0)), np.empty(len(Y0)), np.empty(len(Y0))
    for i, p in enumerate(P):
        m = model.with_parameters(**dict(zip(model.parameter_names, p)))
        E0[i], E1[i] = m.energy(Y0[i]), m.energy(Y1[i])
        res[i] = float(np.max(m.scaled_residuals(Y1[i]), initial=0.0))
    return E0, E1, res
