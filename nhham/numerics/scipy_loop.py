"""scipy's solvers stepped here: projection, ``t_eval``, dense output and events.

:func:`run_scipy` drives one of :mod:`scipy.integrate`'s ``OdeSolver`` classes step by
step on the projected field, so that a failure keeps the trajectory computed so far and
that every step can be projected onto M_1 (``projection=True``). The state carries one
extra entry, the work of the forces (constraint, applied, dissipative). ``dense_output``
and ``events`` behave as in :func:`scipy.integrate.solve_ivp`: event functions
``event(t, y)`` receive the state ``y`` of shape (2n,) and may have ``terminal`` (bool, or
the number of occurrences after which to stop) and ``direction`` attributes; a terminal event ends the run with
``Status.EVENT``. With projection the dense output interpolates each step from its
projected start. No sympy here.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

import numpy as np

from nhham.errors import BudgetExceeded, ComputationError, InputError
from nhham.numerics.methods import METHODS
from nhham.numerics.run import Run, report_progress
from nhham.numerics.status import NumericalFailure, Status

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

__all__ = ["scipy_solver", "WORK_ATOL", "DenseOutput", "run_scipy", "eval_failure"]


@cache
def scipy_solver(method: str):
    """The scipy solver class of an adaptive method (:data:`~nhham.numerics.methods.METHODS`),
    imported on first use: :mod:`scipy.integrate` takes half a second to import, and a run
    in the compiled loop never needs it."""
    if METHODS[method].scipy_name is None:
        raise KeyError(method)
    return METHODS[method].load()

#: Absolute tolerance of the work integral that rides along as an extra state: it must
#: not steer the step size (finite: scipy's numerical Jacobian scales by atol).
WORK_ATOL = 1e100


@dataclass(frozen=True)
class DenseOutput:
    """The continuous solution of a run, as scipy's ``OdeSolution``.

    ``sol(t)`` is the state at ``t``: shape (2n,) for a float, (2n, len(t)) for an array.
    """

    solution: OdeSolution
    size: int

    def __call__(self, t):
        return self.solution(t)[:self.size]

    @property
    def t_min(self) -> float:
        return float(self.solution.t_min)

    @property
    def t_max(self) -> float:
        return float(self.solution.t_max)


def eval_failure(status, t, y) -> NumericalFailure:
    """The failure of a field evaluation at time ``t`` and state ``y``."""
    status = Status(status)
    y = np.array(y, dtype=float)
    if status == Status.SINGULAR:
        return NumericalFailure(status, f"singular saddle-point system at t = {t:.6g} "
                                        f"(cond(C) is infinite)", state=y)
    return NumericalFailure(status, f"non-finite right-hand side (NaN or overflow) at "
                                    f"t = {t:.6g}; the run was stopped (state max |y| = "
                                    f"{float(np.max(np.abs(y))):.3g})", state=y)


def _control_value(name, f, t, y) -> float:
    """f(t, y) as a float, or an InputError naming the control and what went wrong."""
    try:
        value = float(f(t, y))
    except BudgetExceeded:  # the budget ran out while the callable ran: not its failure
        raise
    except Exception as exc:  # a user's callable: any failure is its own
        raise InputError(f"controls.{name}: f(t, y) (t a float, y the state of shape "
                         f"(2n,)) must give a number; at t = {t:.6g} it raised "
                         f"{type(exc).__name__}: {exc}", key="controls") from None
    return value


def _make_fun(model, baumgarte, counter, controls=None):
    """scipy's fun(t, z); ``controls``: ``{input: f(t, y)}`` set at every evaluation."""
    n2 = 2 * model.n
    field = model.field_function(baumgarte)
    moving = controls or model.time_slot is not None  # the field changes with t (or y)

    def at(t, y):
        """The model at time t with the controls' input values at (t, y)."""
        now = model.at_time(t)
        if controls:
            now = now.with_parameters(**{u: _control_value(u, f, t, y)
                                         for u, f in controls.items()})
        return now

    def fun(t, z):
        nonlocal field
        if z.ndim == 1:
            if moving:
                field = at(t, z[:n2]).field_function(baumgarte)
            try:
                out = field(z)
            except (ArithmeticError, ValueError):   # the Python kernels' 1/0, sqrt(-1)
                out = int(Status.NONFINITE)        # (where compiled code returns NaN)
            counter[0] += 1
            if isinstance(out, int):
                raise eval_failure(out, t, z[:n2])
            return out
        # Vectorised call (scipy's finite-difference Jacobian): z is (2n+1, k); with
        # controls each column has its own inputs.
        Y = np.ascontiguousarray(z[:n2].T)
        try:
            parts = [at(t, y).evaluate(y, baumgarte) for y in Y] if controls else \
                [model.at_time(t).evaluate(Y, baumgarte)]
        except (ArithmeticError, ValueError):
            raise eval_failure(Status.NONFINITE, t, z[:n2, 0]) from None
        counter[0] += z.shape[1]
        status = next((p[3] for p in parts if p[3]), 0)
        if status:
            raise eval_failure(status, t, z[:n2, 0])
        dY = np.vstack([np.atleast_2d(p[0]) for p in parts])
        P = np.concatenate([np.atleast_1d(p[2]) for p in parts])
        return np.vstack([dY.T, P[None, :]])

    return fun


class _Events:
    """Sign changes of the event functions over each step, located on the dense output."""

    def __init__(self, events, n2, t0, z0):
        self.events = (events,) if callable(events) else tuple(events)
        self.n2 = n2
        self.g = [float(e(t0, z0[:n2])) for e in self.events]
        self.count = [0] * len(self.events)
        self.t_events = [[] for _ in self.events]
        self.y_events = [[] for _ in self.events]

    def check(self, t_old, t, z, dense):
        """Record the events inside (t_old, t]; the time of a terminal one, or None."""
        n2 = self.n2
        g_new = [float(e(t, z[:n2])) for e in self.events]
        found = []
        for i, e in enumerate(self.events):
            up, down = self.g[i] <= 0 <= g_new[i], self.g[i] >= 0 >= g_new[i]
            direction = getattr(e, "direction", 0)
            if (up and direction >= 0 and g_new[i] != self.g[i]) or (
                    down and direction <= 0 and g_new[i] != self.g[i]):
                from scipy.optimize import brentq

                root = brentq(lambda s: e(s, dense(s)[:n2]), min(t_old, t), max(t_old, t),
                              xtol=4 * np.finfo(float).eps, rtol=4 * np.finfo(float).eps)
                found.append((root, i))
        self.g = g_new
        found.sort(reverse=bool(t < t_old))
        for root, i in found:
            self.count[i] += 1
            self.t_events[i].append(root)
            self.y_events[i].append(np.asarray(dense(root))[:n2])
            terminal = getattr(self.events[i], "terminal", False)
            if terminal and self.count[i] >= int(terminal):
                return root
        return None

    def results(self):
        return ([np.asarray(t) for t in self.t_events],
                [np.asarray(y).reshape(-1, self.n2) for y in self.y_events])


def _solver_options(method, n2, rtol, atol, max_step, first_step):
    atol_z = np.append(np.broadcast_to(np.asarray(atol, dtype=float), (n2,)), WORK_ATOL)
    opts = {"rtol": rtol, "atol": atol_z, "max_step": max_step}
    if METHODS[method].batched_jacobian:
        opts["vectorized"] = True
    if first_step is not None:
        opts["first_step"] = first_step
    return opts


def run_scipy(model, y0, t0, t1, method, *, rtol, atol, max_step, first_step, t_eval,
              projection, baumgarte, recorder, progress=False, dense_output=False,
              events=None, deadline=None, controls=None) -> Run:
    """Integrate with scipy's ``method`` (see the module docstring); the states go into
    ``recorder`` (a :class:`~nhham.numerics.storage.Recorder`). ``controls``:
    ``{input: f(t, y)}`` Python callables giving inputs at every evaluation."""
    n2 = 2 * model.n
    counter = [0]
    fun = _make_fun(model, baumgarte, counter, controls)
    cls = scipy_solver(method)
    opts = _solver_options(method, n2, rtol, atol, max_step, first_step)
    z0 = np.append(y0, 0.0)
    t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
    store = _Store(t0, z0, t_eval, model, projection, forward=t1 > t0, recorder=recorder)
    watch = _Events(events, n2, t0, z0) if events is not None else None
    knots, pieces = [t0], []
    status, message, failed = Status.SUCCESS, Status.SUCCESS.message, None
    nsteps = njev = nlu = reported = 0
    try:
        solver = cls(fun, t0, z0, t1, **opts)
        while solver.status == "running":
            t_old = solver.t
            msg = solver.step()
            if solver.status == "failed":
                status = Status.STEP_FAILED
                message = f"{method} failed at t = {solver.t:.6g}: {msg}"
                break
            nsteps += 1
            z = solver.y
            if not np.all(np.isfinite(z[:n2])) or np.max(np.abs(z[:n2])) > 1e150:
                raise NumericalFailure(Status.NONFINITE, f"non-finite or overflowing state "
                                       f"at t = {solver.t:.6g}; the run was stopped")
            if projection:
                solver = _project_solver(solver, model, fun, cls, t1, opts)
            # scipy's dense output costs extra evaluations (DOP853: 3): only when needed
            dense = solver.dense_output() if dense_output or watch is not None else None
            t_stop = watch.check(t_old, solver.t, solver.y, dense) if watch else None
            t_end = solver.t if t_stop is None else t_stop
            store.add(t_end, dense(t_end) if t_stop is not None and dense is not None
                      else solver.y,
                      solver.dense_output if dense is None else (lambda d=dense: d))
            if dense_output:
                knots.append(t_end)
                pieces.append(dense)
            njev = max(njev, getattr(solver, "njev", 0))
            nlu = max(nlu, getattr(solver, "nlu", 0))
            if progress:
                reported = report_progress(solver.t, t0, t1, reported)
            if t_stop is not None:
                status, message = Status.EVENT, Status.EVENT.message
                break
            if deadline is not None and deadline.passed():
                status, message = deadline.stop_status(), deadline.message(solver.t)
                break
    except NumericalFailure as exc:
        status, message, failed = exc.status, str(exc), exc.state
    except np.linalg.LinAlgError as exc:
        status, message = Status.SINGULAR, f"singular linear system: {exc}"
    except ComputationError as exc:  # a projection that did not converge and the like
        status, message = Status.NOT_CONVERGED, str(exc)
    store.close()
    T, Y, work = recorder.result(n2)
    if dense_output and pieces:
        from scipy.integrate import OdeSolution
    sol = DenseOutput(OdeSolution(knots, pieces), n2) if dense_output and pieces else None
    t_events, y_events = watch.results() if watch else (None, None)
    return Run(T, Y, work, status, message, counter[0], nsteps,
               njev=njev, nlu=nlu, sol=sol, t_events=t_events, y_events=y_events,
               failed_state=None if failed is None else failed[:n2])


class _Store:
    """The kept times and states (into a Recorder): every stride-th step and the last,
    or the ``t_eval`` points."""

    def __init__(self, t0, z0, t_eval, model, projection, forward, recorder):
        self.t_eval, self.model, self.projection = t_eval, model, projection
        self.forward, self.recorder = forward, recorder
        if t_eval is None or (len(t_eval) and np.isclose(t_eval[0], t0)):
            recorder.add(t0, z0)
        self.i = recorder.count
        self.steps = 0
        self.last = (t0, z0)

    def add(self, t, z, make_dense):
        """The step ending at ``t`` (state ``z``); the t_eval points inside it from the
        step's dense output (``make_dense()``, called only when a point is inside)."""
        if self.t_eval is None:
            self.steps += 1
            self.last = (t, z)
            if self.recorder.keep(self.steps):
                self.recorder.add(t, z)
            return
        t_eval, dense = self.t_eval, None
        while self.i < len(t_eval) and ((t_eval[self.i] <= t) if self.forward
                                        else (t_eval[self.i] >= t)):
            dense = make_dense() if dense is None else dense
            point = np.asarray(dense(t_eval[self.i]), dtype=float)
            if self.projection:  # onto M_1 at that time (t may enter the constraints)
                point[:-1] = self.model.at_time(t_eval[self.i]).project(point[:-1]).y
            self.recorder.add(float(t_eval[self.i]), point)
            self.i += 1

    def close(self):
        """Keep the last state (steps only: with t_eval only those times are kept)."""
        if self.t_eval is None:
            self.recorder.close(*self.last)


def _project_solver(solver, model, fun, cls, t1, opts):
    """Project the solver's current state onto M_1 and make the solver consistent."""
    n2 = 2 * model.n
    z = solver.y.copy()
    z[:n2] = model.at_time(solver.t).project(z[:n2]).y  # M_1 at the step's time
    from scipy.integrate import BDF, LSODA   # restarted by their own rules

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
