"""High-precision reference solutions in mpmath (for measuring errors).

The field is the generated mpmath kernel (same expressions as the float
kernels, printed for mpmath by :mod:`nhham.numerics.codegen.emit`) with the saddle-point
system solved by Gaussian elimination with partial pivoting in mpmath. The
integrator is Gragg-Bulirsch-Stoer extrapolation: the modified midpoint rule
with step numbers 2, 4, 6, ... and Aitken-Neville extrapolation in h^2
(Hairer, Norsett, Wanner, *Solving ODEs I*, II.9), whose order grows with the
column, so any number of digits is reachable at moderate cost. Steps are
accepted when the last two diagonal entries agree to ``tol`` (relative to
1 + |y|); the sum of accepted local estimates is reported as
``error_estimate`` (a guide, not a bound).

Defaults: ``tol = 10^-(digits - 6)`` with ``digits`` working digits (plus a
guard of 10 for the arithmetic), which for digits >= 25 is far more than two
orders of magnitude below any float64 setting.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from nhham.numerics.run import report_progress
from nhham.numerics.status import Status


__all__ = ["ReferenceSolution", "reference_solution"]

_GUARD = 10


@dataclass(frozen=True)
class ReferenceSolution:
    """Result of :func:`reference_solution`.

    Attributes
    ----------
    t : ndarray (K,)
    y : ndarray (2n, K)
        float64 rounding of the high-precision states (``y[i]`` is the i-th state
        variable over time, as in scipy).
    y_mp : list of list of mpf
        The states at full precision, one list per stored time.
    work : ndarray (K,)
        Work of the constraint forces (integrated with the state).
    digits, tol : int, float
    error_estimate : float
        Sum of the accepted local error estimates (relative).
    nfev, nsteps, rejected : int
    status : Status; message : str
    """

    t: np.ndarray
    y: np.ndarray
    y_mp: list
    work: np.ndarray
    digits: int
    tol: float
    error_estimate: float
    nfev: int
    nsteps: int
    rejected: int
    status: Status
    message: str


class _MpField:
    """z' = (v, a, power) at one state in mpmath arithmetic."""

    def __init__(self, model):
        self.model = model
        self.n, self.m, self.k = model.n, model.m, model.k
        self.p = [mpmath.mpf(x) for x in model.parameter_values]
        self.nfev = 0
        # a time-dependent system: t is the state's last entry (t' = 1), copied into its
        # parameter slot at every evaluation
        self.slot = model.time_slot
        self.timed = int(self.slot is not None)  # entries after the work in the state

    def __call__(self, z):
        n, m = self.n, self.m
        if self.slot is not None:
            self.p[self.slot] = z[-1]
        out = self.model.kernels.mp("saddle", z[:2 * n], self.p)
        self.nfev += 1
        if any(isinstance(x, mpmath.mpc) or not mpmath.isfinite(x) for x in out):
            # log or sqrt of a negative number (mpmath goes complex), 1/0, an overflow
            raise OverflowError("the kernels are not finite real numbers at the state")
        N = n + m
        K = mpmath.zeros(N, N)
        rhs = mpmath.zeros(N, 1)
        for i in range(n):
            for j in range(n):
                K[i, j] = out[i * n + j]
            rhs[i] = out[n * n + i]
        base = n * n + n
        v = z[n:2 * n]
        muv = []
        for c in range(m):
            row = out[base + c * n: base + (c + 1) * n]
            for j in range(n):
                K[n + c, j] = row[j]
                K[j, n + c] = row[j]
            rhs[n + c] = -out[base + m * n + c]
            muv.append(mpmath.fsum(row[j] * v[j] for j in range(n)))
        # mpmath's LU raises ZeroDivisionError on a singular matrix.
        x = list(mpmath.lu_solve(K, rhs))
        power = -mpmath.fsum(x[n + c] * muv[c] for c in range(m)) if m else mpmath.mpf(0)
        if self.model.layout.get("forced"):
            power += out[-1]  # the applied power Q . v (- dL/dt)
        return list(v) + x[:n] + [power] + ([mpmath.mpf(1)] if self.slot is not None else [])


def reference_solution(model, y0, t_span, *, digits: int = 30, t_eval=None, tol=None,
                       kmax: int = 12, max_steps: int = 200000,
                       progress: bool = False) -> ReferenceSolution:
    """Integrate with GBS extrapolation in mpmath.

    Parameters
    ----------
    model : NumericModel
    y0 : array_like (2n,) or sequence of mpf
        Initial state (floats are taken exactly).
    t_span : (t0, t1)
    digits : int
        Decimal digits of the solution (working precision digits + 10).
    t_eval : array_like, optional
        Output times (default: every accepted step).
    tol : float, optional
        Local relative tolerance (default 10^-(digits - 6)).
    kmax : int
        Largest extrapolation column.
    progress : bool
        Report each tenth of the interval on stderr.
    """
    if digits < 16:
        raise ValueError("reference_digits must be at least 16 (more than float64)")
    tol = 10.0 ** (-(digits - 6)) if tol is None else float(tol)
    t0, t1 = float(t_span[0]), float(t_span[1])
    with mpmath.workdps(digits + _GUARD):
        return _integrate(model, y0, t0, t1, digits, t_eval, mpmath.mpf(tol), kmax, max_steps,
                          progress)


def _integrate(model, y0, t0, t1, digits, t_eval, tol, kmax, max_steps, progress):
    f = _MpField(model)
    z = [mpmath.mpf(float(x)) if not isinstance(x, mpmath.mpf) else x for x in y0]
    z.append(mpmath.mpf(0))
    T0, T1 = mpmath.mpf(t0), mpmath.mpf(t1)
    if f.slot is not None:
        z.append(T0)  # the time, integrated exactly by every stage (t' = 1)
    outputs = [mpmath.mpf(float(x)) for x in t_eval] if t_eval is not None else None
    direction = 1 if t1 > t0 else -1
    t = T0
    H = (T1 - T0) / 20
    ts, zs = [], []
    if outputs is None or (outputs and abs(outputs[0] - T0) == 0):
        ts.append(t)
        zs.append(list(z))
    oi = len(ts) if outputs is not None else 0
    reported = 0
    err_sum = mpmath.mpf(0)
    nsteps = rejected = 0
    status, message = Status.SUCCESS, Status.SUCCESS.message
    try:
        while direction * (T1 - t) > 0:
            if nsteps + rejected > max_steps:
                status, message = Status.STEP_FAILED, f"more than {max_steps} steps"
                break
            target = T1 if outputs is None or oi >= len(outputs) else outputs[oi]
            clipped = direction * (t + H - target) >= 0
            Hs = target - t if clipped else H
            try:
                result = _gbs_step(f, z, Hs, kmax, tol)
            except (OverflowError, ValueError):
                f(z)  # not finite at the state itself: the run stops (below)
                result = None  # at a trial state of the step only: a shorter step
            if result is None:
                H = Hs / 2
                rejected += 1
                if abs(H) < abs(T1 - T0) * mpmath.mpf(10) ** (-digits):
                    status = Status.STEP_FAILED
                    message = "step size underflow in the reference integrator"
                    break
                continue
            z, err, col = result
            t = target if clipped else t + Hs
            nsteps += 1
            if progress:
                reported = report_progress(float(t), t0, t1, reported)
            err_sum += err
            if outputs is None or (clipped and oi < len(outputs)):
                ts.append(t)
                zs.append(list(z))
                oi += outputs is not None
            if not clipped:  # column-based control: few columns -> longer steps
                if col <= kmax // 2:
                    H = Hs * 2
                elif col >= kmax - 1:
                    H = Hs * mpmath.mpf("0.6")
    except ZeroDivisionError as exc:
        status, message = Status.SINGULAR, f"singular saddle-point system: {exc}"
    except (OverflowError, ValueError) as exc:  # mpmath's exp of 1e60 has too many digits
        status, message = Status.NONFINITE, f"{Status.NONFINITE.message}: {exc}"
    n2 = 2 * model.n
    y = np.array([[float(v) for v in zz[:n2]] for zz in zs]).T if zs else np.zeros((n2, 0))
    work = np.array([float(zz[n2]) for zz in zs])
    return ReferenceSolution(
        t=np.array([float(x) for x in ts]), y=y, y_mp=[zz[:n2] for zz in zs], work=work,
        digits=digits, tol=float(tol), error_estimate=float(err_sum), nfev=f.nfev,
        nsteps=nsteps, rejected=rejected, status=status, message=message)


def _gbs_step(f, z, H, kmax, tol):
    """One extrapolation step; (z_new, error, column) or None if not converged."""
    d = len(z)
    f0 = f(z)
    T = []  # T[j] = extrapolation row j (list of vectors)
    for j in range(1, kmax + 1):
        nj = 2 * j
        h = H / nj
        zm = list(z)
        zc = [z[i] + h * f0[i] for i in range(d)]
        for _ in range(nj - 1):
            fc = f(zc)
            zm, zc = zc, [zm[i] + 2 * h * fc[i] for i in range(d)]
        fc = f(zc)
        row = [[(zc[i] + zm[i] + h * fc[i]) / 2 for i in range(d)]]
        for kk in range(1, j):
            ratio = (mpmath.mpf(nj) / (2 * (j - kk))) ** 2 - 1
            prev, cur = T[j - 2][kk - 1], row[kk - 1]
            row.append([cur[i] + (cur[i] - prev[i]) / ratio for i in range(d)])
        T.append(row)
        if j >= 3:
            a, b = row[-1], row[-2]
            err = max(abs(a[i] - b[i]) / (1 + abs(a[i])) for i in range(d - 1 - f.timed))
            if err <= tol:
                return a, err, j
    return None
