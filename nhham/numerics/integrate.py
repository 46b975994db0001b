"""``simulate``: every integration method behind one function, with diagnostics.

Methods
-------
The methods are the records of :data:`nhham.numerics.methods.METHODS` (name, family,
order, what each takes); ``simulate`` reads them to check the options and to choose the
loop. By family:

adaptive: RK23, RK45, DOP853, Radau, BDF, LSODA
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
fixed-step: rattle, rattle4, rk4
    Fixed step ``step`` (:mod:`nhham.numerics.integrators`): the structure-preserving
    nonholonomic RATTLE scheme (order 2), its triple-jump composition
    (order 4), classical RK4 (with ``projection``/``baumgarte`` if asked).
reference
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

from nhham.autonomy import TIME_IN_GEOMETRY, require_autonomous
from nhham.errors import ComputationError, InconsistentInitialDataError, InputError
from nhham.numerics.compiled_loop import run_compiled
from nhham.numerics.diagnostics import (Diagnostics, Singularity, singularity_at,
                                        trajectory_diagnostics)
from nhham.numerics.model import (LibraryReady, NumericModel, NumericsWarning,
                                  ProjectionOutcome)
from nhham.numerics.run import Deadline, Run, final_state_text, interruptible
from nhham.numerics.method_choice import choice_for
from nhham.numerics.methods import DEFAULT_METHOD, METHODS, Method, lookup, names
from nhham.numerics.scipy_loop import DenseOutput, run_scipy
from nhham.numerics.simulate_options import (AdaptiveOptions, FixedStepOptions, MethodOptions,
                                             ReferenceOptions, RunOptions, split_options)
from nhham.numerics.status import Status
from nhham.numerics.storage import (Recorder, Storage, check_plan, default_max_points,
                                    storage_plan)

__all__ = ["simulate", "SimulationResult", "METHODS", "RunOptions", "AdaptiveOptions",
           "FixedStepOptions", "ReferenceOptions", "storage_plan"]

_LOOPS = ("auto", "compiled", "scipy")


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
        0 success; 1 a terminal event stopped the run; -1 step failure; -2 NaN/overflow;
        -3 singular saddle-point system; -4 Newton/projection failure; -5 stopped at
        ``time_limit``; -6 interrupted (Ctrl-C). The trajectory up to there is kept.
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
        ``energy_balance_residual``, ``cond_C_max``, ``cond_W_max``, ``kkt_solve``: the
        solve of the constrained accelerations, "null-space").
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

    Examples
    --------
    x'' = -x from x = 1 in four RK4 steps: x(t) = cos t to four places.

    >>> import numpy as np
    >>> from nhham import System, simulate
    >>> spring = System(["x"], "x_dot**2/2 - x**2/2")
    >>> run = simulate(spring, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rk4",
    ...                step=0.25, backend="numpy")
    >>> run.t, run.names, run.y.shape, run.success
    (array([0.  , 0.25, 0.5 , 0.75, 1.  ]), ('x', 'x_dot'), (2, 5), True)
    >>> np.round(run["x"], 4)
    array([1.    , 0.9689, 0.8776, 0.7317, 0.5403])
    >>> np.round(np.cos(run.t), 4)
    array([1.    , 0.9689, 0.8776, 0.7317, 0.5403])
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
        if model is None:   # a result read back from a file
            raise ComputationError("the multipliers need the run's model; a result read "
                                   "from a file has none (simulate again to have them)")
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
        chosen = self.settings.get("method_choice")
        lines = [
            f"{self.method}: {self.message} (status {self.status}) at t = {self.t[-1]:.6g}",
            *([f"  chosen by auto: {chosen['reason']}"] if chosen else []),
            f"  steps {self.nsteps}, right-hand-side evaluations {self.nfev}, "
            f"wall time {self.wall_time_s:.3g} s, {self.settings.get('backend')} backend",
            f"  max constraint residual {d.constraint_residual_max:.2e} "
            f"(scaled {d.constraint_residual_rel_max:.2e})",
            f"  energy drift {d.energy_drift:.2e} (relative {d.energy_drift_rel:.2e}), "
            f"energy balance residual {d.energy_balance_residual:.2e}",
            f"  max cond(C) {d.cond_C_max:.3g}, max cond(W) {d.cond_W_max:.3g}",
        ]
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
        lines.append(final_state_text(self.final_state))
        return "\n".join(lines)

    def save(self, path) -> str:
        """Write t and the states: ``.npz`` (numpy) or otherwise CSV with a header."""
        from nhham.numerics.storage import save_states

        return save_states(path, self.t, self.y, self.names, self.energy, self.work)

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


def simulate(system_or_model, t_span, y0, *, method: str | Method = DEFAULT_METHOD,
             options: RunOptions | None = None, method_options: MethodOptions | None = None,
             **keywords) -> SimulationResult:
    """Integrate the constrained dynamics from ``y0`` over ``t_span``.

    Parameters
    ----------
    system_or_model : nhham.System, sympy.physics.mechanics.System or NumericModel
    t_span : (float, float)
        Start and end (``t_span`` before ``y0``, as in scipy's ``solve_ivp``).
    y0 : mapping or array_like
        Shape (2n,), or ``{name: value}``: with a System the names may be dynamicsymbols
        or a mechanics model's speeds, and only the independent entries are needed
        (:mod:`nhham.system.state_keys`).
    method : str or Method
        One of :data:`~nhham.numerics.methods.METHODS`, or ``"auto"``: chosen from the
        system (:mod:`nhham.numerics.method_choice`; ``settings["method_choice"]``).
    options : RunOptions, optional
        The options every method takes (below); a keyword overrides its field.
    method_options : AdaptiveOptions, FixedStepOptions or ReferenceOptions, optional
        The options of the method's family (below); a keyword overrides its field; one
        the method does not take is refused, as a fixed-step method without ``step``.

    Other Parameters
    ----------------
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
        Digits of the reference method (default 30).
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
    warn, progress : bool
        Warn of the diagnostics (:class:`NumericsWarning`); report each tenth of t_span
        on stderr (not the reference method).
    loop : {"auto", "compiled", "scipy"}
        RK23, RK45, DOP853: ``"auto"`` runs the whole integration as one
        compiled loop when the model has the compiled backend (saddle path),
        else scipy's Python loop; ``"compiled"`` insists (InputError if
        impossible); ``"scipy"`` always uses scipy's loop. Both give the same
        steps up to round-off. ``result.settings["loop"]`` says which ran.
    time_limit : float, optional
        Wall seconds after which the run stops (``Status.TIME_LIMIT``, keeping it so far).
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
    TypeError
        For a keyword that is not an option.

    Examples
    --------
    A particle on a line, x'' = -x from x = 1: x(1) = cos 1.

    >>> import math, nhham
    >>> from nhham import simulate
    >>> from nhham.numerics.simulate_options import FixedStepOptions, RunOptions
    >>> spring = nhham.System(["x"], "x_dot**2/2 - x**2/2")
    >>> run = simulate(spring, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rk4", step=0.01,
    ...                backend="numpy")
    >>> bool(abs(run["x"][-1] - math.cos(1.0)) < 1e-9)
    True
    >>> same = simulate(spring, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rk4",
    ...                 options=RunOptions(backend="numpy"),
    ...                 method_options=FixedStepOptions(step=0.01))
    >>> bool((same.y == run.y).all())
    True
    >>> simulate(spring, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rk4", step=0.01,
    ...          rtol=1e-6)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.InputError: rtol applies to the adaptive methods, not to the fixed-step ...
    """
    if method == "auto":   # a method chosen from the system and the request
        choice = choice_for(system_or_model, t_span, y0, options, method_options, keywords)
        result = simulate(system_or_model, t_span, y0, method=choice.method, options=options,
                          method_options=method_options, **{**keywords, **choice.options})
        return replace(result, settings=MappingProxyType({**result.settings,
                                                          "method_choice": choice.to_dict()}))
    spec = lookup(method)
    common, own = split_options(spec, options, method_options, **keywords)
    if hasattr(y0, "keys") and not isinstance(system_or_model, NumericModel):
        from nhham.numerics.codegen import system_and_state  # the user's names, solved
        system_or_model, y0 = system_and_state(system_or_model, y0)
    contacts, controls = common.contacts, common.controls
    if contacts and isinstance(system_or_model, NumericModel):
        raise InputError("simulate: contacts need the System (its constraints' velocity "
                         "maps), not a NumericModel", key="contacts")
    system_or_model, callables = _with_controls(system_or_model, controls, spec, contacts)
    loop = "scipy" if callables else common.loop
    model = _as_model(system_or_model, common.backend,
                      background=spec.background_build and loop != "compiled")
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
    _check_model(spec, common.baumgarte, model)
    scipy_features = common.dense_output or common.events is not None
    compiled_loop = _use_compiled_loop(model, spec, loop, scipy_features)
    # on M_1(t0) when t enters the constraints (at_time: the model itself otherwise)
    y_init, initial = _initial_state(model.at_time(t0), y0, common.project_initial,
                                     common.initial_tol)
    recorder = _recorder(model, spec, common)
    settings = _settings(spec, own, common, model, recorder)
    residual_tol = common.residual_tol
    if residual_tol is None:
        residual_tol = 1e-11 if common.projection or spec.keeps_constraints else 1e-8
    start = time.perf_counter()
    deadline = Deadline.after(common.time_limit)
    with interruptible():   # a Ctrl-C stops the run keeping its states (INTERRUPTED)
        run, model, recorder = _run_loop(model, spec, own, common, y_init, t0, t1, recorder,
                                         settings, deadline, compiled_loop, loop,
                                         scipy_features, callables)
    wall = time.perf_counter() - start
    storage = None if spec.reference else recorder.storage(common.t_eval is not None)
    result = _result(model, run, spec.name, settings, wall, residual_tol, initial,
                     common.warn, storage)
    if callables:
        result = replace(result, controls=MappingProxyType(dict(callables)))
    if not contacts:
        return result
    from nhham.numerics.contact_forces import contact_forces

    return replace(result, contact_forces=contact_forces(
        system_or_model, contacts, result.states, result.multipliers.T,
        parameters=dict(zip(model.parameter_names, model.parameter_values))))


def _run_loop(model, spec, own, common, y_init, t0, t1, recorder, settings, deadline,
              compiled_loop, loop, scipy_features, callables):
    """(run, model, recorder): the run in its loop, again compiled if the build wins."""
    while True:
        try:
            if compiled_loop:
                settings["loop"] = "compiled"
                run = run_compiled(model, y_init, t0, t1, spec.name, recorder=recorder,
                                   **_adaptive(own, common, deadline))
            elif spec.adaptive:
                settings["loop"] = "scipy"
                run = run_scipy(model, y_init, t0, t1, spec.name,
                                dense_output=common.dense_output, events=common.events,
                                recorder=recorder, controls=callables,
                                **_adaptive(own, common, deadline))
            elif spec.fixed_step:
                assert isinstance(own, FixedStepOptions)
                opts = {"recorder": recorder, "progress": common.progress,
                        "deadline": deadline}
                if spec.takes_projection:
                    opts.update(projection=common.projection, baumgarte=common.baumgarte)
                if spec.needs_reduction:
                    opts["reduced"] = common.reduced
                run = spec.load()(model, y_init, t0, t1, float(own.step), **opts)
                settings.update(step=run.step, newton_iterations=run.newton_iterations)
            else:
                assert isinstance(own, ReferenceOptions)
                run = _run_reference(spec, model, y_init, t0, t1, own.digits, common.t_eval,
                                     settings)
            break
        except LibraryReady:  # the background build won: the whole run on compiled code
            model = model.with_library()
            compiled_loop = _use_compiled_loop(model, spec, loop, scipy_features)
            settings.update(backend=model.backend, backend_note=model.backend_note)
            recorder = _recorder(model, spec, common)
    return run, model, recorder


def _adaptive(own, common, deadline) -> dict:
    """The keywords of the adaptive loops."""
    assert isinstance(own, AdaptiveOptions)
    return dict(rtol=own.rtol, atol=own.atol, max_step=own.max_step,
                first_step=own.first_step, t_eval=common.t_eval,
                projection=common.projection, baumgarte=common.baumgarte,
                progress=common.progress, deadline=deadline)


def _settings(spec, own, common, model, recorder) -> dict:
    """``result.settings``. rtol and atol are listed for every method (the adaptive
    defaults for the others), step for every method (None for the adaptive ones), so
    that the JSON of every run has the same keys."""
    adaptive = own if isinstance(own, AdaptiveOptions) else AdaptiveOptions()
    baumgarte = common.baumgarte
    return {"rtol": adaptive.rtol, "atol": adaptive.atol,
            "step": own.step if isinstance(own, FixedStepOptions) else None,
            "projection": common.projection,
            "baumgarte": None if baumgarte is None else tuple(map(float, baumgarte)),
            "backend": model.backend, "backend_note": model.backend_note,
            "path": model.path, "save_every": int(common.save_every),
            "max_points": recorder.max_points}


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
    if callables and not method.scipy_loop:
        scipy = ", ".join(names(lambda m: m.scipy_loop, cheapest_first=True))
        raise InputError(f"controls: Python callables run with the scipy methods "
                         f"({scipy}), not {method.name!r}; give expressions to "
                         f"compile them with the field", key="controls")
    if callables and contacts:
        raise InputError("controls: contact forces need the inputs as expressions (the "
                         "multipliers at the stored states)", key="controls")
    return system_or_model, callables


def _run_reference(spec, model, y0, t0, t1, digits, t_eval, settings) -> Run:
    digits = int(digits)
    ref = spec.load()(model, y0, (t0, t1), digits=digits, t_eval=t_eval)
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


def _check_model(spec, baumgarte, model):
    """What the method needs of the model (the options are checked by
    :func:`~nhham.numerics.simulate_options.check_method_options`)."""
    require_autonomous("method", model.time_in_geometry and not spec.takes_time,
                       method=spec.name, what=TIME_IN_GEOMETRY)
    if model.forced and not spec.takes_forces:
        raise InputError(f"method: {spec.name!r} is {spec.forces_refused}; this system has "
                         f"forces (choose an adaptive method such as {DEFAULT_METHOD})",
                         key="method")
    require_autonomous("method", model.time_slot is not None and not spec.takes_time,
                       method=spec.name)
    if model.nonlinear and not spec.takes_nonlinear:
        raise InputError(f"method {spec.name!r} takes no constraint nonlinear in the "
                         f"velocities: {spec.nonlinear_refused}; use an adaptive method "
                         f"such as {DEFAULT_METHOD}", key="method")
    if spec.needs_quadratic and not model.quadratic and not (
            spec.takes_gyroscopic and model.layout.get("linear_terms")):
        linear = "" if spec.takes_gyroscopic else "no terms linear in the velocities, "
        raise InputError(f"method {spec.name!r} needs L = 1/2 v^T W(q) v - V(q) ({linear}W "
                         f"independent of v); use a scipy method for this system",
                         key="method")
    model.require_inputs()
    if baumgarte is not None:
        if len(baumgarte) != 2 or not all(math.isfinite(float(x)) and float(x) >= 0
                                          for x in baumgarte):
            raise InputError(f"baumgarte: expected (alpha, beta) with alpha, beta >= 0, got "
                             f"{baumgarte!r}")
        if model.path != "saddle":
            raise InputError("baumgarte: needs the saddle path (path='saddle')")


def _recorder(model, spec, common) -> Recorder:
    """Where the loop puts the states: the t_eval points (refused beyond max_points),
    or every save_every-th step within max_points."""
    t_eval, save_every, max_points = common.t_eval, common.save_every, common.max_points
    width = 2 * model.n + (1 if spec.carries_work else 0)
    bound = default_max_points(width) if max_points is None else int(max_points)
    if t_eval is not None and not spec.reference:
        points = len(np.atleast_1d(t_eval))
        check_plan(points, bound, width, "t_eval")
        return Recorder(width, max(2, points), thin=False)
    if int(save_every) != save_every:
        raise InputError(f"save_every: a positive whole number of steps, got {save_every!r}")
    return Recorder(width, bound, int(save_every))


def _use_compiled_loop(model, spec, loop, scipy_features=False) -> bool:
    if loop not in _LOOPS:
        raise InputError(f"loop: expected one of {', '.join(_LOOPS)}, got {loop!r}")
    possible = (spec.compiled_loop and model.compiled is not None
                and model.path == "saddle" and not scipy_features)
    if loop == "compiled" and not possible:
        compiled = ", ".join(names(lambda m: m.compiled_loop, cheapest_first=True))
        why = (f"it is for {compiled}, not {spec.name!r}"
               if not spec.compiled_loop else
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

