"""Diagnostics of a computed trajectory: residuals, energy, conditioning.

:func:`singularity_at` says what is singular at a state where a run stopped.

Everything is evaluated on the stored states in batches (no Python loop over
states; blocks of a few thousand, so that a long run's diagnostics need little
memory). The energy balance uses the exact identity of the constrained field
dE_L/dt = -lambda . (mu v) + Q . v (= lambda . h + Q . v on M_1, see
:mod:`nhham.numerics.model`): the integrators carry its time integral W(t) (the work of
the constraint forces, and of the applied forces and the dissipation, Q, when the system
has any), and the residual max |E(t) - E(0) - W(t)| measures integration error alone,
also for affine constraints or forces where E is not conserved.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nhham.numerics.model import COND_C_WARN
from nhham.numerics.nullspace import KKT_SOLVE, diagonal_ratio
from nhham.numerics.saddle import condition

__all__ = ["Diagnostics", "trajectory_diagnostics", "Singularity", "singularity_at"]

# cond is an SVD per state; beyond this many states every j-th is used (and
# the first and last): long runs stay cheap, spikes between samples can be
# missed, which the docstring of Diagnostics states.
_COND_SAMPLES = 20000

# States per batch call: the kernels' temporaries (W, mu, ... for every state of the
# batch) stay at a few MB however long the run.
_BLOCK = 8192


def _blockwise(fn, Y):
    """``fn`` on blocks of rows of Y, the results concatenated."""
    if len(Y) <= _BLOCK:
        return np.asarray(fn(Y))
    return np.concatenate([np.atleast_1d(fn(Y[i:i + _BLOCK]))
                           for i in range(0, len(Y), _BLOCK)])


def _row_max(A):
    return A.max(axis=1) if A.shape[1] else np.zeros(A.shape[0])


@dataclass(frozen=True)
class Diagnostics:
    """Diagnostics of one trajectory.

    Attributes
    ----------
    energy : ndarray, shape (K,)
        E_L at the stored states.
    work : ndarray, shape (K,)
        Work of the constraint forces W(t) = int_0^t -lambda . (mu v) dt.
    constraint_residual : ndarray, shape (K,)
        max_i |phi_i| and |g_a| at each stored state (absolute).
    constraint_residual_max : float
        Its maximum.
    constraint_residual_rel_max : float
        Largest residual scaled by its natural size (see
        :meth:`NumericModel.scaled_residuals`): meaningful at any velocity scale.
    energy_drift : float
        max |E(t) - E(0)|.
    energy_drift_rel : float
        energy_drift / |E(0)| (/ max |E(t)| when E(0) = 0, e.g. from rest).
    energy_balance_residual : float
        max |E(t) - E(0) - W(t)| (equals energy_drift for linear constraints
        up to the off-manifold part of W).
    cond_C_max, cond_W_max : float
        Largest 2-norm condition numbers along the trajectory (on at most
        20000 sampled states for very long runs).
    cond_C_sampled : int
        Number of states at which cond was evaluated.
    warnings : tuple of str
    kkt_solve : str
        The solve of the constrained accelerations: ``"null-space"``
        (:mod:`nhham.numerics.nullspace`, at every state).
    kkt_ratio_max : float
        The largest max W_AA / min W_AA at those states: the spread of the masses in the
        scene's units, a diagnostic.
    """

    energy: np.ndarray
    work: np.ndarray
    constraint_residual: np.ndarray
    constraint_residual_max: float
    constraint_residual_rel_max: float
    energy_drift: float
    energy_drift_rel: float
    energy_balance_residual: float
    cond_C_max: float
    cond_W_max: float
    cond_C_sampled: int
    warnings: tuple
    kkt_solve: str = KKT_SOLVE
    kkt_ratio_max: float = 1.0


def trajectory_diagnostics(model, t, y, work=None, *, residual_tol: float = 1e-8,
                           cond_warn: float = COND_C_WARN) -> Diagnostics:
    """Diagnostics of states ``y`` (shape (2n, K), as in scipy) at times ``t`` (K,).

    Parameters
    ----------
    model : NumericModel
    t : ndarray, shape (K,)
    y : ndarray, shape (2n, K)
    work : ndarray, shape (K,), optional
        Work of the constraint forces carried by the integrator; if None it is
        the trapezoidal integral of the power at the stored states (second
        order: right for the fixed-step schemes of that order).
    residual_tol : float
        Tolerance on the *scaled* constraint residuals; exceeding it gives a
        warning with the time at which it first happened.
    cond_warn : float
        cond(C) above which a warning is given (errors grow like cond(C) eps).
    """
    t = np.asarray(t, dtype=float)
    Y = np.asarray(y, dtype=float).T  # states as rows: what the model's batch calls take
    notes = []
    finite = np.all(np.isfinite(Y), axis=1)
    if not np.all(finite):
        Yf, tf = Y[finite], t[finite]
        notes.append(f"{int((~finite).sum())} stored states are not finite; diagnostics use "
                     f"the finite ones")
    else:
        Yf, tf = Y, t
    if Yf.shape[0] == 0:
        nan = float("nan")
        return Diagnostics(np.array([]), np.array([]), np.array([]), nan, nan, nan, nan, nan,
                           nan, nan, 0, tuple(notes))
    each = _at_times(model, tf)
    with np.errstate(all="ignore"):
        E = np.atleast_1d(each(lambda M, B: np.atleast_1d(M.energy(B)), Yf))
        rmax = each(lambda M, B: _row_max(np.abs(M.residuals(B))), Yf)
        rrel = each(lambda M, B: _row_max(M.scaled_residuals(B)), Yf)
    if work is None:
        work = _trapezoid_work(model, tf, Yf)
    else:
        work = np.asarray(work, dtype=float)[finite] if not np.all(finite) else np.asarray(work)
    with np.errstate(all="ignore"):  # an infinite energy (W not finite) drifts by NaN
        drift = np.abs(E - E[0])
        e_drift = float(drift.max())
        balance = float(np.max(np.abs(E - E[0] - work)))
    idx = _cond_indices(len(tf))
    each = _at_times(model, tf[idx])
    with np.errstate(all="ignore"):
        cC = np.atleast_1d(each(lambda M, B: np.atleast_1d(M.cond_C(B)), Yf[idx]))
        cW, ratio = np.atleast_2d(each(_w_conditions, Yf[idx])).T
    cond_C_max = float(np.nanmax(cC)) if cC.size else 1.0
    cond_W_max = float(np.nanmax(cW)) if cW.size else 1.0
    if max(cond_W_max, cond_C_max) > cond_warn:
        # a spread of W's diagonal (a mass ratio, units) is no near-singularity: the
        # warnings read the conditions with the diagonals scaled to 1, as the solves scale
        with np.errstate(all="ignore"):
            cW, cC = each(_scaled_conditions, Yf[idx]).T
    if np.nanmax(cW, initial=1.0) > cond_warn:  # then C is not what to look at
        first = tf[idx][np.argmax(cW > cond_warn)]
        notes.append(f"cond(W) = {np.nanmax(cW):.3g} (its diagonal scaled to 1) exceeds "
                     f"{cond_warn:.0e} (first at t = {first:.6g}): W = d2L/dv2 is close to "
                     f"singular, the Lagrangian nearly degenerate there")
    elif np.nanmax(cC, initial=1.0) > cond_warn:
        c = float(np.nanmax(cC))
        first = tf[idx][np.argmax(cC > cond_warn)]
        notes.append(f"cond(C) = {c:.3g} (its diagonal scaled to 1) exceeds {cond_warn:.0e} "
                     f"(first at t = {first:.6g}): errors grow like cond(C)*eps ~ "
                     f"{c * 2.2e-16:.1g}; the constraint matrix is close to singular")
    if np.any(rrel > residual_tol):
        first = tf[np.argmax(rrel > residual_tol)]
        notes.append(f"constraint residual {float(rrel.max()):.3g} (scaled) exceeds the tolerance "
                     f"{residual_tol:.1e}, first at t = {first:.6g}")
    return Diagnostics(
        energy=E, work=work, constraint_residual=rmax,
        constraint_residual_max=float(rmax.max()),
        constraint_residual_rel_max=float(rrel.max()),
        energy_drift=e_drift,
        energy_drift_rel=e_drift / max(abs(float(E[0])) or float(np.abs(E).max()),
                                       np.finfo(float).tiny),
        energy_balance_residual=balance,
        cond_C_max=cond_C_max, cond_W_max=cond_W_max, cond_C_sampled=int(len(idx)),
        warnings=tuple(notes),
        kkt_ratio_max=float(np.nanmax(ratio)) if ratio.size else 1.0,
    )


def _w_conditions(model, Y):
    """(K, 2): cond(W) (as ``model.cond_W``) and max W_AA / min W_AA at the states Y (K, 2n),
    from one evaluation of W."""
    W = model.geometry(Y)[0]
    return np.column_stack([condition(W), diagonal_ratio(W)])


def _scaled_conditions(model, Y):
    """(K, 2): cond(D W D) and cond(E C E) at the states Y, with D, E the inverse square
    roots of the diagonals of W and of C = mu W^-1 mu^T (inf where singular)."""
    W, mu, _, _ = model.geometry(Y)
    dW = np.abs(np.diagonal(W, axis1=1, axis2=2))
    d = 1.0 / np.sqrt(np.where(dW > 0, dW, 1.0))
    Ws = W * d[:, :, None] * d[:, None, :]
    out = np.ones((len(Y), 2))
    out[:, 0] = condition(Ws)
    if model.m:
        mus = mu * d[:, None, :]
        try:
            C = mus @ np.linalg.solve(Ws, np.swapaxes(mus, 1, 2))
        except np.linalg.LinAlgError:  # a singular W: C is not what to look at there
            C = np.stack([mus[i] @ np.linalg.pinv(Ws[i]) @ mus[i].T for i in range(len(Y))])
        dC = np.abs(np.diagonal(C, axis1=1, axis2=2))
        e = 1.0 / np.sqrt(np.where(dC > 0, dC, 1.0))
        out[:, 1] = condition(C * e[:, :, None] * e[:, None, :])
    return np.where(np.isfinite(out), out, np.inf)


def _cond_indices(K):
    if K <= _COND_SAMPLES:
        return np.arange(K)
    idx = np.linspace(0, K - 1, _COND_SAMPLES).astype(int)
    return np.unique(idx)


def _at_times(model, times):
    """``each(f, Y)``: f(model, block) over the rows of Y (blockwise), or row by row with
    the model at each row's time when t enters L or the constraints (E_L, the residuals,
    the conditions and the power change with t there; with t in the forces alone they
    do not, or the integrator carries them)."""
    if not model.time_in_geometry:
        return lambda f, Y: _blockwise(lambda B: f(model, B), Y)

    def each(f, Y):
        rows = [np.asarray(f(model.at_time(tk), Y[k:k + 1]))[0] for k, tk in enumerate(times)]
        return np.array(rows)

    return each


def _trapezoid_work(model, t, Y):
    with np.errstate(all="ignore"):
        P = _at_times(model, t)(lambda M, B: np.atleast_1d(M.evaluate(B)[2]), Y) \
            if len(t) > 1 else np.zeros(1)
    if len(t) == 1:
        return np.zeros(1)
    inc = 0.5 * (P[1:] + P[:-1]) * np.diff(t)
    return np.concatenate([[0.0], np.cumsum(inc)])


@dataclass(frozen=True)
class Singularity:
    """What makes the saddle-point system singular, or nearly so, at one state.

    C = -mu W^-1 mu^T, so cond(C) <= cond(W) cond(mu)^2: the larger of the two factors
    is named (``part``): ``"W"`` (the Lagrangian is not regular there), ``"mu"`` (the
    constraints' one-forms are dependent there: a singular configuration of the
    constraints) or ``"C"`` (W and mu are regular and C is still singular: an indefinite
    W, or constraints whose C vanishes, as with free multipliers).

    Attributes
    ----------
    part : {"W", "mu", "C"}
    cond_W, cond_mu, cond_C : float
        2-norm condition numbers at the state (inf when exactly singular); cond_mu is
        sigma_max / sigma_min of the m x n matrix mu.
    rank_mu : int
        Numerical rank of mu (singular values above 1e-10 sigma_max).
    m : int
    where : str
        The coordinates at the state (``x = 0, phi = 1.5708``).
    state : tuple of float
        The state (coordinates and velocities).
    """

    part: str
    cond_W: float
    cond_mu: float
    cond_C: float
    rank_mu: int
    m: int
    where: str
    state: tuple = ()

    def describe(self) -> str:
        """One clause: what is singular there."""
        if self.part == "W":
            nearly = "" if np.isinf(self.cond_W) else "nearly "
            return (f"W = d2L/dv2 is {nearly}singular (cond(W) = {self.cond_W:.3g}): the "
                    f"Lagrangian is not regular at {self.where}")
        if self.part == "mu":
            how = (f"dependent (rank of mu {self.rank_mu} of {self.m})" if self.rank_mu < self.m
                   else f"nearly dependent (cond(mu) = {self.cond_mu:.3g})")
            return (f"the constraints' one-forms are {how}, so C is singular (cond(C) = "
                    f"{self.cond_C:.3g}): a singular configuration of the constraints at "
                    f"{self.where}")
        return (f"C = -mu W^-1 mu^T is singular (cond(C) = {self.cond_C:.3g}) while W "
                f"(cond {self.cond_W:.3g}) and the one-forms mu (cond {self.cond_mu:.3g}) are "
                f"regular, at {self.where}")


def singularity_at(model, y, threshold: float = COND_C_WARN) -> Singularity | None:
    """What is singular at state ``y`` (2n,), or None when cond(C) and cond(W) are both
    below ``threshold`` (see :class:`Singularity`)."""
    y = np.asarray(y, dtype=float)
    W, mu, _, _ = model.geometry(y)
    with np.errstate(all="ignore"):
        sW = np.linalg.svd(W, compute_uv=False) if np.all(np.isfinite(W)) else np.zeros(1)
        s_mu = (np.linalg.svd(mu, compute_uv=False) if model.m and np.all(np.isfinite(mu))
                else np.ones(1))
        cond_W = float(sW[0] / sW[-1]) if sW[-1] > 0 else np.inf
        cond_mu = float(s_mu[0] / s_mu[-1]) if s_mu[-1] > 0 else np.inf
        cond_C = float(model.cond_C(y))
    if max(cond_C, cond_W) <= threshold:
        return None
    rank_mu = int(np.sum(s_mu > 1e-10 * s_mu[0])) if model.m else 0
    if cond_W >= max(cond_mu ** 2, np.sqrt(threshold)):
        part = "W"
    elif cond_mu ** 2 >= np.sqrt(threshold):
        part = "mu"
    else:
        part = "C"
    where = ", ".join(f"{name} = {value:.6g}" for name, value in
                      zip(model.coordinate_names, y[:model.n]))
    return Singularity(part, cond_W, cond_mu, cond_C, rank_mu, model.m, where,
                       tuple(float(x) for x in y))
