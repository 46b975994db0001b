"""Fixed-step integrators: nonholonomic RATTLE, its 4th-order composition, RK4.

All work on a :class:`~nhham.numerics.model.NumericModel` (no sympy) and return a
:class:`FixedStepRun` (grid, states, counts, status: a
:class:`~nhham.numerics.status.Status`). :func:`nhham.numerics.integrate.simulate` wraps
them with diagnostics. A failed step raises
:class:`~nhham.numerics.status.NumericalFailure` inside; the run then stops and keeps
what it computed.

The nonholonomic RATTLE scheme
------------------------------
For L = 1/2 v^T W(q) v - V(q) with momenta p = W(q) v, constraints
phi_i = mu_i(q) v + h_i(q) (complete lifts of holonomic g_a first), one step
(q0, v0) -> (q1, v1) of size h solves::

    p_h = p0 + h/2 [ L_q(q0, W(q0)^{-1} p_h) - mu(q0)^T lam0 ]
    q1  = q0 + h/2 [ W(q0)^{-1} + W(q1)^{-1} ] p_h
    0   = mu_i(qm) (q1 - q0)/h + h_i(qm),  qm = (q0 + q1)/2   (nonholonomic rows)
    0   = g_a(q1)                                              (holonomic rows)
    p1  = p_h + h/2 [ L_q(q1, W(q1)^{-1} p_h) - mu(q1)^T lam1 ]
    0   = mu(q1) W(q1)^{-1} p1 + h(q1)                          (all rows)

i.e. the Lobatto IIIA-IIIB pair (generalised Stoermer-Verlet; for constant W
the velocity Verlet / RATTLE scheme) with multipliers, the constraints
discretised at the midpoint inside the step and imposed exactly on (q1, v1)
at the grid points. This is the RATTLE-type nonholonomic integrator of
R. I. McLachlan and M. Perlmutter, "Integrators for nonholonomic mechanical
systems", J. Nonlinear Sci. 16 (2006) 283-328, in the form of the SPARK
(Lobatto IIIA-B) methods of L. O. Jay, "Structure preservation for
constrained dynamics with super partitioned additive Runge-Kutta methods",
SIAM J. Sci. Comput. 20 (1998) 416-446; for holonomic rows it is RATTLE
(H. C. Andersen 1983; Hairer, Lubich, Wanner, *Geometric Numerical
Integration*, VII.1). It is symmetric (time-reversible: the step with -h
from (q1, v1) returns to (q0, v0)), second order, keeps phi = 0 and g = 0 to
round-off at every grid point, and for linear constraints with constant W and
a quadratic L has the good long-time energy behaviour of reversible methods on
reversible integrable problems (Modin & Verdier, "What makes nonholonomic
integrators work?", Numer. Math. 145 (2020) 405-435, explain why and show
problems where it fails).

With t in L or a constraint, each half kick reads the model at its grid point's time and
the inner constraint at t + h/2; with constraints nonlinear in v (Chetaev's rule) the rows
read (q, v): the reaction's direction mu = d phi/d v at (q0, v0) and (q1, v1), the inner
constraint phi(q_m, (q1 - q0)/h) = 0, and (v1, lam1) by Newton's method. Both keep the
step symmetric (so of order 2) and phi = 0 to round-off at the grid points; they run in
the Python stepper (:meth:`_RattleStepper._step_extended`), not the compiled loop.

Restrictions: L must be quadratic in v without linear terms
(``model.quadratic``); otherwise :class:`~nhham.errors.InputError` is raised.
The nonlinear equations are solved by Newton's method: for constant W only
for lam0 (m unknowns, analytic Jacobian); otherwise for (p_h, q1, lam0) with a
finite-difference Jacobian. A model with a compiled library runs the whole loop in C
(``nhham/numerics/c/rattle.c``: the same equations and the same Newton iterations, the
states agree with the Python stepper's to round-off); :class:`_RattleStepper` (numpy,
the Jacobian's columns in one batched call) is the fallback of a model without one.
"""

from __future__ import annotations

import math

import numpy as np

from nhham.errors import InputError
from nhham.numerics.run import PAUSE_SECONDS, Run, report_progress
from nhham.numerics.saddle import solve_saddle
from nhham.numerics.status import STOPPED, NumericalFailure, Status
from nhham.numerics.storage import Recorder, default_max_points

__all__ = ["FixedStepRun", "rattle", "rattle4", "rk4", "rattle_step", "step_grid", "run_fixed",
           "fixed_recorder", "drive_compiled"]

# The methods' records (order, what each takes) are in nhham.numerics.methods; a new
# fixed-step scheme is a function with rk4's signature here and one record there.

# Yoshida / Suzuki triple jump: a symmetric method of order 2 composed with
# these substeps is symmetric of order 4.
_G1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_G2 = 1.0 - 2.0 * _G1


#: Raw output of a fixed-step integrator: a :class:`~nhham.numerics.run.Run` with
#: ``y`` of shape (2n, K) (as in scipy), ``newton_iterations`` and ``step`` (the step
#: actually used, (t1 - t0)/N); ``work`` is carried by RK4 only.
FixedStepRun = Run


def step_grid(t0, t1, h):
    if not (h > 0 and math.isfinite(h)):
        raise InputError(f"step: a positive finite step is required for fixed-step methods, "
                         f"got {h!r}")
    span = t1 - t0
    N = max(1, int(math.ceil(abs(span) / h - 1e-9)))
    return N, span / N


def _check_quadratic(model):
    if not model.quadratic:
        raise InputError(
            "RATTLE needs L = 1/2 v^T W(q) v - V(q) (no terms linear in the "
            "velocities, W independent of v); use a scipy method for this system")


# ------------------------------------------------------------------ RATTLE
class _RattleStepper:
    """One nonholonomic RATTLE step; keeps counters and the last multiplier."""

    def __init__(self, model, tol=None, maxiter=30):
        _check_quadratic(model)
        self.model = model
        self.n, self.m, self.k = model.n, model.m, model.k
        self.tol = tol if tol is not None else 4 * np.finfo(float).eps
        self.maxiter = maxiter
        self.nfev = 0
        self.newton = 0
        self.lam_guess = None
        if model.constant_W and not self.extended:
            self.W = model.geometry(np.zeros(model.n))[0]

    def step(self, y0, h, t=0.0):
        """(y1, lam1) after one step of size h from y0 at the time t."""
        if self.extended:
            return self._step_extended(y0, h, t)
        if self.model.constant_W:
            return self._step_constant(y0, h)
        return self._step_general(y0, h)

    @property
    def extended(self) -> bool:
        """t in L or a constraint, or a constraint nonlinear in v (Chetaev): the step of
        :meth:`_step_extended` (the Python stepper; the compiled loop takes neither)."""
        return self.model.time_in_geometry or self.model.nonlinear

    # ---------------------------------------------------- residual pieces
    def _r3(self, q0, q1, h):
        """Discrete constraints: midpoint rows (nonholonomic), g(q1) (holonomic); and the
        size of each row's terms, which its round-off is relative to: u = (q1 - q0)/h
        carries the round-off of q1, eps |q1| / |h|, which grows with the coordinates
        (an angle that has turned 1e4 times), so the Newton test is relative to it."""
        k = self.k
        qm = 0.5 * (q0 + q1)
        u = (q1 - q0) / h
        _, mu_m, h_m, _ = self.model.geometry(qm)
        r = mu_m @ u + h_m
        size = 1.0 + np.abs(h_m) + np.abs(mu_m) @ (np.abs(u) + np.abs(q1) / abs(h))
        if k:
            _, G, _, g1 = self.model.geometry(q1)
            r[:k] = g1
            size[:k] = 1.0 + np.abs(G[:k]) @ np.abs(q1)
        return r, size

    def _r3_jac_q1(self, q0, q1, h):
        """d r3 / d q1 (m x n)."""
        k = self.k
        qm = 0.5 * (q0 + q1)
        u = (q1 - q0) / h
        _, mu_m, _, _ = self.model.geometry(qm)
        J = mu_m / h + 0.5 * self.model.constraint_jacobian_q(np.concatenate([qm, u]))
        if k:
            J[:k] = self.model.geometry(q1)[1][:k]
        return J

    def guess_lambda(self, y0):
        if self.lam_guess is None:
            dy, lam, _, status = self.model.evaluate(y0)
            self.nfev += 1
            if status:
                raise NumericalFailure(Status.SINGULAR,
                                       "singular saddle-point system at the initial state")
            return lam
        return self.lam_guess

    def _finish(self, q1, p_h, h):
        """Second half kick and the exact end constraint: (v1, lam1)."""
        W1, mu1, h1, _ = self.model.geometry(q1)
        u1 = np.linalg.solve(W1, p_h) if not self.model.constant_W else self._Winv(p_h)
        Lq1 = self.model.lagrangian_q(np.concatenate([q1, u1]))
        # W1 v1 + (h/2) mu1^T lam1 = p_h + h/2 Lq1,  mu1 v1 = -h1
        # A velocity-level solve: the saddle solve whatever W's diagonal (the null-space
        # solve keeps the O(1) v, not its small step increments, any better: measured on
        # a mass ratio of 1e16 it kept them 3-10x worse), as the compiled RATTLE step.
        v1, nu = solve_saddle(W1, mu1, p_h + 0.5 * h * Lq1, -h1)
        # One step of iterative refinement of the constraint rows: LU is only
        # normwise backward stable, and with extreme mass ratios the rows of
        # mu would otherwise keep a residual far above round-off.
        r = mu1 @ v1 + h1
        if self.m and np.any(r):
            dv, dnu = solve_saddle(W1, mu1, np.zeros(self.n), -r)
            v1, nu = v1 + dv, nu + dnu
        return v1, nu * (2.0 / h)

    def _Winv(self, p):
        return np.linalg.solve(self.W, p)

    # ------------------------------------------------------- constant W
    def _step_constant(self, y0, h):
        n, m = self.n, self.m
        q0, v0 = y0[:n], y0[n:]
        W = self.W
        p0 = W @ v0
        _, mu0, _, _ = self.model.geometry(q0)
        Lq0 = self.model.lagrangian_q(y0)  # independent of v for constant W
        base = p0 + 0.5 * h * Lq0
        if m == 0:
            q1 = q0 + h * self._Winv(base)
            v1, lam1 = self._finish(q1, base, h)
            return np.concatenate([q1, v1]), lam1
        WinvMuT = np.linalg.solve(W, mu0.T)  # n x m
        lam = self.guess_lambda(y0).copy()
        q_free = q0 + h * self._Winv(base)
        dq_dlam = -0.5 * h * h * WinvMuT
        best = np.inf
        for it in range(self.maxiter):
            q1 = q_free + dq_dlam @ lam
            r, size = self._r3(q0, q1, h)
            err = float(np.max(np.abs(r) / size))
            _finite_or_fail(err)
            if err <= self.tol:
                break
            if it > 2 and err >= best:
                _floor_or_fail(err)
                break
            best = min(best, err)
            J = self._r3_jac_q1(q0, q1, h) @ dq_dlam
            lam = lam - np.linalg.solve(J, r)
            self.newton += 1
        else:
            raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the RATTLE step "
                                   f"did not converge (residual {err:.3g}); reduce the step")
        q1 = q_free + dq_dlam @ lam
        p_h = base - 0.5 * h * (mu0.T @ lam)
        v1, lam1 = self._finish(q1, p_h, h)
        self.lam_guess = lam1
        return np.concatenate([q1, v1]), lam1

    # -------------------------------------------------------- general W
    def _residual(self, Z, q0, p0, W0, mu0, h):
        """Residuals of (p_h, q1, lam0) for a batch Z (K, 2n+m) in one call each."""
        n, k = self.n, self.k
        P, Q1, Lam = Z[:, :n], Z[:, n:2 * n], Z[:, 2 * n:]
        U0 = np.linalg.solve(W0, P.T).T
        Lq0 = self.model.lagrangian_q(np.concatenate([np.broadcast_to(q0, U0.shape), U0], axis=1))
        W1, mu1, h1, g1 = self.model.geometry(Q1)
        U1 = np.linalg.solve(W1, P[..., None])[..., 0]
        R1 = P - p0 - 0.5 * h * (Lq0 - Lam @ mu0)
        R2 = Q1 - q0 - 0.5 * h * (U0 + U1)
        Qm = 0.5 * (q0 + Q1)
        _, mu_m, h_m, _ = self.model.geometry(Qm)
        R3 = np.einsum("kij,kj->ki", mu_m, (Q1 - q0) / h) + h_m
        if k:
            R3[:, :k] = g1
        return np.concatenate([R1, R2, R3], axis=1)

    def _step_general(self, y0, h):
        n, m = self.n, self.m
        q0, v0 = y0[:n], y0[n:]
        W0, mu0, _, _ = self.model.geometry(q0)
        p0 = W0 @ v0
        lam = self.guess_lambda(y0)
        Lq = self.model.lagrangian_q(y0)
        p_h = p0 + 0.5 * h * (Lq - mu0.T @ lam)
        q1 = q0 + h * np.linalg.solve(W0, p_h)
        z = np.concatenate([p_h, q1, lam])
        scale = np.concatenate([np.full(n, 1.0 + np.max(np.abs(p0))),
                                np.full(n, 1.0 + np.max(np.abs(q0))),
                                np.full(m, 1.0 + np.max(np.abs(lam), initial=0.0))])
        J = None
        best = np.inf
        for it in range(self.maxiter):
            r = self._residual(z[None], q0, p0, W0, mu0, h)[0]
            size = scale.copy()
            if m:
                size[2 * n:] = np.maximum(self._r3(q0, z[n:2 * n], h)[1],
                                          1.0 + np.max(np.abs(p0)))
            err = float(np.max(np.abs(r) / size))
            _finite_or_fail(err)
            if err <= self.tol:
                break
            if it > 3 and err >= best:
                _floor_or_fail(err)
                break
            if J is None or err > 0.1 * best:
                J = self._fd_jacobian(z, r, q0, p0, W0, mu0, h, scale)
            best = min(best, err)
            z = z - np.linalg.solve(J, r)
            self.newton += 1
        else:
            raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the RATTLE step "
                                   f"did not converge (residual {err:.3g}); reduce the step")
        p_h, q1 = z[:n], z[n:2 * n]
        v1, lam1 = self._finish(q1, p_h, h)
        self.lam_guess = lam1
        return np.concatenate([q1, v1]), lam1

    # ------------------------------------------ t and Chetaev's constraints
    def _geometry(self, model, q, v):
        """W, mu, h, g of ``model`` at q, the constraints' rows at (q, v) when they read v
        (mu v + h = phi(q, v) whatever phi); q and v of the same shape."""
        if not self.model.nonlinear:
            return model.geometry(q)
        return model.geometry(np.concatenate([q, v], axis=-1))

    def _residual_extended(self, Z, q0, p0, W0, mu0, h, models):
        """The step's equations for a batch Z (K, 2n+m) of (p_h, q1, lam0), each model at
        its own time (t0, t0 + h/2, t0 + h): the kick with the reaction direction at
        (q0, v0), the drift, and phi(q_m, (q1 - q0)/h) = 0 at the midpoint (g(q1) = 0 for
        the holonomic rows): as the affine scheme, with mu and h read at (q, v)."""
        n, k = self.n, self.k
        m0, mm, m1 = models
        P, Q1, Lam = Z[:, :n], Z[:, n:2 * n], Z[:, 2 * n:]
        U0 = np.linalg.solve(W0, P.T).T
        Lq0 = m0.lagrangian_q(np.concatenate([np.broadcast_to(q0, U0.shape), U0], axis=1))
        Qm, Um = 0.5 * (q0 + Q1), (Q1 - q0) / h
        # W reads q only; where the constraints read v they are read at the mean velocity
        # (v = 0 may be singular for them: sqrt(x'^2 + y'^2))
        W1, _, _, g1 = self._geometry(m1, Q1, Um)
        U1 = np.linalg.solve(W1, P[..., None])[..., 0]
        R1 = P - p0 - 0.5 * h * (Lq0 - Lam @ mu0)
        R2 = Q1 - q0 - 0.5 * h * (U0 + U1)
        _, mu_m, h_m, _ = self._geometry(mm, Qm, Um)
        R3 = np.einsum("kij,kj->ki", mu_m, Um) + h_m
        if k:
            R3[:, :k] = g1
        return np.concatenate([R1, R2, R3], axis=1)

    def _step_extended(self, y0, h, t):
        """One step of the scheme with t in L or the constraints, or constraints nonlinear
        in v (Chetaev's rule: the reaction along mu = d phi/d v). Each half kick takes the
        reaction's direction at its own grid point, (q0, v0) and (q1, v1), and the inner
        constraint is phi(q_m, (q1 - q0)/h, t + h/2) = 0: the step with -h from
        (q1, v1) at t + h is the step's inverse (symmetric, so of even order: 2), and
        phi(q1, v1, t + h) = 0 holds at the grid points."""
        n, m = self.n, self.m
        model = self.model
        models = tuple(model.at_time(t + c * h) for c in (0.0, 0.5, 1.0))
        q0, v0 = y0[:n], y0[n:]
        W0, mu0, _, _ = self._geometry(models[0], q0, v0)
        p0 = W0 @ v0
        lam = self.lam_guess if self.lam_guess is not None else self._lambda_at(models[0], y0)
        Lq = models[0].lagrangian_q(y0)
        p_h = p0 + 0.5 * h * (Lq - mu0.T @ lam)
        z = np.concatenate([p_h, q0 + h * np.linalg.solve(W0, p_h), lam])
        scale = np.concatenate([np.full(n, 1.0 + np.max(np.abs(p0))),
                                np.full(n, 1.0 + np.max(np.abs(q0))),
                                np.full(m, 1.0 + np.max(np.abs(lam), initial=0.0))])
        z = self._newton(lambda Z: self._residual_extended(Z, q0, p0, W0, mu0, h, models),
                         z, scale)
        p_h, q1 = z[:n], z[n:2 * n]
        v1, lam1 = self._finish_extended(models[2], q1, p_h, h, (q1 - q0) / h)
        self.lam_guess = lam1
        return np.concatenate([q1, v1]), lam1

    def _lambda_at(self, model, y0):
        dy, lam, _, status = model.evaluate(y0)
        self.nfev += 1
        if status:
            raise NumericalFailure(Status.SINGULAR, "singular saddle-point system at the "
                                   "initial state")
        return lam

    def _newton(self, residual, z, scale):
        """Newton's method on residual(Z) (batched) from z, with a finite-difference
        Jacobian refreshed when the residual stops falling fast (relative test)."""
        J, best = None, np.inf
        for it in range(self.maxiter):
            r = residual(z[None])[0]
            err = float(np.max(np.abs(r) / scale))
            _finite_or_fail(err)
            if err <= self.tol:
                return z
            if it > 3 and err >= best:
                _floor_or_fail(err)
                return z
            if J is None or err > 0.1 * best:
                eps = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(z), scale)
                R = residual(z[None, :] + np.diag(eps))
                J = ((R - r[None, :]) / eps[:, None]).T
            best = min(best, err)
            z = z - np.linalg.solve(J, r)
            self.newton += 1
        raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the RATTLE step "
                               f"did not converge (residual {err:.3g}); reduce the step")

    def _finish_extended(self, model, q1, p_h, h, mean):
        """The second half kick and phi(q1, v1) = 0, (v1, lam1): a saddle solve for
        constraints affine in v, Newton's method on (v1, lam1) for Chetaev's (mu read at
        the v1 sought; W, free of v, at the step's mean velocity)."""
        n, m = self.n, self.m
        W1 = self._geometry(model, q1, mean)[0]
        u1 = np.linalg.solve(W1, p_h)
        rhs = p_h + 0.5 * h * model.lagrangian_q(np.concatenate([q1, u1]))
        _, mu1, h1, _ = self._geometry(model, q1, u1)
        v1, nu = solve_saddle(W1, mu1, rhs, -h1)
        if not self.model.nonlinear or not m:
            return v1, nu * (2.0 / h)

        def residual(Z):   # W1 v + mu(q1, v)^T nu = rhs, phi(q1, v) = 0; lam1 = 2 nu/h
            V, N = Z[:, :n], Z[:, n:]
            _, mu, hh, _ = self._geometry(model, np.broadcast_to(q1, V.shape), V)
            return np.concatenate([V @ W1.T + np.einsum("kij,ki->kj", mu, N) - rhs,
                                   np.einsum("kij,kj->ki", mu, V) + hh], axis=1)

        scale = np.concatenate([np.full(n, 1.0 + np.max(np.abs(rhs))),
                                np.full(m, 1.0 + np.max(np.abs(nu), initial=0.0))])
        z = self._newton(residual, np.concatenate([v1, nu]), scale)
        return z[:n], z[n:] * (2.0 / h)

    def _fd_jacobian(self, z, r, q0, p0, W0, mu0, h, scale):
        eps = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(z), scale)
        Z = z[None, :] + np.diag(eps)
        R = self._residual(Z, q0, p0, W0, mu0, h)
        return ((R - r[None, :]) / eps[:, None]).T


def _finite_or_fail(err):
    """A non-finite residual: the step left the domain (as the compiled step says)."""
    if not math.isfinite(err):
        raise NumericalFailure(Status.NONFINITE, "non-finite residual in the Newton "
                               "iteration of the RATTLE step; the run was stopped")


def _floor_or_fail(err):
    """Newton stalled: accept at the round-off floor, fail if far from it (``err`` is
    relative)."""
    if err > 1e-9:
        raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the RATTLE step "
                               f"stalled at residual {err:.3g}; reduce the step")


def rattle_step(model, y0, h):
    """One nonholonomic RATTLE step from y0 (2n,) with step h; returns y1 (2n,).

    Exposed for tests of symmetry (a step with -h from y1 returns to y0).
    """
    y1, _ = _RattleStepper(model).step(np.asarray(y0, dtype=float), h)
    return y1


def fixed_recorder(recorder, width, save_every):
    """The given recorder, or one keeping every ``save_every``-th step within the default
    bound."""
    if recorder is not None:
        return recorder
    return Recorder(width, default_max_points(width), int(save_every))


def run_fixed(step_fn, recorder, y0, t0, t1, h, progress=False, deadline=None):
    """Steps of ``step_fn`` from y0; the kept states go into ``recorder``."""
    N, h = step_grid(t0, t1, h)
    y = np.asarray(y0, dtype=float).copy()
    recorder.add(t0, y)
    status, message = Status.SUCCESS, Status.SUCCESS.message
    t = t0
    i = done = reported = 0
    try:
        for i in range(1, N + 1):
            y_new = step_fn(y, h)
            t_new = t0 + i * h
            if not np.all(np.isfinite(y_new)) or np.max(np.abs(y_new)) > 1e150:
                raise NumericalFailure(Status.NONFINITE, f"non-finite or overflowing state at "
                                       f"t = {t_new:.6g} (step {i}); the run was stopped")
            y, t, done = y_new, t_new, i
            if recorder.keep(i):
                recorder.add(t, y)
            if progress:
                reported = report_progress(t, t0, t1, reported)
            if deadline is not None and i < N and deadline.passed():
                status, message = deadline.stop_status(), deadline.message(t)
                break
    except NumericalFailure as exc:
        status, message = exc.status, str(exc)
    except np.linalg.LinAlgError as exc:
        status, message = Status.SINGULAR, f"singular linear system at t = {t:.6g}: {exc}"
    recorder.close(t, y)
    return recorder, status, message, done, h


def rattle(model, y0, t0, t1, h, *, save_every: int = 1, tol=None, recorder=None,
           progress: bool = False, deadline=None) -> FixedStepRun:
    """Integrate with the nonholonomic RATTLE scheme (see the module docstring).

    Parameters
    ----------
    model : NumericModel
    y0 : ndarray, shape (2n,)
        A state on M_1.
    t0, t1 : float
    h : float
        Requested step; the grid uses (t1 - t0)/N with N = ceil((t1 - t0)/h).
    save_every : int
        Store every j-th step (and the last).
    tol : float, optional
        Newton tolerance (default 4 eps, relative to the size of each constraint's terms).
    recorder : Recorder, optional
        Where the states go (:mod:`nhham.numerics.storage`); default: every
        ``save_every``-th step within the default memory bound.
    progress : bool
        Report each tenth of the interval on stderr.
    deadline : Deadline, optional
        Stop with ``Status.TIME_LIMIT`` when it has passed (:class:`~nhham.numerics.run.Deadline`).
    """
    st = _RattleStepper(model, tol=tol)
    recorder = fixed_recorder(recorder, 2 * model.n, save_every)
    if _compiled_ok(st):
        return _compiled_rattle(model, st, y0, t0, t1, h, recorder, 0, progress, deadline)
    clock = _Clock(t0)
    _, status, msg, nsteps, hh = run_fixed(lambda y, h: st.step(y, h, clock.tick(h))[0],
                                            recorder, y0, t0, t1, h, progress, deadline)
    t, y, _ = recorder.result(2 * model.n)
    return Run(t, y, None, status, msg, st.nfev + nsteps + st.newton, nsteps,
               newton_iterations=st.newton, step=hh)


def rattle4(model, y0, t0, t1, h, *, save_every: int = 1, tol=None, recorder=None,
            progress: bool = False, deadline=None) -> FixedStepRun:
    """Fourth order: RATTLE composed with the triple jump (g1, g2, g1) h.

    g1 = 1/(2 - 2^(1/3)), g2 = 1 - 2 g1 (Yoshida 1990; Suzuki 1990): the
    composition of a symmetric method is symmetric of order 4. Constraints
    hold at every substep, hence at every grid point. Options as :func:`rattle`.
    """
    st = _RattleStepper(model, tol=tol)
    recorder = fixed_recorder(recorder, 2 * model.n, save_every)
    if _compiled_ok(st):
        return _compiled_rattle(model, st, y0, t0, t1, h, recorder, 1, progress, deadline)
    clock = _Clock(t0)

    def step(y, h):
        t = clock.tick(h)
        y = st.step(y, _G1 * h, t)[0]
        y = st.step(y, _G2 * h, t + _G1 * h)[0]
        return st.step(y, _G1 * h, t + (_G1 + _G2) * h)[0]

    _, status, msg, nsteps, hh = run_fixed(step, recorder, y0, t0, t1, h, progress, deadline)
    t, y, _ = recorder.result(2 * model.n)
    return Run(t, y, None, status, msg, st.nfev + 3 * nsteps + st.newton, nsteps,
               newton_iterations=st.newton, step=hh)


def _compiled_ok(stepper):
    """The compiled loop runs every model with a compiled library (constant W and W(q),
    nonholonomic and holonomic rows, either path: the step uses the geometry kernels
    only) but those with t in L or a constraint and Chetaev's constraints (the Python
    stepper's extended step); the Python stepper is the fallback of a model without one."""
    return stepper.model.compiled is not None and not stepper.extended


class _Clock:
    """The time of the grid point a fixed-step run is at (as :func:`_run_fixed` counts
    its steps: t0 + i h, never a sum of steps)."""

    def __init__(self, t0):
        self.t0, self.steps = float(t0), 0

    def tick(self, h) -> float:
        """The time at the start of the next step."""
        t = self.t0 + self.steps * h
        self.steps += 1
        return t


_REDUCE_THE_STEP = {Status.NOT_CONVERGED: "; reduce the step"}


def drive_compiled(call, recorder, y, t0, t1, h, info, progress, deadline, scheme) -> tuple:
    """Call a compiled fixed-step loop until it is done: ``call(z_room)`` runs it into the
    recorder's free rows and returns its status; it returns every few milliseconds (so
    that signals and the deadline are handled) and when the room is full. ``info`` is its
    int64 array [steps done, Newton iterations, rows stored by the call, ...]; ``y`` the
    state it updates in place. Returns (status, message, steps done, Newton iterations);
    the recorder is closed on the last state (``scheme`` names the step in a failure)."""
    reported = 0
    while True:
        before = int(info[0])
        t_room, z_room = recorder.room()
        status = Status(call(z_room))
        k = int(info[2])
        if k:  # the rows are the steps after `before` that are multiples of the stride
            s = recorder.stride
            t_room[:k] = t0 + h * ((before // s + 1) * s + s * np.arange(k))
            recorder.advance(k)
        if progress:
            reported = report_progress(t0 + h * int(info[0]), t0, t1, reported)
        if status != Status.PAUSED:
            break
        if deadline is not None and deadline.passed():
            status = deadline.stop_status()
            break
    done, newton = int(info[0]), int(info[1])
    recorder.close(t0 + h * done, y)
    msg = status.message if status == 0 else deadline.message(t0 + h * done) if (
        status in STOPPED) else (
        f"{status.message} in the {scheme} step at t = {t0 + (done + 1) * h:.6g} "
        f"(step {done + 1}){_REDUCE_THE_STEP.get(status, '')}; the run was stopped")
    return status, msg, done, newton


def _compiled_rattle(model, st, y0, t0, t1, h, recorder, composition, progress, deadline):
    """The compiled RATTLE loop (:func:`drive_compiled`)."""
    N, h = step_grid(t0, t1, h)
    y = np.array(y0, dtype=float)
    recorder.add(t0, y)
    try:
        lam = np.append(st.guess_lambda(y), 0.0)
    except NumericalFailure as exc:  # the field is singular at the initial state
        T, Y, _ = recorder.result(2 * model.n)
        return Run(T, Y, None, exc.status, str(exc), st.nfev, 0, step=h)
    wsp = np.empty(2 * model.n * model.n)
    info = np.zeros(3, dtype=np.int64)  # steps done, Newton iterations, rows stored
    pointer = model.parameter_block().pointer
    first = [True]

    def call(z_room):
        status = model.compiled.rattle(y, h, N, recorder.stride, composition,
                                       not model.constant_W, z_room, pointer, lam, wsp,
                                       first[0], st.tol, st.maxiter, PAUSE_SECONDS, info)
        first[0] = False
        return status

    status, msg, done, newton = drive_compiled(call, recorder, y, t0, t1, h, info, progress,
                                               deadline, "RATTLE")
    T, Y, _ = recorder.result(2 * model.n)
    # A step costs about one field evaluation plus one per Newton iteration.
    return Run(T, Y, None, status, msg, st.nfev + done * (1 + composition * 2) + newton,
               done, newton_iterations=newton, step=h)


# --------------------------------------------------------------------- RK4
def rk4(model, y0, t0, t1, h, *, projection: bool = False, baumgarte=None,
        save_every: int = 1, recorder=None, progress: bool = False,
        deadline=None) -> FixedStepRun:
    """Classical fourth-order Runge-Kutta on the projected field.

    Each stage sets the model's time to its own (t, t + h/2, t + h) where L, a
    constraint or a force depends on t. With ``projection`` every step ends with
    :meth:`NumericModel.project` at the step's end time (Newton for g,
    kinetic-metric projection of v onto M_1(t + h)). The work of the
    constraint forces is integrated with the same weights as the state.
    ``save_every`` and ``recorder`` as in :func:`rattle` (the recorder's width is
    2n + 1: the state and the work).
    """
    n2 = 2 * model.n
    counter = {"nfev": 0, "steps": 0}
    field = model.field_function(baumgarte)  # z (2n + 1) -> [dy, power] or a status
    timed = model.time_slot is not None

    def at(t):
        # t in L, a constraint or a force: the model with its time slot at the stage's t
        return model.at_time(t) if timed else model

    def f(z, t):
        out = (at(t).field_function(baumgarte) if timed else field)(z)
        counter["nfev"] += 1
        if isinstance(out, int):
            raise NumericalFailure(out)
        return out

    def step(z, h):
        t = t0 + counter["steps"] * h  # the grid's time (as _run_fixed counts it)
        counter["steps"] += 1
        k1 = f(z, t)
        k2 = f(z + 0.5 * h * k1, t + 0.5 * h)
        k3 = f(z + 0.5 * h * k2, t + 0.5 * h)
        k4 = f(z + h * k3, t + h)
        z = z + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
        if projection:
            z[:n2] = at(t + h).project(z[:n2]).y  # onto M_1(t + h)
        return z

    z0 = np.append(np.asarray(y0, dtype=float), 0.0)
    recorder = fixed_recorder(recorder, n2 + 1, save_every)
    _, status, msg, nsteps, hh = run_fixed(step, recorder, z0, t0, t1, h, progress, deadline)
    t, y, work = recorder.result(n2)
    return Run(t, y, work, status, msg, counter["nfev"], nsteps, step=hh)
