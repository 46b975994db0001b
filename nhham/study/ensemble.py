"""``--what simulate``: a run from every point, its end state and diagnostics.

A point sets parameters and initial values (swept names of the scene's state, and
``--initial-perturbation`` draws added to them); the rest of the initial state is the
scene's ``[initial]`` table and the rest of the options its ``[simulate]`` table (or the
study's). Where the start depends on the point (``[initial]`` leaves values to be solved
from the constraints, or its expressions use a swept parameter), it is completed at each
point as ``nhham simulate --set`` completes it
(:func:`nhham.journeys.simulation.initial_at`; a point where the command would refuse it,
the values left out not determined there, is not run: ``status`` :data:`NOT_STARTED`).
Perturbations are added to the completed start. An initial state still off M_1 there is
projected onto M_1 (the kinetic-metric projection of
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

__all__ = ["prepare", "variables", "evaluate", "summary", "summary_warnings", "summary_rows",
           "OPTIONS", "METHODS", "NOT_STARTED"]

#: ``status`` of a point whose start ``nhham simulate`` refuses (``[initial]`` cannot be
#: completed there): not run.
NOT_STARTED = -10

#: Run options a study takes (the scene's [simulate] table gives the defaults).
OPTIONS = ("t_end", "method", "rtol", "atol", "max_step", "projection")

#: Largest scaled residual of an initial state taken as on M_1 (``simulate``'s default).
INITIAL_TOL = 1e-10

_DEFAULTS = {"t_end": 10.0, "method": DEFAULT_METHOD, "rtol": 1e-9, "atol": 1e-12,
             "max_step": None, "projection": False}


def prepare(scene, model, design, *, along=None, run_options=None, policy=None) -> dict:
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
    swept = [n for n in design.names if n in params]
    uses = set().union(*(e.free_symbols for e in scene.initial_given.given.values())) \
        if scene.initial_given is not None else set()
    complete = bool(scene.initial_solved) or any(s.name in swept for s in uses)
    from nhham.system.scene_dump import dependent_velocities

    # velocities [initial] gives that the constraints determine: off M_1 wherever a
    # parameter they depend on moves (the summary's warning says to leave them out)
    given = set(scene.initial_given.given) if scene.initial_given is not None else set()
    fixed = sorted(given & dependent_velocities(scene.system, dict(scene.initial)))
    return {**opts, "initial": [float(x) for x in y0], "state_names": states,
            "parameters": swept, "complete": complete, "given_dependent": fixed}


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
    unstarted = np.zeros(N, dtype=bool)
    if opts.get("complete"):
        unstarted = _complete_starts(ctx.scene, opts, values, states, Y0)
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
    Y0[unstarted] = np.asarray(opts["initial"], dtype=float)   # not run (below)
    runs = simulate_many(model, Y0, (0.0, float(opts["t_end"])), parameters=P,
                         method=opts["method"], rtol=opts["rtol"], atol=opts["atol"],
                         max_step=np.inf if opts["max_step"] is None else opts["max_step"],
                         projection=bool(opts["projection"]), deadline=deadline)
    if (runs.status == int(Status.TIME_LIMIT)).any():
        raise BudgetExceeded("the study's --budget ran out during a chunk's runs")
    E0, E1, residual = _ends(model, P, Y0, runs.y_final, runs.t_final)
    work = np.where(np.isnan(runs.work), 0.0, runs.work)
    status = np.where(unstarted, NOT_STARTED, runs.status)
    Y1 = np.where(unstarted[:, None], np.nan, runs.y_final)
    out = {
        "final_state": Y1, "initial_state": np.where(unstarted[:, None], np.nan, Y0),
        "t_final": np.where(unstarted, np.nan, runs.t_final),
        "status": status, "success": status >= 0, "nfev": runs.nfev,
        "nsteps": runs.nsteps, "wall_time": runs.wall_time_s,
        "constraint_residual": residual, "energy_error": E1 - E0 - work,
        "projection_distance": distance,
    }
    for k in ("constraint_residual", "energy_error", "projection_distance", "wall_time"):
        out[k] = np.where(unstarted, np.nan, out[k])
    for k in ("nfev", "nsteps"):
        out[k] = np.where(unstarted, -1, out[k])
    return {k: np.asarray(v).reshape(shape + np.asarray(v).shape[1:]) for k, v in out.items()}


def _complete_starts(scene, opts, values, states, Y0) -> np.ndarray:
    """``Y0`` (N, 2n) completed in place at each point's swept values, as the command
    completes ``[initial]``; returns where that is refused (not determined there)."""
    from nhham.journeys.simulation import initial_at

    flat = {k: v.ravel() for k, v in values.items()}
    refused = np.zeros(len(Y0), dtype=bool)
    for i in range(len(Y0)):
        params = {k: float(flat[k][i]) for k in opts["parameters"]}
        given = {k: float(v[i]) for k, v in flat.items() if k in states}
        try:
            y, _ = initial_at(scene, params, given)
        except InputError:
            refused[i] = True
            continue
        Y0[i] = [y[name] for name in states]
    return refused


def _off_manifold(model, P, Y0) -> np.ndarray:
    """Which initial states are not on M_1 (scaled residual above 1e-10, as ``simulate``
    checks): a point that changed them, or whose parameters moved M_1."""
    if P is None:
        return model.scaled_residuals(Y0).max(axis=1, initial=0.0) > INITIAL_TOL
    return np.array([float(np.max(model.with_parameters(
        **dict(zip(model.parameter_names, p))).scaled_residuals(y), initial=0.0)) > INITIAL_TOL
        for p, y in zip(P, Y0)])


def _ends(model, P, Y0, Y1, T1=None) -> tuple:
    """(E at the start, E at the end, largest scaled residual at the end), one per run
    (at t = 0 and at the runs' end times ``T1`` when t enters L or a constraint)."""
    if model.time_in_geometry:
        return _timed_ends(model, P, Y0, Y1, T1)
    if P is None:
        return model.energy(Y0), model.energy(Y1), model.scaled_residuals(Y1).max(
            axis=1, initial=0.0)
    E0, E1, res = np.empty(len(Y0)), np.empty(len(Y0)), np.empty(len(Y0))
    for i, p in enumerate(P):
        m = model.with_parameters(**dict(zip(model.parameter_names, p)))
        E0[i], E1[i] = m.energy(Y0[i]), m.energy(Y1[i])
        res[i] = float(np.max(m.scaled_residuals(Y1[i]), initial=0.0))
    return E0, E1, res


def _timed_ends(model, P, Y0, Y1, T1) -> tuple:
    """:func:`_ends` with the model at each state's time."""
    E0, E1, res = np.empty(len(Y0)), np.empty(len(Y0)), np.empty(len(Y0))
    for i in range(len(Y0)):
        m = model if P is None else model.with_parameters(
            **dict(zip(model.parameter_names, P[i])))
        E0[i] = m.at_time(0.0).energy(Y0[i])
        end = m.at_time(T1[i])
        E1[i] = end.energy(Y1[i])
        res[i] = float(np.max(end.scaled_residuals(Y1[i]), initial=0.0))
    return E0, E1, res


def summary(ds) -> dict:
    """What the study found, in a few numbers (JSON-ready)."""
    done = np.asarray(ds["done"].values, dtype=bool)
    success = np.asarray(ds["success"].values, dtype=bool) & done
    err = np.abs(np.asarray(ds["energy_error"].values))[done]
    res = np.asarray(ds["constraint_residual"].values)[done]
    moved = np.asarray(ds["projection_distance"].values)[done]
    import json

    given = json.loads(ds.attrs.get("options", "{}")).get("given_dependent") or []
    return {"done_points": int(done.sum()), "failed_runs": int((done & ~success).sum()),
            "given_dependent": list(given),
            "max_energy_error": float(np.nanmax(err)) if np.isfinite(err).any() else None,
            "max_constraint_residual": (float(np.nanmax(res)) if np.isfinite(res).any()
                                        else None),
            "projected_starts": int((moved > 0).sum()),
            "max_projection_distance": (float(np.nanmax(moved)) if np.isfinite(moved).any()
                                        else None)}


def summary_warnings(s: dict) -> list:
    """The warnings a summary calls for (one line each)."""
    if not s["projected_starts"]:
        return []
    why = ""
    if s.get("given_dependent"):
        names = ", ".join(s["given_dependent"])
        why = (f": [initial] gives {names}, which the constraints determine; leave "
               f"{'it' if len(s['given_dependent']) == 1 else 'them'} out and "
               f"{'it is' if len(s['given_dependent']) == 1 else 'they are'} solved at "
               f"every point instead")
    return [f"{s['projected_starts']} of {s['done_points']} initial states were off M_1 at "
            f"their point (its values or parameters) and were projected onto it (largest "
            f"move {s['max_projection_distance']:.3g}; projection_distance in the "
            f"results){why}"]


def summary_rows(s: dict) -> list:
    """(label, text) rows of the command's report."""
    return [("runs failed", str(s["failed_runs"])),
            ("max |energy error|", f"{s['max_energy_error']:.3g}"
             if s["max_energy_error"] is not None else "-"),
            ("max constraint residual", f"{s['max_constraint_residual']:.3g}"
             if s["max_constraint_residual"] is not None else "-")]
