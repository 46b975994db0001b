"""``simulate``: every integration method behind one function, with diagnostics.

Methods
-------
``"RK23"``, ``"RK45"``, ``"DOP853"``, ``"Radau"``, ``"BDF"``, ``"LSODA"``
    The :mod:`scipy.integrate` solvers on the projected field (stepped here,
    so that a failure keeps the trajectory computed so far:
    :mod:`nhham.numerics.scipy_loop`; ``dense_output`` and ``events`` as in
    :func:`scipy.integrate.solve_ivp`). With the compiled backend, RK23, RK45
    and DOP853 run as one compiled loop instead (``loop="auto"``,
    :mod:`nhham.numerics.compiled_loop`): scipy's algorithm (its coefficients,
    initial step, error norm, step-size control and dense output) with the
    projection and the storage done in C too, so no Python runs per step;
    ``loop="scipy"`` keeps scipy's own Python loop (same steps up to
    round-off), and so do ``dense_output`` and ``events``. Options:
    ``projection=True`` projects onto M_1 after every step (velocities in the
    kinetic metric, position constraints by Newton iteration);
    ``baumgarte=(alpha, beta)`` replaces d(phi)/dt = 0 by
    d(phi)/dt = -2 alpha phi - beta^2 g. Implicit methods get their
    finite-difference Jacobian from one batched evaluation.
``"rattle"``, ``"rattle4"``, ``"rk4"``
    Fixed step ``step`` (:mod:`nhham.numerics.integrators`): the structure-preserving
    nonholonomic RATTLE scheme (order 2), its triple-jump composition
    (order 4), classical RK4 (with ``projection``/``baumgarte`` if asked).
``"reference"``
    High-precision extrapolation in mpmath with ``reference_digits`` digits
    (:mod:`nhham.numerics.reference`), for measuring errors.

The integrators never import sympy: a System is turned into a
:class:`~nhham.numerics.model.NumericModel` by
:func:`nhham.numerics.codegen.numeric_model` (the one bridge), or a model is
passed directly. Every result's ``status`` is a
:class:`~nhham.numerics.status.Status`.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field, replace
from functools import cached_property
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from nhham.autonomy import require_autonomous
from nhham.errors import InconsistentInitialDataError, InputError
from nhham.numerics.compiled_loop import COMPILED_METHODS, run_compiled
from nhham.numerics.diagnostics import (Diagnostics, Singularity, singularity_at,
                                        trajectory_diagnostics)
from nhham.numerics.integrators import FIXED_STEP_METHODS, run_fixed_step
from nhham.numerics.nullspace import describe_kkt_solve
from nhham.numerics.model import (LibraryReady, NumericModel, NumericsWarning,
                                  ProjectionOutcome)
from nhham.numerics.run import Deadline, Run
from nhham.numerics.scipy_loop import SCIPY_METHODS, DenseOutput, run_scipy
from nhham.numerics.status import Status
from nhham.numerics.storage import (Recorder, Storage, check_plan, default_max_points,
                                    memory_text, storage_bytes)

__all__ = ["simulate", "SimulationResult", "SCIPY_METHODS", "COMPILED_METHODS", "METHODS",
           "storage_plan"]

_LOOPS = ("auto", "compiled", "scipy")
METHODS = tuple(SCIPY_METHODS) + tuple(FIXED_STEP_METHODS) + ("reference",)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Trajectory and diagnostics, in the style of scipy's ``OdeResult``.

    Attributes
    ----------
    t : ndarray, shape (K,)
    y : ndarray, shape (2n, K)
        As in scipy: ``y[i]`` is the i-th state variable over time (names in
        :attr:`names`: coordinates then velocities). ``states`` gives (K, 2n).
    status : Status
        An int-valued enum: 0 success; 1 a terminal event stopped the run; -1 step
        failure; -2 NaN/overflow (run stopped); -3 singular saddle-point system; -4
        Newton/projection failure; -5 stopped at ``time_limit``. The trajectory up to the
        failure is kept.
    message : str
    success : bool
        ``status >= 0``, as in scipy.
    method : str
    settings : mapping
        The options that determined the run (rtol, atol, step, ...).
    nfev : int
        Right-hand-side evaluations counted in states (a batched call on k
        states counts k).
    njev, nlu, nsteps : int
    wall_time_s : float
        Integration time (without diagnostics and code generation).
    diagnostics : Diagnostics
        See :class:`nhham.numerics.diagnostics.Diagnostics`; its main fields are also
        attributes here (``constraint_residual_max``, ``energy_drift``,
        ``energy_balance_residual``, ``cond_C_max``, ``cond_W_max``, ``kkt_solve``: which
        solve gave the constrained accelerations, "saddle", "null-space" or "mixed").
    warnings : tuple of str
        Also issued as :class:`~nhham.numerics.model.NumericsWarning` unless
        ``warn=False`` was passed.
    initial_projection : ProjectionOutcome or None
        When the initial data were projected onto M_1: by how much.
    sol : DenseOutput or None
        With ``dense_output=True`` (scipy methods): ``sol(t)`` is the state at t.
    t_events, y_events : list of ndarray or None
        With ``events`` (scipy methods): per event function, its times (k,) and
        states (k, 2n), as in scipy.
    storage : Storage or None
        What was kept of the steps (every how many, how many states, their memory;
        :mod:`nhham.numerics.storage`).
    failed_state : ndarray (2n,) or None
        When the run stopped because the field could not be evaluated: the state where
        that happened (a stage of the step that did not complete; ``t`` and ``y`` end at
        the last completed step), if the loop knows it.
    contact_forces : ContactForces or None
        The forces of the constraints at the contact points given to ``simulate``
        (``contacts=``), at the stored states: ``contact_forces.forces[name]`` of shape
        (K, 3); None without contacts.
    controls : mapping or None
        The Python callables that gave inputs (``controls=``), kept so that the
        multipliers at the stored states use the inputs the run used.
    """

    t: np.ndarray
    y: np.ndarray
    status: Status
    message: str
    method: str
    settings: MappingProxyType
    names: tuple
    nfev: int
    njev: int
    nlu: int
    nsteps: int
    wall_time_s: float
    diagnostics: Diagnostics
    warnings: tuple
    initial_projection: ProjectionOutcome | None = None
    model: NumericModel | None = field(default=None, repr=False)
    sol: DenseOutput | None = field(default=None, repr=False)
    t_events: list | None = None
    y_events: list | None = None
    storage: Storage | None = None
    failed_state: np.ndarray | None = field(default=None, repr=False)
    contact_forces: Any = None
    controls: Mapping | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        # One line: the arrays are in .t, .y (a repr printing them ran to 14 KB).
        return (f"<SimulationResult {self.method}: {self.message} at t = {self.t[-1]:.6g}; "
                f"{self.y.shape[1]} states of {self.y.shape[0]} variables, {self.nsteps} "
                f"steps, max constraint residual {self.diagnostics.constraint_residual_max:.2e}>")

    @property
    def success(self) -> bool:
        return self.status >= 0

    @property
    def states(self) -> np.ndarray:
        """States as rows, shape (K, 2n)."""
        return self.y.T

    def __getitem__(self, name) -> np.ndarray:
        """Time series of one state variable by name (``result["x_dot"]``)."""
        return self.y[self.names.index(name)]

    @property
    def final_state(self) -> dict:
        return {k: float(v) for k, v in zip(self.names, self.y[:, -1])}

    constraint_residual_max = property(lambda self: self.diagnostics.constraint_residual_max)
    constraint_residual_rel_max = property(
        lambda self: self.diagnostics.constraint_residual_rel_max)
    energy_drift = property(lambda self: self.diagnostics.energy_drift)
    energy_drift_rel = property(lambda self: self.diagnostics.energy_drift_rel)
    energy_balance_residual = property(lambda self: self.diagnostics.energy_balance_residual)
    cond_C_max = property(lambda self: self.diagnostics.cond_C_max)
    cond_W_max = property(lambda self: self.diagnostics.cond_W_max)
    kkt_solve = property(lambda self: self.diagnostics.kkt_solve)
    energy = property(lambda self: self.diagnostics.energy)
    work = property(lambda self: self.diagnostics.work)

    @cached_property
    def singularity(self) -> Singularity | None:
        """For a run that stopped: what is singular (W, the constraints' one-forms, or C)
        where it stopped (at :attr:`failed_state` when known, else at the last state),
        or None when nothing is nearly singular there (see
        :func:`nhham.numerics.diagnostics.singularity_at`)."""
        if self.success or self.model is None:
            return None
        y = self.failed_state if self.failed_state is not None else self.y[:, -1]
        return singularity_at(self.model, y)

    @cached_property
    def multipliers(self) -> np.ndarray:
        """lambda at the stored states, shape (m, K) (continuous-field values; with
        time-dependent forces or Python controls each state at its own time and inputs)."""
        model, controls = self.model, self.controls or {}
        if model.time_slot is None and not controls:
            return np.atleast_2d(model.multipliers(self.states)).T
        rows = []
        for t, y in zip(self.t, self.states):
            now = model.at_time(t)
            if controls:
                now = now.with_parameters(**{u: float(f(t, y)) for u, f in controls.items()})
            rows.append(now.multipliers(y))
        return np.atleast_2d(np.array(rows)).T

    def describe(self) -> str:
        """A few human-readable lines: status, cost and diagnostics."""
        d = self.diagnostics
        lines = [
            f"{self.method}: {self.message} (status {self.status}) at t = {self.t[-1]:.6g}",
            f"  steps {self.nsteps}, right-hand-side evaluations {self.nfev}, "
            f"wall time {self.wall_time_s:.3g} s, {self.settings.get('backend')} backend",
            f"  max constraint residual {d.constraint_residual_max:.2e} "
            f"(scaled {d.constraint_residual_rel_max:.2e})",
            f"  energy drift {d.energy_drift:.2e} (relative {d.energy_drift_rel:.2e}), "
            f"energy balance residual {d.energy_balance_residual:.2e}",
            f"  max cond(C) {d.cond_C_max:.3g}, max cond(W) {d.cond_W_max:.3g}",
        ]
        if d.kkt_solve != "saddle":   # the usual solve is said in the JSON only
            lines.append(f"  {describe_kkt_solve(d.kkt_solve, d.kkt_ratio_max)}")
        if self.storage is not None:
            lines.append(f"  {self.storage.describe(self.nsteps)}")
        if self.initial_projection is not None:
            p = self.initial_projection
            lines.append(f"  initial data projected onto M_1: residual {p.residual_before:.2e} -> "
                         f"{p.residual_after:.2e}, |dq| = {p.displacement_q:.2e}, "
                         f"|dv| = {p.displacement_v:.2e}")
        if self.singularity is not None:
            lines.append(f"  where it stopped, {self.singularity.describe()}")
        lines += [f"  warning: {w}" for w in self.warnings]
        lines.append("  final state: " + ", ".join(f"{k} = {v:.10g}"
                                                  for k, v in self.final_state.items()))
        return "\n".join(lines)

    def save(self, path) -> str:
        """Write t and the states: ``.npz`` (numpy) or otherwise CSV with a header."""
        path = str(path)
        if path.endswith(".npz"):
            np.savez(path, t=self.t, y=self.y, names=np.array(self.names),
                     energy=self.energy, work=self.work)
        else:
            header = ",".join(("t",) + tuple(self.names) + ("energy",))
            data = np.column_stack([self.t, self.states, self.energy])
            np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.17g")
        return path

    def summary(self) -> dict:
        """Plain numbers for JSON output."""
        d = self.diagnostics
        out = {
            "method": self.method, "status": int(self.status), "message": self.message,
            "success": self.success, "t_end": float(self.t[-1]), "steps": self.nsteps,
            "nfev": self.nfev, "njev": self.njev, "nlu": self.nlu,
            "wall_time_s": self.wall_time_s,
            "constraint_residual_max": d.constraint_residual_max,
            "constraint_residual_rel_max": d.constraint_residual_rel_max,
            "energy_drift": d.energy_drift, "energy_drift_rel": d.energy_drift_rel,
            "energy_balance_residual": d.energy_balance_residual,
            "cond_C_max": d.cond_C_max, "cond_W_max": d.cond_W_max,
            "kkt_solve": d.kkt_solve, "kkt_ratio_max": d.kkt_ratio_max,
            "warnings": list(self.warnings), "final_state": self.final_state,
            "settings": dict(self.settings),
            "storage": None if self.storage is None else self.storage.to_dict(),
        }
        if self.initial_projection is not None:
            p = self.initial_projection
            out["initial_projection"] = {
                "residual_before": p.residual_before, "residual_after": p.residual_after,
                "displacement_q": p.displacement_q, "displacement_v": p.displacement_v}
        return out


def simulate(system_or_model, t_span, y0, *, method: str = "DOP853", rtol: float = 1e-9,
             atol: float = 1e-12, step: float | None = None, t_eval=None,
             dense_output: bool = False, events=None,
             max_step: float = np.inf, first_step: float | None = None,
             projection: bool = False, baumgarte=None, project_initial: bool = False,
             initial_tol: float = 1e-10, residual_tol: float | None = None,
             reference_digits: int | None = None, save_every: int = 1,
             max_points: int | None = None, backend: str = "auto", warn: bool = True,
             progress: bool = False, loop: str = "auto",
             time_limit: float | None = None, contacts=(),
             controls=None) -> SimulationResult:
    """Integrate the constrained dynamics from ``y0`` over ``t_span``.

    Parameters
    ----------
    system_or_model : nhham.System or NumericModel
    t_span : (float, float)
        Start and end (as in :func:`scipy.integrate.solve_ivp`: ``t_span`` before
        ``y0``).
    y0 : mapping or array_like
        ``{name: value}`` for every coordinate and velocity, or shape (2n,).
    method : str
        One of :data:`METHODS` (see the module docstring).
    rtol, atol : float
        Tolerances of the adaptive methods.
    step : float
        Step of the fixed-step methods (required for them).
    t_eval : array_like, optional
        Output times (adaptive and reference methods); default every step (see
        ``save_every`` and ``max_points``).
    max_step, first_step : float, optional
        Passed to the scipy solvers.
    projection : bool
        Project onto M_1 after every step (scipy methods and rk4).
    baumgarte : (alpha, beta), optional
        Baumgarte stabilisation (scipy methods and rk4).
    project_initial : bool
        Project initial data that violate the constraints onto M_1 instead of
        refusing them; ``result.initial_projection`` says by how much.
    initial_tol : float
        Largest scaled residual accepted in ``y0`` (see
        :meth:`NumericModel.scaled_residuals`).
    controls : mapping, optional
        The inputs: ``{input: law}`` with a law an expression in ``t``, the coordinates,
        velocities and parameters (compiled with the field: :meth:`System.closed_loop`), or
        a Python callable ``f(t, y) -> float`` (y the state, shape (2n,); the scipy
        methods, evaluated at every right-hand side).
    residual_tol : float, optional
        Scaled residual above which a warning is given (default 1e-8 for
        unprojected adaptive methods, 1e-11 for projected and structure-
        preserving ones).
    reference_digits : int, optional
        Digits of the ``"reference"`` method (default 30).
    save_every : int
        Keep every j-th step (and the last state); every method but the reference.
    max_points : int, optional
        Most states kept in memory. When every ``save_every``-th step would be more,
        every other kept state is dropped and the stride doubles, as often as needed
        (``result.storage`` says what was kept); a ``t_eval`` longer than it is refused
        with the memory it would need. Default: as many states as fit in
        :data:`~nhham.numerics.storage.STORE_BYTES` (64 MiB; 8 (2n + 2) bytes a state:
        838,860 states for n = 4).
    backend : str
        Backend when a System is given (see :func:`nhham.numerics.codegen.numeric_model`).
        With ``"auto"`` a library not yet in the compile cache is built in the background
        while numpy integrates; when the build finishes first the run starts again on
        the compiled code. ``result.settings["backend"]`` (and ``"backend_note"``) say
        which ran; both give the same steps up to round-off.
    warn : bool
        Issue the diagnostics' warnings as :class:`NumericsWarning`.
    progress : bool
        Report progress on stderr (each tenth of t_span; not the reference method).
    loop : {"auto", "compiled", "scipy"}
        RK23, RK45, DOP853: ``"auto"`` runs the whole integration as one
        compiled loop when the model has the compiled backend (saddle path),
        else scipy's Python loop; ``"compiled"`` insists (InputError if
        impossible); ``"scipy"`` always uses scipy's loop. Both give the same
        steps up to round-off. ``result.settings["loop"]`` says which ran.
    time_limit : float, optional
        Seconds of wall time after which the run stops with ``Status.TIME_LIMIT`` (a
        failure that keeps the trajectory so far; not the reference method).
    contacts : sequence of ContactPoint, optional
        Contact points (a scene's ``contacts``; a System must be given): the forces of
        their constraints at the stored states are in ``result.contact_forces``
        (:func:`nhham.numerics.contact_forces.contact_forces`).
    dense_output : bool
        scipy methods: keep the continuous solution, ``result.sol(t)`` (runs
        scipy's loop; its memory grows with the steps, a few hundred bytes each, and is
        not bounded by ``max_points``).
    events : callable or sequence of callables, optional
        scipy methods: ``event(t, y) -> float`` on the state y (2n,), located as
        in :func:`scipy.integrate.solve_ivp` (``terminal`` and ``direction``
        attributes); times and states in ``result.t_events``/``y_events``; a
        terminal event ends the run with ``Status.EVENT`` (runs scipy's loop).

    Returns
    -------
    SimulationResult

    Raises
    ------
    InconsistentInitialDataError
        If ``y0`` violates the constraints (the residuals are shown) and
        ``project_initial`` is False, or names are missing.
    InputError
        For an unknown method or inconsistent options (``dense_output`` or
        ``events`` with a method that is not a scipy one, for instance).
    """
    if contacts and isinstance(system_or_model, NumericModel):
        raise InputError("simulate: contacts need the System (its constraints' velocity "
                         "maps), not a NumericModel", key="contacts")
    system_or_model, callables = _with_controls(system_or_model, controls, method, contacts)
    if callables:
        loop = "scipy"
    model = _as_model(system_or_model, backend,
                      background=method not in ("rattle", "rattle4") and loop != "compiled")
    if callables:
        unknown = sorted(set(callables) - set(model.input_names))
        if unknown:
            raise InputError(f"controls: {', '.join(unknown)} not an input of the system "
                             f"(inputs: {', '.join(model.input_names) or 'none'})",
                             key="controls")
        model = model.with_parameters(**{u: 0.0 for u in callables})  # set at every call
    t0, t1 = (float(t_span[0]), float(t_span[1]))
    if not (math.isfinite(t0) and math.isfinite(t1)) or t1 == t0:
        raise InputError(f"t_span: need two different finite times, got {t_span!r}")
    _check_options(method, step, projection, baumgarte, model)
    _check_scipy_only(method, dense_output, events)
    compiled_loop = _use_compiled_loop(model, method, loop, dense_output or events is not None)
    y_init, initial = _initial_state(model, y0, project_initial, initial_tol)
    recorder = _recorder(model, method, t_eval, save_every, max_points)
    settings = {"rtol": rtol, "atol": atol, "step": step, "projection": projection,
                "baumgarte": None if baumgarte is None else tuple(map(float, baumgarte)),
                "backend": model.backend, "backend_note": model.backend_note,
                "path": model.path, "save_every": int(save_every),
                "max_points": recorder.max_points}
    if residual_tol is None:
        exact = projection or method in ("rattle", "rattle4", "reference")
        residual_tol = 1e-11 if exact else 1e-8
    start = time.perf_counter()
    deadline = Deadline.after(time_limit)
    adaptive = dict(rtol=rtol, atol=atol, max_step=max_step, first_step=first_step,
                    t_eval=t_eval, projection=projection, baumgarte=baumgarte,
                    progress=progress, deadline=deadline)
    while True:
        try:
            if compiled_loop:
                settings["loop"] = "compiled"
                run = run_compiled(model, y_init, t0, t1, method, recorder=recorder, **adaptive)
            elif method in SCIPY_METHODS:
                settings["loop"] = "scipy"
                run = run_scipy(model, y_init, t0, t1, method, dense_output=dense_output,
                                events=events, recorder=recorder, controls=callables,
                                **adaptive)
            elif method in FIXED_STEP_METHODS:
                opts = {"recorder": recorder, "progress": progress, "deadline": deadline}
                if method == "rk4":
                    opts.update(projection=projection, baumgarte=baumgarte)
                run = run_fixed_step(method, model, y_init, t0, t1, float(step), **opts)
                settings.update(step=run.step, newton_iterations=run.newton_iterations)
            else:
                run = _run_reference(model, y_init, t0, t1, reference_digits, t_eval,
                                     settings)
            break
        except LibraryReady:  # the background build won: the whole run on compiled code
            model = model.with_library()
            compiled_loop = _use_compiled_loop(model, method, loop, dense_output or
                                               events is not None)
            settings.update(backend=model.backend, backend_note=model.backend_note)
            recorder = _recorder(model, method, t_eval, save_every, max_points)
    wall = time.perf_counter() - start
    storage = None if method == "reference" else recorder.storage(t_eval is not None)
    result = _result(model, run, method, settings, wall, residual_tol, initial, warn, storage)
    if callables:
        result = replace(result, controls=MappingProxyType(dict(callables)))
    if not contacts:
        return result
    from nhham.numerics.contact_forces import contact_forces

    return replace(result, contact_forces=contact_forces(
        system_or_model, contacts, result.states, result.multipliers.T,
        parameters=dict(zip(model.parameter_names, model.parameter_values))))


def _with_controls(system_or_model, controls, method, contacts) -> tuple:
    """(system or model, {input: callable}): expressions closed into the System, Python
    callables kept for the scipy loop (which sets them at every evaluation)."""
    if not controls:
        return system_or_model, {}
    laws = {str(u): f for u, f in controls.items() if not callable(f)}
    callables = {str(u): f for u, f in controls.items() if callable(f)}
    if laws:
        if isinstance(system_or_model, NumericModel):
            raise InputError("controls: laws given as expressions need the System (they are "
                             "compiled with the field); give callables for a NumericModel",
                             key="controls")
        system_or_model = system_or_model.closed_loop(laws)
    if callables and method not in SCIPY_METHODS:
        raise InputError(f"controls: Python callables run with the scipy methods "
                         f"({', '.join(SCIPY_METHODS)}), not {method!r}; give expressions to "
                         f"compile them with the field", key="controls")
    if callables and contacts:
        raise InputError("controls: contact forces need the inputs as expressions (the "
                         "multipliers at the stored states)", key="controls")
    return system_or_model, callables


def _run_reference(model, y0, t0, t1, digits, t_eval, settings) -> Run:
    from nhham.numerics.reference import reference_solution

    digits = 30 if digits is None else int(digits)
    ref = reference_solution(model, y0, (t0, t1), digits=digits, t_eval=t_eval)
    settings.update(digits=digits, tol=ref.tol, error_estimate=ref.error_estimate)
    return Run(ref.t, ref.y, ref.work, ref.status, ref.message, ref.nfev, ref.nsteps)


def _result(model, run, method, settings, wall, residual_tol, initial, warn, storage):
    """The diagnostics of ``run`` and the result (warnings issued here: stacklevel 3
    points at the caller of :func:`simulate`)."""
    diag = trajectory_diagnostics(model, run.t, run.y, run.work, residual_tol=residual_tol)
    notes = list(diag.warnings)
    if run.status < 0:
        notes.insert(0, f"run stopped: {run.message}")
    if warn:
        for note in notes:
            warnings.warn(note, NumericsWarning, stacklevel=3)
    return SimulationResult(
        t=run.t, y=np.asarray(run.y, dtype=float), status=Status(run.status),
        message=run.message, method=method, settings=MappingProxyType(settings),
        names=model.names, nfev=run.nfev, njev=run.njev, nlu=run.nlu, nsteps=run.nsteps,
        wall_time_s=wall, diagnostics=diag, warnings=tuple(notes),
        initial_projection=initial, model=model, sol=run.sol, t_events=run.t_events,
        y_events=run.y_events, storage=storage, failed_state=run.failed_state)


# ------------------------------------------------------------------ helpers
def _as_model(obj, backend, background=False) -> NumericModel:
    if isinstance(obj, NumericModel):
        return obj
    from nhham.numerics.codegen import numeric_model  # the one bridge from sympy

    return numeric_model(obj, backend=backend, background=background)


def _check_options(method, step, projection, baumgarte, model):
    if method not in METHODS:
        raise InputError(f"method: unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if method in FIXED_STEP_METHODS and step is None:
        raise InputError(f"step: method {method!r} is fixed-step and needs step=...")
    if model.forced and method in ("rattle", "rattle4"):
        raise InputError(f"method: {method!r} is a structure-preserving scheme for "
                         f"conservative systems; this system has forces (choose an adaptive "
                         f"method such as DOP853)", key="method")
    require_autonomous("method", model.time_slot is not None and (
        method in FIXED_STEP_METHODS or method == "reference"), method=method)
    model.require_inputs()
    if (projection or baumgarte is not None) and method in ("rattle", "rattle4", "reference"):
        raise InputError(f"projection/baumgarte: not applicable to method {method!r} "
                         f"(it keeps the constraints itself)")
    if baumgarte is not None:
        if len(baumgarte) != 2 or not all(math.isfinite(float(x)) and float(x) >= 0
                                          for x in baumgarte):
            raise InputError(f"baumgarte: expected (alpha, beta) with alpha, beta >= 0, got "
                             f"{baumgarte!r}")
        if model.path != "saddle":
            raise InputError("baumgarte: needs the saddle path (path='saddle')")


def _width(n, method) -> int:
    """Numbers a loop keeps per state: the state, and the work of the forces
    where the loop carries it (all but RATTLE)."""
    return 2 * n + (0 if method in ("rattle", "rattle4") else 1)


def storage_plan(n: int, method: str, save_every: int = 1, max_points=None) -> str:
    """What a run of ``method`` on n coordinates will keep, and the memory that takes at
    most (without t_eval)."""
    width = _width(n, method)
    bound = default_max_points(width) if max_points is None else int(max_points)
    kept = "every step" if save_every == 1 else f"one step in {save_every}"
    return f"keeps {kept}, at most {bound} states: {memory_text(storage_bytes(bound, width))}"


def _recorder(model, method, t_eval, save_every, max_points) -> Recorder:
    """Where the loop puts the states: the t_eval points (refused beyond max_points),
    or every save_every-th step within max_points."""
    width = _width(model.n, method)
    bound = default_max_points(width) if max_points is None else int(max_points)
    if t_eval is not None and method in FIXED_STEP_METHODS:
        raise InputError(f"t_eval: the fixed-step method {method!r} keeps its grid points "
                         f"(every save_every-th step); t_eval is for the adaptive methods")
    if t_eval is not None and method != "reference":
        points = len(np.atleast_1d(t_eval))
        check_plan(points, bound, width, "t_eval")
        return Recorder(width, max(2, points), thin=False)
    if int(save_every) != save_every:
        raise InputError(f"save_every: a positive whole number of steps, got {save_every!r}")
    return Recorder(width, bound, int(save_every))


def _check_scipy_only(method, dense_output, events):
    if (dense_output or events is not None) and method not in SCIPY_METHODS:
        raise InputError(f"dense_output/events: only with the scipy methods "
                         f"({', '.join(SCIPY_METHODS)}), not {method!r}")


def _use_compiled_loop(model, method, loop, scipy_features=False) -> bool:
    if loop not in _LOOPS:
        raise InputError(f"loop: expected one of {', '.join(_LOOPS)}, got {loop!r}")
    possible = (method in COMPILED_METHODS and model.compiled is not None
                and model.path == "saddle" and not scipy_features)
    if loop == "compiled" and not possible:
        why = (f"it is for {', '.join(COMPILED_METHODS)}, not {method!r}"
               if method not in COMPILED_METHODS else
               f"the model has no compiled C backend ({model.backend_note})"
               if model.compiled is None else "the compiled loop needs the saddle path"
               if model.path != "saddle" else "dense_output and events run scipy's loop")
        raise InputError(f"loop: 'compiled' is not possible: {why}")
    return possible and loop != "scipy"


def _initial_state(model, y0, project_initial, tol):
    y = model.state(y0)
    if not np.all(np.isfinite(y)):
        raise InconsistentInitialDataError(f"initial data: not finite: {y.tolist()}")
    scaled = model.scaled_residuals(y)
    if scaled.size == 0 or np.max(scaled) <= tol:
        return y, None
    raw = model.residuals(y)
    if not project_initial:
        shown = ", ".join(f"{name} = {r:.3g}" for name, r in zip(model.residual_names, raw)
                          if abs(r) > 0)
        raise InconsistentInitialDataError(
            f"initial data violate the constraints: {shown} (scaled residual "
            f"{np.max(scaled):.3g} > {tol:.1e}); pass project_initial=True to project them "
            f"onto M_1")
    outcome = model.project(y)
    return outcome.y, outcome
