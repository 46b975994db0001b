"""``simulate``: every integration method behind one function, with diagnostics.

Methods
-------
``"RK23"``, ``"RK45"``, ``"DOP853"``, ``"Radau"``, ``"BDF"``, ``"LSODA"``
    The :mod:`scipy.integrate` solvers on the projected field (stepped here,
    so that a failure keeps the trajectory computed so far). With the
    compiled backend, RK23, RK45 and DOP853 run as one compiled loop instead
    (``loop="auto"``): scipy's algorithm (its coefficients, initial step,
    error norm, step-size control and dense output) with the projection and
    the storage done in C too, so no Python runs per step; ``loop="scipy"``
    keeps scipy's own Python loop (same steps up to round-off). Options:
    ``projection=True`` projects onto M_1 after every step (velocities in the
    kinetic metric, position constraints by Newton iteration);
    ``baumgarte=(alpha, beta)`` replaces d(phi)/dt = 0 by
    d(phi)/dt = -2 alpha phi - beta^2 g. Implicit methods get their
    finite-difference Jacobian from one batched evaluation.
``"rattle"``, ``"rattle4"``, ``"rk4"``
    Fixed step ``step`` (:mod:`nhham.integrators`): the structure-preserving
    nonholonomic RATTLE scheme (order 2), its triple-jump composition
    (order 4), classical RK4 (with ``projection``/``baumgarte`` if asked).
``"reference"``
    High-precision extrapolation in mpmath with ``reference_digits`` digits
    (:mod:`nhham.reference`), for measuring errors.

The integrators never import sympy: a System is turned into a
:class:`~nhham.numeric.NumericModel` by :func:`nhham.codegen.numeric_model`
(the one bridge), or a model is passed directly.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, Radau

from nhham.numerics.diagnostics import Diagnostics, trajectory_diagnostics
from nhham.errors import InconsistentInitialDataError, InputError
from nhham.numerics.integrators import FIXED_STEP_METHODS, run_fixed_step
from nhham.numerics.model import NumericModel, NumericsWarning, ProjectionOutcome

__all__ = ["simulate", "SimulationResult", "SCIPY_METHODS", "COMPILED_METHODS", "METHODS"]


SCIPY_METHODS = {"RK23": RK23, "RK45": RK45, "DOP853": DOP853, "Radau": Radau, "BDF": BDF,
                 "LSODA": LSODA}
#: scipy methods that also run as one compiled loop (``loop="compiled"``).
COMPILED_METHODS = ("RK23", "RK45", "DOP853")
_LOOPS = ("auto", "compiled", "scipy")
METHODS = tuple(SCIPY_METHODS) + tuple(FIXED_STEP_METHODS) + ("reference",)

# The work integral rides along as an extra state; it must not steer the
# step size, so its absolute tolerance is huge (finite: scipy's numerical
# Jacobian scales its perturbation by atol).
_WORK_ATOL = 1e100

STATUS = MappingProxyType({
    0: "reached the end of the interval",
    -1: "integration step failed",
    -2: "non-finite or overflowing state",
    -3: "singular saddle-point system",
    -4: "nonlinear iteration or projection failed",
})


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Trajectory and diagnostics, in the style of scipy's ``OdeResult``.

    Attributes
    ----------
    t : ndarray, shape (K,)
    y : ndarray, shape (2n, K)
        As in scipy: ``y[i]`` is the i-th state variable over time (names in
        :attr:`names`: coordinates then velocities). ``states`` gives (K, 2n).
    status : int
        0 success; -1 step failure; -2 NaN/overflow (run stopped); -3 singular
        saddle-point system; -4 Newton/projection failure. The trajectory up to
        the failure is kept.
    message : str
    success : bool
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
        See :class:`nhham.diagnostics.Diagnostics`; its main fields are also
        attributes here (``constraint_residual_max``, ``energy_drift``,
        ``energy_balance_residual``, ``cond_C_max``, ``cond_W_max``).
    warnings : tuple of str
        Also issued as :class:`~nhham.numeric.NumericsWarning` unless
        ``warn=False`` was passed.
    initial_projection : ProjectionOutcome or None
        When the initial data were projected onto M_1: by how much.
    """

    t: np.ndarray
    y: np.ndarray
    status: int
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

    @property
    def success(self) -> bool:
        return self.status == 0

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
    energy = property(lambda self: self.diagnostics.energy)
    work = property(lambda self: self.diagnostics.work)

    @cached_property
    def multipliers(self) -> np.ndarray:
        """lambda at the stored states, shape (m, K) (continuous-field values)."""
        return np.atleast_2d(self.model.multipliers(self.states)).T

    def describe(self) -> str:
        """A few human-readable lines: status, cost and diagnostics."""
        d = self.diagnostics
        lines = [
            f"{self.method}: {self.message} (status {self.status}) at t = {self.t[-1]:.6g}",
            f"  steps {self.nsteps}, right-hand-side evaluations {self.nfev}, "
            f"wall time {self.wall_time_s:.3g} s",
            f"  max constraint residual {d.constraint_residual_max:.2e} "
            f"(scaled {d.constraint_residual_rel_max:.2e})",
            f"  energy drift {d.energy_drift:.2e} (relative {d.energy_drift_rel:.2e}), "
            f"energy balance residual {d.energy_balance_residual:.2e}",
            f"  max cond(C) {d.cond_C_max:.3g}, max cond(W) {d.cond_W_max:.3g}",
        ]
        if self.initial_projection is not None:
            p = self.initial_projection
            lines.append(f"  initial data projected onto M_1: residual {p.residual_before:.2e} -> "
                         f"{p.residual_after:.2e}, |dq| = {p.displacement_q:.2e}, "
                         f"|dv| = {p.displacement_v:.2e}")
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
            "method": self.method, "status": self.status, "message": self.message,
            "success": self.success, "t_end": float(self.t[-1]), "steps": self.nsteps,
            "nfev": self.nfev, "njev": self.njev, "nlu": self.nlu,
            "wall_time_s": self.wall_time_s,
            "constraint_residual_max": d.constraint_residual_max,
            "constraint_residual_rel_max": d.constraint_residual_rel_max,
            "energy_drift": d.energy_drift, "energy_drift_rel": d.energy_drift_rel,
            "energy_balance_residual": d.energy_balance_residual,
            "cond_C_max": d.cond_C_max, "cond_W_max": d.cond_W_max,
            "warnings": list(self.warnings), "final_state": self.final_state,
            "settings": dict(self.settings),
        }
        if self.initial_projection is not None:
            p = self.initial_projection
            out["initial_projection"] = {
                "residual_before": p.residual_before, "residual_after": p.residual_after,
                "displacement_q": p.displacement_q, "displacement_v": p.displacement_v}
        return out


def simulate(system_or_model, y0, t_span, *, method: str = "DOP853", rtol: float = 1e-9,
             atol: float = 1e-12, step: float | None = None, t_eval=None,
             max_step: float = np.inf, first_step: float | None = None,
             projection: bool = False, baumgarte=None, project_initial: bool = False,
             initial_tol: float = 1e-10, residual_tol: float | None = None,
             reference_digits: int | None = None, save_every: int = 1,
             backend: str = "auto", warn: bool = True, progress: bool = False,
             loop: str = "auto") -> SimulationResult:
    """Integrate the constrained dynamics from ``y0`` over ``t_span``.

    Parameters
    ----------
    system_or_model : nhham.System or NumericModel
    y0 : mapping or array_like
        ``{name: value}`` for every coordinate and velocity, or shape (2n,).
    t_span : (float, float)
    method : str
        One of :data:`METHODS` (see the module docstring).
    rtol, atol : float
        Tolerances of the adaptive methods.
    step : float
        Step of the fixed-step methods (required for them).
    t_eval : array_like, optional
        Output times (adaptive and reference methods); default every step.
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
    residual_tol : float, optional
        Scaled residual above which a warning is given (default 1e-8 for
        unprojected adaptive methods, 1e-11 for projected and structure-
        preserving ones).
    reference_digits : int, optional
        Digits of the ``"reference"`` method (default 30).
    save_every : int
        Fixed-step methods: store every j-th step.
    backend : str
        Backend when a System is given (see :func:`nhham.codegen.numeric_model`).
    warn : bool
        Issue the diagnostics' warnings as :class:`NumericsWarning`.
    progress : bool
        Report progress of the adaptive methods on stderr (every 10% of t_span).
    loop : {"auto", "compiled", "scipy"}
        RK23, RK45, DOP853: ``"auto"`` runs the whole integration as one
        compiled loop when the model has the compiled backend (saddle path),
        else scipy's Python loop; ``"compiled"`` insists (InputError if
        impossible); ``"scipy"`` always uses scipy's loop. Both give the same
        steps up to round-off. ``result.settings["loop"]`` says which ran.

    Returns
    -------
    SimulationResult

    Raises
    ------
    InconsistentInitialDataError
        If ``y0`` violates the constraints (the residuals are shown) and
        ``project_initial`` is False, or names are missing.
    InputError
        For an unknown method or inconsistent options.
    """
    model = _as_model(system_or_model, backend)
    t0, t1 = (float(t_span[0]), float(t_span[1]))
    if not (math.isfinite(t0) and math.isfinite(t1)) or t1 == t0:
        raise InputError(f"t_span: need two different finite times, got {t_span!r}")
    _check_options(method, step, projection, baumgarte, model)
    compiled_loop = _use_compiled_loop(model, method, loop)
    y_init, initial = _initial_state(model, y0, project_initial, initial_tol)
    settings = {"rtol": rtol, "atol": atol, "step": step, "projection": projection,
                "baumgarte": None if baumgarte is None else tuple(map(float, baumgarte)),
                "backend": model.backend, "path": model.path}
    if residual_tol is None:
        exact = projection or method in ("rattle", "rattle4", "reference")
        residual_tol = 1e-11 if exact else 1e-8

    start = time.perf_counter()
    if compiled_loop:
        settings["loop"] = "compiled"
        run = _run_compiled(model, y_init, t0, t1, method, rtol, atol, max_step, first_step,
                            t_eval, projection, baumgarte, progress)
    elif method in SCIPY_METHODS:
        settings["loop"] = "scipy"
        run = _run_scipy(model, y_init, t0, t1, method, rtol, atol, max_step, first_step,
                         t_eval, projection, baumgarte, progress)
    elif method in FIXED_STEP_METHODS:
        opts = {"save_every": int(save_every)}
        if method == "rk4":
            opts.update(projection=projection, baumgarte=baumgarte)
        fs = run_fixed_step(method, model, y_init, t0, t1, float(step), **opts)
        settings["step"] = fs.step
        run = _Run(fs.t, fs.y, fs.work, fs.status, fs.message, fs.nfev, 0, 0, fs.nsteps)
        settings["newton_iterations"] = fs.newton_iterations
    else:
        from nhham.numerics.reference import reference_solution

        digits = 30 if reference_digits is None else int(reference_digits)
        ref = reference_solution(model, y_init, (t0, t1), digits=digits, t_eval=t_eval)
        settings.update(digits=digits, tol=ref.tol, error_estimate=ref.error_estimate)
        run = _Run(ref.t, ref.y, ref.work, ref.status, ref.message, ref.nfev, 0, 0, ref.nsteps)
    wall = time.perf_counter() - start

    diag = trajectory_diagnostics(model, run.t, run.y, run.work, residual_tol=residual_tol)
    notes = list(diag.warnings)
    if run.status != 0:
        notes.insert(0, f"run stopped: {run.message}")
    if warn:
        for note in notes:
            warnings.warn(note, NumericsWarning, stacklevel=2)
    return SimulationResult(
        t=run.t, y=run.y.T.copy(), status=run.status, message=run.message, method=method,
        settings=MappingProxyType(settings), names=model.names, nfev=run.nfev,
        njev=run.njev, nlu=run.nlu, nsteps=run.nsteps, wall_time_s=wall, diagnostics=diag,
        warnings=tuple(notes), initial_projection=initial, model=model)


# ------------------------------------------------------------------ helpers
@dataclass
class _Run:
    t: np.ndarray
    y: np.ndarray
    work: np.ndarray | None
    status: int
    message: str
    nfev: int
    njev: int
    nlu: int
    nsteps: int


def _as_model(obj, backend) -> NumericModel:
    if isinstance(obj, NumericModel):
        return obj
    from nhham.numerics.codegen import numeric_model  # the one bridge from sympy

    return numeric_model(obj, backend=backend)


def _check_options(method, step, projection, baumgarte, model):
    if method not in METHODS:
        raise InputError(f"method: unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if method in FIXED_STEP_METHODS and step is None:
        raise InputError(f"step: method {method!r} is fixed-step and needs step=...")
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


def _use_compiled_loop(model, method, loop) -> bool:
    if loop not in _LOOPS:
        raise InputError(f"loop: expected one of {', '.join(_LOOPS)}, got {loop!r}")
    possible = (method in COMPILED_METHODS and model.compiled is not None
                and model.path == "saddle")
    if loop == "compiled" and not possible:
        why = (f"it is for {', '.join(COMPILED_METHODS)}, not {method!r}"
               if method not in COMPILED_METHODS else
               f"the model has no compiled C backend ({model.backend_note})"
               if model.compiled is None else "the compiled loop needs the saddle path")
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


class _Stop(Exception):
    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def _make_fun(model, baumgarte, counter):
    n2 = 2 * model.n
    field = model.field_function(baumgarte)

    def fun(t, z):
        if z.ndim == 1:
            out = field(z)
            counter[0] += 1
            if type(out) is int:
                raise _Stop(*_eval_failure(out, t, z[:n2]))
            return out
        # Vectorised call (scipy's finite-difference Jacobian): z is (2n+1, k).
        dY, _, P, status = model.evaluate(np.ascontiguousarray(z[:n2].T), baumgarte)
        counter[0] += z.shape[1]
        if status:
            raise _Stop(*_eval_failure(status, t, z[:n2, 0]))
        return np.vstack([dY.T, np.atleast_1d(P)[None, :]])

    return fun


def _eval_failure(status, t, y):
    if status == 1:
        return -3, f"singular saddle-point system at t = {t:.6g} (cond(C) is infinite)"
    return -2, (f"non-finite right-hand side (NaN or overflow) at t = {t:.6g}; the run was "
                f"stopped (state max |y| = {float(np.max(np.abs(y))):.3g})")


def _run_scipy(model, y0, t0, t1, method, rtol, atol, max_step, first_step, t_eval,
               projection, baumgarte, progress=False) -> _Run:
    n2 = 2 * model.n
    counter = [0]
    fun = _make_fun(model, baumgarte, counter)
    atol_z = np.append(np.broadcast_to(np.asarray(atol, dtype=float), (n2,)), _WORK_ATOL)
    cls = SCIPY_METHODS[method]
    opts = {"rtol": rtol, "atol": atol_z, "max_step": max_step}
    if method in ("Radau", "BDF"):
        opts["vectorized"] = True
    if first_step is not None:
        opts["first_step"] = first_step
    z0 = np.append(y0, 0.0)
    t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
    ts, zs = [t0], [z0.copy()]
    if t_eval is not None:
        ts, zs = ([t0], [z0.copy()]) if np.isclose(t_eval[0], t0) else ([], [])
        next_eval = len(ts)
    status, message, nsteps = 0, STATUS[0], 0
    njev = nlu = 0
    reported = 0
    try:
        solver = cls(fun, t0, z0, t1, **opts)
        while solver.status == "running":
            msg = solver.step()
            if solver.status == "failed":
                status, message = -1, f"{method} failed at t = {solver.t:.6g}: {msg}"
                break
            nsteps += 1
            z = solver.y
            if not np.all(np.isfinite(z[:n2])) or np.max(np.abs(z[:n2])) > 1e150:
                raise _Stop(-2, f"non-finite or overflowing state at t = {solver.t:.6g}; "
                                f"the run was stopped")
            if projection:
                solver = _project_solver(solver, model, fun, cls, t1, opts)
            if t_eval is None:
                ts.append(solver.t)
                zs.append(solver.y.copy())
            else:
                next_eval = _collect_eval(solver, t_eval, next_eval, ts, zs, model, projection,
                                          t0, t1)
            njev = max(njev, getattr(solver, "njev", 0))
            nlu = max(nlu, getattr(solver, "nlu", 0))
            if progress:
                reported = _report(solver.t, t0, t1, reported)
    except _Stop as exc:
        status, message = exc.status, str(exc)
    except np.linalg.LinAlgError as exc:
        status, message = -3, f"singular linear system: {exc}"
    except Exception as exc:  # projection Newton failure and the like
        from nhham.errors import ComputationError

        if not isinstance(exc, ComputationError):
            raise
        status, message = -4, str(exc)
    Z = np.array(zs) if zs else np.zeros((0, n2 + 1))
    return _Run(np.array(ts), Z[:, :n2], Z[:, n2], status, message, counter[0], njev, nlu,
                nsteps)


_TABLEAUX: dict = {}
_EXTRA_STAGES = 16  # DOP853's stages with the dense-output extras (SEXT in the C source)


def _tableau(method):
    """(info, coefficients) of scipy's class for ``nhham_erk`` (see its C comment)."""
    if method not in _TABLEAUX:
        cls = SCIPY_METHODS[method]
        s = cls.n_stages
        A = np.zeros((s, s))
        A0 = np.asarray(cls.A, dtype=float)
        A[:, :A0.shape[1]] = A0[:s]
        B, C = np.asarray(cls.B, dtype=float), np.asarray(cls.C, dtype=float)[:s]
        if method == "DOP853":
            E, E3, P = cls.E5, cls.E3, np.zeros((s + 1, 0))
            Aext, Cext, D = cls.A_EXTRA, cls.C_EXTRA, cls.D
        else:
            E, E3, P = cls.E, np.zeros(s + 1), np.asarray(cls.P, dtype=float)
            Aext, Cext, D = (np.zeros((3, _EXTRA_STAGES)), np.zeros(3),
                             np.zeros((4, _EXTRA_STAGES)))
        tab = np.concatenate([A.ravel(), B, C, np.asarray(E, dtype=float), E3, P.ravel(),
                              np.asarray(Aext, dtype=float).ravel(), Cext,
                              np.asarray(D, dtype=float).ravel()])
        info = np.array([s, method == "DOP853", P.shape[1], cls.error_estimator_order, 1],
                        dtype=np.intc)
        _TABLEAUX[method] = (info, np.ascontiguousarray(tab))
    info, tab = _TABLEAUX[method]
    return info.copy(), tab


def _run_compiled(model, y0, t0, t1, method, rtol, atol, max_step, first_step, t_eval,
                  projection, baumgarte, progress=False) -> _Run:
    """RK23/RK45/DOP853 as one compiled loop (``nhham_erk``): scipy's algorithm,
    projection and storage in C; Python only between chunks of stored steps."""
    n2 = 2 * model.n
    nz = n2 + 1
    # scipy's validation of the options
    if not max_step > 0:
        raise ValueError("`max_step` must be positive.")
    if first_step is not None:
        if first_step <= 0:
            raise ValueError("`first_step` must be positive.")
        if first_step > abs(t1 - t0):
            raise ValueError("`first_step` exceeds bounds.")
    eps = np.finfo(float).eps
    rtol = float(rtol)
    if rtol < 100 * eps:
        warnings.warn("At least one element of `rtol` is too small. "
                      f"Setting `rtol = np.maximum(rtol, {100 * eps})`.", stacklevel=3)
        rtol = 100 * eps
    info, tab = _tableau(method)
    a2, b2 = (0.0, 0.0) if baumgarte is None else (2.0 * baumgarte[0], baumgarte[1] ** 2)
    pext = model._pext(a2, b2)
    # ws = [t, h_abs, z, f | fail: t, z | atol]; iw = [t_eval index, stored, nfev, nsteps]
    ws = np.zeros(2 + 2 * nz + 1 + nz + nz)
    ws[0], ws[1] = t0, (-1.0 if first_step is None else float(first_step))
    ws[2:2 + n2] = y0
    ws[-nz:-1] = atol
    ws[-1] = _WORK_ATOL
    if np.any(ws[-nz:] < 0):
        raise ValueError("`atol` must be positive.")
    state, fail = ws[:2 + 2 * nz], ws[2 + 2 * nz:2 + 2 * nz + 1 + nz]
    z0 = state[2:2 + nz].copy()
    ts, zs = [np.array([t0])], [z0[None, :]]
    if t_eval is not None:
        t_eval = np.ascontiguousarray(t_eval, dtype=float)
        if not np.isclose(t_eval[0], t0):
            ts, zs = [], []
        cap = max(1, len(t_eval))
    else:
        cap = 256
    iw = np.array([len(ts), 0, 0, 0], dtype=np.int64)
    out_t, out_z = np.empty(cap), np.empty((cap, nz))
    reported = 0
    while True:
        t_pause = t1 if not progress else t0 + (t1 - t0) * min(1.0, (reported + 1) / 10)
        status = model.compiled.erk(info, tab, ws, iw, t1, rtol, float(max_step), projection,
                                    1e-14, 50, t_eval, out_t, out_z, t_pause, pext)
        info[4] = 0
        if t_eval is None:
            k = int(iw[1])
            ts.append(out_t[:k].copy())
            zs.append(out_z[:k].copy())
            iw[1] = 0
            if k == cap and cap < 65536:
                cap *= 4
                out_t, out_z = np.empty(cap), np.empty((cap, nz))
        if progress:
            reported = _report(state[0], t0, t1, reported)
        if status != 1:
            break
    if t_eval is not None:
        ts.append(out_t[:int(iw[1])])
        zs.append(out_z[:int(iw[1])])
    t_now = float(state[0])
    message = STATUS[0]
    if status == -1:
        status, message = -1, (f"{method} failed at t = {t_now:.6g}: Required step size is "
                               f"less than spacing between numbers.")
    elif status == -2:
        message = f"non-finite or overflowing state at t = {t_now:.6g}; the run was stopped"
    elif status in (-3, -5):
        status, message = _eval_failure(1 if status == -3 else 2, fail[0], fail[1:1 + n2])
    elif status == -4:
        message = (f"projection onto M_1 failed at t = {t_now:.6g}: the Newton iteration for "
                   f"the position constraints did not converge")
    elif status == -6:
        status, message = -3, (f"singular linear system in the projection onto M_1 at "
                               f"t = {t_now:.6g}")
    T = np.concatenate(ts) if ts else np.zeros(0)
    Z = np.concatenate(zs) if zs else np.zeros((0, nz))
    return _Run(T, Z[:, :n2], Z[:, n2], int(status), message, int(iw[2]), 0, 0, int(iw[3]))


def _report(t, t0, t1, reported):
    """Print each passed tenth of the interval on stderr; returns the tenths done."""
    import sys

    tenths = int(10 * (t - t0) / (t1 - t0))
    if tenths > reported:
        print(f"  t = {t:.6g} ({10 * tenths}%)", file=sys.stderr, flush=True)
    return max(reported, tenths)


def _collect_eval(solver, t_eval, i, ts, zs, model, projection, t0, t1):
    """Store the t_eval points inside the last step (from its dense output)."""
    forward = t1 > t0
    dense = None
    while i < len(t_eval) and ((t_eval[i] <= solver.t) if forward else (t_eval[i] >= solver.t)):
        if dense is None:
            dense = solver.dense_output()
        z = np.asarray(dense(t_eval[i]), dtype=float)
        if projection:
            z[:-1] = model.project(z[:-1]).y
        ts.append(float(t_eval[i]))
        zs.append(z)
        i += 1
    return i


def _project_solver(solver, model, fun, cls, t1, opts):
    """Project the solver's current state onto M_1 and make the solver consistent."""
    n2 = 2 * model.n
    z = solver.y.copy()
    z[:n2] = model.project(z[:n2]).y
    if isinstance(solver, LSODA):
        return _reset_lsoda(solver, z, fun, cls, t1, opts)
    solver.y = z
    if isinstance(solver, BDF):
        solver.D[0] = z
    if hasattr(solver, "f"):
        solver.f = fun(solver.t, z)
    return solver


def _reset_lsoda(solver, z, fun, cls, t1, opts):
    """Put a projected state into LSODA.

    LSODA keeps its Nordsieck history in the Fortran work array; its first
    column (rwork[20:20+N], the ODEPACK layout) is the current state. Replacing
    it keeps the history (order and step size) as for the other solvers. If the
    private layout is not there, restart from the projected state instead
    (correct, slower: the order drops to 1).
    """
    try:
        inner = solver._lsoda_solver
        work = inner._integrator.rwork
        if work.shape[0] < 20 + z.size:
            raise AttributeError("unexpected LSODA work array")
        work[20:20 + z.size] = z
        inner._y = z.copy()
        solver.y = z
        return solver
    except AttributeError:
        if solver.status != "running":
            solver.y = z
            return solver
        step = min(2 * solver.step_size, abs(t1 - solver.t))
        return cls(fun, solver.t, z, t1, **dict(opts, first_step=step))
