"""Many runs of one model, only their ends kept: the integrations of a parameter study.

:func:`simulate_many` integrates N initial states (each with its own parameter values,
if given) over one time span with the loop :func:`~nhham.numerics.integrate.simulate`
uses for the method (the compiled Runge-Kutta loop when the model has it, else
``simulate`` itself), so each end state is the one a single run gives, to rounding. It
keeps per run the end state, the work of the constraint and applied forces (the energy
balance), the status and the counts, and no trajectory. No sympy.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from nhham.errors import InputError
from nhham.numerics.compiled_loop import run_compiled
from nhham.numerics.methods import DEFAULT_METHOD, lookup
from nhham.numerics.run import Deadline
from nhham.numerics.status import Status
from nhham.numerics.storage import Recorder

__all__ = ["EnsembleResult", "simulate_many"]


@dataclass(frozen=True)
class EnsembleResult:
    """The ends of N runs.

    Attributes
    ----------
    t_final : ndarray, shape (N,)
        Where each run ended (``t_span[1]`` unless it failed or ran out of time).
    y_final : ndarray, shape (N, 2n)
        The state there (coordinates, then velocities).
    work : ndarray, shape (N,)
        The work of the constraint, applied and dissipative forces over the run: the
        energy balance is E(t_final) - E(0) - work (NaN where the loop does not carry it).
    status : ndarray of int8, shape (N,)
        :class:`~nhham.numerics.status.Status` of each run (0 success).
    nfev, nsteps : ndarray of int64, shape (N,)
    wall_time_s : ndarray, shape (N,)
    messages : tuple of str
        The message of each run that did not succeed (``index: message``).
    loop : str
        ``"compiled"`` or ``"simulate"``.

    Examples
    --------
    x'' = -x over a quarter period: (x, x') = (1, 0) goes to (0, -1), (0, 1) to (1, 0).

    >>> import numpy as np
    >>> from nhham import System, numeric_model, simulate_many
    >>> model = numeric_model(System(["x"], "x_dot**2/2 - x**2/2"), backend="numpy")
    >>> ends = simulate_many(model, [[1.0, 0.0], [0.0, 1.0]], (0.0, np.pi / 2))
    >>> np.round(ends.y_final, 8) + 0.0, ends.status, ends.messages
    (array([[ 0., -1.],
           [ 1.,  0.]]), array([0, 0], dtype=int8), ())
    >>> np.round(ends.t_final, 4)
    array([1.5708, 1.5708])
    """

    t_final: np.ndarray
    y_final: np.ndarray
    work: np.ndarray
    status: np.ndarray
    nfev: np.ndarray
    nsteps: np.ndarray
    wall_time_s: np.ndarray
    messages: tuple
    loop: str


def simulate_many(model, y0, t_span, *, parameters=None, method: str = DEFAULT_METHOD,
                  rtol: float = 1e-9, atol: float = 1e-12, max_step: float = np.inf,
                  projection: bool = False, time_limit: float | None = None,
                  deadline: Deadline | None = None) -> EnsembleResult:
    """Integrate from each of N initial states; keep the ends.

    Parameters
    ----------
    model : NumericModel
    y0 : array_like, shape (N, 2n)
        Initial states on M_1 (checked by ``simulate`` where it runs; here the caller
        projects perturbed states).
    t_span : (float, float)
    parameters : array_like, shape (N, P), optional
        Each run's parameter values (``model.parameter_names`` order); default the
        model's.
    method, rtol, atol, max_step, projection
        As for :func:`~nhham.numerics.integrate.simulate`.
    time_limit : float, optional
        Seconds for all runs together; the runs not finished then end with
        ``Status.TIME_LIMIT`` (those not started keep t_final = t_span[0]).
    deadline : Deadline, optional
        Instead of ``time_limit``: the :class:`~nhham.numerics.run.Deadline` the runs stop
        at (a parameter study's passes also when the study is interrupted).

    Returns
    -------
    EnsembleResult

    Examples
    --------
    x'' = -k x from x = 1, at k = 1 and k = 4: x(pi/2) = cos(sqrt(k) pi/2) = 0 and -1.

    >>> import numpy as np
    >>> from nhham import System, numeric_model, simulate_many
    >>> spring = System(["x"], "x_dot**2/2 - k*x**2/2", parameters={"k": 1.0})
    >>> model = numeric_model(spring, backend="numpy")
    >>> ends = simulate_many(model, [[1.0, 0.0], [1.0, 0.0]], (0.0, np.pi / 2),
    ...                      parameters=[[1.0], [4.0]])
    >>> np.round(ends.y_final[:, 0], 8) + 0.0
    array([ 0., -1.])
    """
    from nhham.numerics.integrate import simulate

    Y0 = np.atleast_2d(np.asarray(y0, dtype=float))
    N, n2 = Y0.shape
    if n2 != 2 * model.n:
        raise InputError(f"y0: expected states of {2 * model.n} values, got shape {Y0.shape}")
    P = None if parameters is None else np.atleast_2d(np.asarray(parameters, dtype=float))
    t0, t1 = float(t_span[0]), float(t_span[1])
    compiled = (lookup(method).compiled_loop and model.compiled is not None
                and model.path == "saddle")
    deadline = deadline if deadline is not None else Deadline.after(time_limit)
    out_t, out_y = np.full(N, t0), Y0.copy()
    work = np.full(N, np.nan)
    status = np.full(N, int(Status.TIME_LIMIT), dtype=np.int8)
    nfev, nsteps = np.zeros(N, dtype=np.int64), np.zeros(N, dtype=np.int64)
    wall = np.zeros(N)
    messages = []
    t_eval = np.array([t1])
    for i in range(N):
        if deadline is not None and deadline.passed():
            messages.append(f"{i}: not started before the time limit")
            continue
        m = model if P is None else model.with_parameters(**dict(zip(model.parameter_names,
                                                                     P[i])))
        start = time.perf_counter()
        if compiled:
            m.require_inputs()
            run = run_compiled(m, Y0[i], t0, t1, method, rtol=rtol, atol=atol,
                               max_step=max_step, first_step=None, t_eval=t_eval,
                               projection=projection, baumgarte=None,
                               recorder=Recorder(n2 + 1, 2, thin=False), deadline=deadline)
            T, Y, W = run.t, run.y, run.work
            code, message, fev, steps = run.status, run.message, run.nfev, run.nsteps
        else:
            res = simulate(m, (t0, t1), Y0[i], method=method, rtol=rtol, atol=atol,
                           max_step=max_step, projection=projection, t_eval=t_eval,
                           warn=False, time_limit=None if deadline is None
                           or deadline.seconds == float("inf") else
                           max(deadline.remaining(), 1e-3))
            T, Y, W = res.t, res.y, None
            code, message, fev, steps = res.status, res.message, res.nfev, res.nsteps
        wall[i] = time.perf_counter() - start
        status[i], nfev[i], nsteps[i] = int(code), fev, steps
        if T.size:
            out_t[i], out_y[i] = T[-1], Y[:, -1]
            if W is not None:
                work[i] = W[-1]
        if int(code) < 0:
            messages.append(f"{i}: {message}")
    return EnsembleResult(out_t, out_y, work, status, nfev, nsteps, wall, tuple(messages),
                          "compiled" if compiled else "simulate")
