"""scipy's explicit Runge-Kutta methods (RK23, RK45, DOP853) as one compiled loop.

:func:`run_compiled` calls ``nhham_erk`` (``nhham/numerics/c/erk.c``): scipy's algorithm
(its coefficients, initial step, error norm, step-size control and dense output) with the
projection onto M_1 and the storage done in C too, so no Python runs per step. The C
loop hands control back every :data:`~nhham.numerics.run.PAUSE_SECONDS` of wall time and
when the recorder's room is full, so that a signal (Ctrl-C, the command's ``--budget``)
is handled within milliseconds and the recorder can thin what it keeps. The statuses
are those of :class:`~nhham.numerics.status.Status`. No sympy here.
"""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np

from nhham.numerics.methods import names
from nhham.numerics.run import PAUSE_SECONDS, Run, report_progress
from nhham.numerics.scipy_loop import WORK_ATOL, eval_failure, scipy_solver
from nhham.numerics.status import STOPPED, Status

__all__ = ["COMPILED_METHODS", "run_compiled"]

#: scipy methods that also run as one compiled loop (their records list the loop).
COMPILED_METHODS = names(lambda m: m.compiled_loop, cheapest_first=True)

_EXTRA_STAGES = 16  # DOP853's stages with the dense-output extras (SEXT in the C source)


@cache
def _coefficients(method):
    """(info, coefficients) of scipy's class for ``nhham_erk`` (see its C comment), read
    from scipy once per scipy version and kept in the compile cache: importing
    :mod:`scipy.integrate` costs half a second that a compiled run has no other use for."""
    import scipy   # the package alone (light): its version keys the kept tableau

    from nhham.numerics.codegen.cache import CompileCache

    cache_ = CompileCache.open()
    name = f"tableau_{method}_scipy_{scipy.__version__}"
    kept = cache_.table(name)
    if kept is None or set(kept) != {"info", "tab"}:
        info, tab = _scipy_tableau(method)
        cache_.keep_table(name, {"info": list(info), "tab": tab.tolist()})
    else:
        info, tab = tuple(int(i) for i in kept["info"]), np.array(kept["tab"], dtype=float)
    tab.flags.writeable = False  # shared by every run (the C code only reads it)
    return info, np.ascontiguousarray(tab)


def _scipy_tableau(method):
    """(info, coefficients) from scipy's solver class."""
    cls = scipy_solver(method)
    s = cls.n_stages
    A = np.zeros((s, s))
    A0 = np.asarray(cls.A, dtype=float)
    A[:, :A0.shape[1]] = A0[:s]
    B, C = np.asarray(cls.B, dtype=float), np.asarray(cls.C, dtype=float)[:s]
    dop = hasattr(cls, "A_EXTRA")  # DOP853's tableau: two error estimates, extra stages
    if dop:
        E, E3, P = cls.E5, cls.E3, np.zeros((s + 1, 0))
        Aext, Cext, D = cls.A_EXTRA, cls.C_EXTRA, cls.D
    else:
        E, E3, P = cls.E, np.zeros(s + 1), np.asarray(cls.P, dtype=float)
        Aext, Cext, D = (np.zeros((3, _EXTRA_STAGES)), np.zeros(3),
                         np.zeros((4, _EXTRA_STAGES)))
    tab = np.concatenate([A.ravel(), B, C, np.asarray(E, dtype=float), E3, P.ravel(),
                          np.asarray(Aext, dtype=float).ravel(), Cext,
                          np.asarray(D, dtype=float).ravel()])
    info = (s, int(dop), P.shape[1], cls.error_estimator_order)
    return info, tab


def _tableau(method):
    """A fresh ``info`` (its last entry, "first call", is changed by the loop) and the
    shared coefficients."""
    info, tab = _coefficients(method)
    return np.array([*info, 1], dtype=np.intc), tab


def _scipy_validation(t0, t1, rtol, max_step, first_step) -> float:
    """scipy's checks of the options; the rtol it would use."""
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
                      f"Setting `rtol = np.maximum(rtol, {100 * eps})`.", stacklevel=4)
        rtol = 100 * eps
    return rtol


def _workspace(y0, t0, atol, first_step, nz):
    """ws = [t, h_abs, z, f | fail: t, z | atol] (float64; the fail time NaN until a field
    evaluation fails)."""
    ws = np.zeros(2 + 2 * nz + 1 + nz + nz)
    ws[0], ws[1] = t0, (-1.0 if first_step is None else float(first_step))
    ws[2:2 + nz - 1] = y0
    ws[2 + 2 * nz] = np.nan
    ws[-nz:-1] = atol
    ws[-1] = WORK_ATOL
    if np.any(ws[-nz:] < 0):
        raise ValueError("`atol` must be positive.")
    return ws


def run_compiled(model, y0, t0, t1, method, *, rtol, atol, max_step, first_step, t_eval,
                 projection, baumgarte, recorder, progress=False, deadline=None) -> Run:
    """RK23/RK45/DOP853 as one compiled loop (see the module docstring); the states go
    into ``recorder`` (a :class:`~nhham.numerics.storage.Recorder`: every stride-th step,
    or room for the t_eval points)."""
    n2 = 2 * model.n
    nz = n2 + 1
    rtol = _scipy_validation(t0, t1, rtol, max_step, first_step)
    info, tab = _tableau(method)
    block = model.parameter_block(baumgarte)
    ws = _workspace(y0, t0, atol, first_step, nz)
    state, fail = ws[:2 + 2 * nz], ws[2 + 2 * nz:2 + 2 * nz + 1 + nz]
    if t_eval is not None:
        t_eval = np.ascontiguousarray(t_eval, dtype=float)
    if t_eval is None or np.isclose(t_eval[0], t0):
        recorder.add(t0, state[2:2 + nz])
    # iw = [t_eval index, rows stored by the call, nfev, nsteps]
    iw = np.array([recorder.count, 0, 0, 0], dtype=np.int64)
    reported = 0
    while True:
        out_t, out_z = recorder.room()
        status = Status(model.compiled.erk(info, tab, ws, iw, t1, rtol, float(max_step),
                                           projection, 1e-14, 50, t_eval, out_t, out_z,
                                           recorder.stride, PAUSE_SECONDS, block.pointer))
        info[4] = 0
        recorder.advance(int(iw[1]))
        iw[1] = 0
        if progress:
            reported = report_progress(state[0], t0, t1, reported)
        if status != Status.PAUSED:
            break
        if deadline is not None and deadline.passed():
            status = deadline.stop_status()
            break
    if t_eval is None:
        recorder.close(float(state[0]), state[2:2 + nz])
    message = (deadline.message(float(state[0])) if status in STOPPED else
               _message(status, method, float(state[0]), fail, n2))
    T, Y, work = recorder.result(n2)
    failed = None if np.isnan(fail[0]) else fail[1:1 + n2].copy()
    return Run(T, Y, work, status, message, int(iw[2]), int(iw[3]), failed_state=failed)


def _message(status, method, t_now, fail, n2) -> str:
    """The message of the status the loop returned, with where it happened."""
    field_failed = not np.isnan(fail[0])  # set by the C code when the field failed
    if status == Status.SUCCESS:
        return status.message
    if status == Status.STEP_FAILED:
        return (f"{method} failed at t = {t_now:.6g}: Required step size is less than "
                f"spacing between numbers.")
    if status in (Status.SINGULAR, Status.NONFINITE) and field_failed:
        return str(eval_failure(status, fail[0], fail[1:1 + n2]))
    if status == Status.NONFINITE:
        return f"non-finite or overflowing state at t = {t_now:.6g}; the run was stopped"
    if status == Status.SINGULAR:
        return f"singular linear system in the projection onto M_1 at t = {t_now:.6g}"
    return (f"projection onto M_1 failed at t = {t_now:.6g}: the Newton iteration for the "
            f"position constraints did not converge")
