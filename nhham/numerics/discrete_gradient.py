"""An energy-exact integrator: a discrete gradient with the constraints kept at the grid points.

For L = 1/2 v^T W(q) v + b(q) . v - V(q) (b: a gyroscopic term, or none), p = W v + b,
H(q, p) = 1/2 (p - b)^T W(q)^-1 (p - b) + V(q) and constraints
phi = mu(q) v + h(q) (complete lifts of the holonomic g first), one step
(q0, p0) -> (q1, p1) of size h solves, for (q1, p1, lambda, nu)::

    q1 - q0 = h dH_p - K G^T nu                     (K G^T: holonomic rows' correction)
    p1 - p0 = -h dH_q - h R lambda
    phi(q1, p1) = 0,   g(q1) = 0

where dH = (dH_q, dH_p) is Gonzalez's midpoint discrete gradient of H,

    dH = grad H(x_m) + (H(x1) - H(x0) - grad H(x_m) . dx) / |dx|^2 dx,
    x_m = (x0 + x1)/2,  dx = x1 - x0,

so that H(x1) - H(x0) = dH . dx holds identically (O. Gonzalez, "Time integration and
discrete Hamiltonian systems", J. Nonlinear Sci. 6 (1996) 449-467), and the reaction's
direction is mu(q_m)^T made to do, along the step, exactly the work the affine terms do:

    R = mu_m^T - w c^T,   w = W(q_m) dH_p,   c = (mu_m dH_p + h_m) / (dH_p . w),

so that dH_p . R lambda = -h_m . lambda. Then

    H(x1) - H(x0) = h h(q_m) . lambda    (0 for linear constraints)

to rounding at every step: the energy is kept exactly where the constraints are linear
and, where they are affine, its balance with the work of the reactions (the run carries
that work). The holonomic rows' position correction K G^T nu (K = W(q_m)^-1,
G = dg/dq at q_m) is taken orthogonal to dH_q in the same way. As mu_m dH_p + h_m = 0
up to O(h^2) on M_1, R = mu^T + O(h^2): the scheme is consistent, symmetric (the step
with -h from x1 returns to x0, with -lambda and -nu) and so of order 2.

This is a discrete-gradient method on the nonholonomic equations with multipliers; the
almost-Poisson discrete gradients of E. Celledoni, M. Farre Puiggali, E. H. Hoiseth and
D. Martin de Diego (arXiv:1605.02845) keep the energy the same way and the constraints
only to the order of the method: here the multipliers put the state on M_1 at each grid
point. Forces, t and Chetaev's constraints are refused (:data:`nhham.numerics.methods.METHODS`):
with forces that do work the energy's balance would need the applied force apart from the
field, which the generated kernels do not give.

No sympy here.
"""

from __future__ import annotations

import math

import numpy as np

from nhham.numerics.integrators import drive_compiled, fixed_recorder, run_fixed, step_grid
from nhham.numerics.run import PAUSE_SECONDS, Run
from nhham.numerics.status import NumericalFailure, Status

__all__ = ["energy_exact", "energy_exact_step", "EnergyExactStepper"]

#: A residual (relative to its block's largest row) at which Newton's method may stop
#: when it no longer halves: rounding, with a margin for rows of many terms; with a
#: Jacobian of the last iterate, up to FLOOR (as RATTLE's floor test). The C loop's too.
ROUNDING = 1e-13
FLOOR = 1e-9


class EnergyExactStepper:
    """One step of the scheme of the module docstring; counts Newton iterations.

    Parameters
    ----------
    model : NumericModel
        Quadratic in v (``model.quadratic``), autonomous, constraints affine in v.
    tol : float, optional
        Newton stops when its update is below ``tol`` relative to the unknowns' scale
        (default eps: the energy identity holds to the residual, so the iteration goes
        to rounding) or where the residual stalls at rounding.
    """

    def __init__(self, model, tol=None, maxiter: int = 30):
        self.model = model
        self.n, self.m, self.k = model.n, model.m, model.k
        self.tol = tol if tol is not None else np.finfo(float).eps
        self.maxiter = maxiter
        self.newton = 0
        self.nfev = 0
        self.work = 0.0
        self._J = None
        self._history: list = []

    # ------------------------------------------------------------ pieces
    def offset(self, Q):
        """b(q) of L = v^T W v / 2 + b . v - V (p = W v + b): zeros without linear terms."""
        if not self.model.layout.get("linear_terms"):
            return np.zeros(np.shape(Q))
        Q = np.asarray(Q, dtype=float)
        if Q.ndim == 1:
            return np.asarray(self.model.kernels.scalar("linear", Q.tolist(),
                                                        list(self.model.parameter_values)))
        return self.model.kernels.batch("linear", Q, list(self.model.parameter_values))

    def momentum(self, y):
        """p = dL/dv = W(q) v + b(q) at the state y (2n,)."""
        q = y[:self.n]
        return self.model.geometry(q)[0] @ y[self.n:] + self.offset(q)

    def _hamiltonian(self, Q, P):
        """H and v = W^-1 (p - b) at a batch of (q, p); also W, mu, h, g there."""
        W, mu, hh, g = self.model.geometry(Q)
        V = np.linalg.solve(W, (P - self.offset(Q))[..., None])[..., 0]
        H = self.model.energy(np.concatenate([Q, V], axis=-1))
        return H, V, W, mu, hh, g

    def residual(self, Z, q0, p0, H0, h):
        """The step's equations for a batch Z (K, 2n + m + k) of (q1, p1, lambda, nu);
        also the work of the reactions along each (h h_m . lambda) and the size of each
        row's terms (K, 2n + m + k), which its rounding is relative to."""
        n, m, k = self.n, self.m, self.k
        Q1, P1, Lam, Nu = Z[:, :n], Z[:, n:2 * n], Z[:, 2 * n:2 * n + m], Z[:, 2 * n + m:]
        H1, V1, W1, mu1, h1, g1 = self._hamiltonian(Q1, P1)
        Qm, Pm = 0.5 * (q0 + Q1), 0.5 * (p0 + P1)
        _, Vm, Wm, mum, hm, _ = self._hamiltonian(Qm, Pm)
        self.nfev += 3 * Z.shape[0]
        gq = -self.model.lagrangian_q(np.concatenate([Qm, Vm], axis=1))   # dH/dq = -dL/dq
        dq, dp = Q1 - q0, P1 - p0
        size2 = np.sum(dq * dq, axis=1) + np.sum(dp * dp, axis=1)
        rest = H1 - H0 - np.sum(gq * dq, axis=1) - np.sum(Vm * dp, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(size2 > 0, rest / np.where(size2 > 0, size2, 1.0), 0.0)
        dHq, dHp = gq + s[:, None] * dq, Vm + s[:, None] * dp
        # the reaction along mu_m^T, its work along the step made h_m . lambda exactly
        w = np.einsum("kij,kj->ki", Wm, dHp)
        ww = np.sum(dHp * w, axis=1)
        c = np.einsum("kij,kj->ki", mum, dHp) + hm
        with np.errstate(divide="ignore", invalid="ignore"):
            c = np.where(ww[:, None] > 0, c / np.where(ww > 0, ww, 1.0)[:, None], 0.0)
        react = np.einsum("kij,ki->kj", mum, Lam) - w * np.sum(c * Lam, axis=1)[:, None]
        R1 = dq - h * dHp
        R2 = dp + h * dHq + h * react
        R3 = np.einsum("kij,kj->ki", mu1, V1) + h1
        R4 = np.zeros((Z.shape[0], 0))
        terms = np.concatenate([np.abs(dq) + h * np.abs(dHp),
                                np.abs(dp) + h * (np.abs(dHq) + np.abs(react)),
                                np.einsum("kij,kj->ki", np.abs(mu1), np.abs(V1))
                                + np.abs(h1), np.abs(g1)], axis=1)
        if k:
            # g(q1) = 0 by a position correction along K G^T (G = the lifts' rows, the
            # first k of mu), made orthogonal to dH_q so that it does no work
            G = mum[:, :k, :]
            D = np.linalg.solve(Wm, np.swapaxes(G, 1, 2))              # (K, n, k)
            sq = np.linalg.solve(Wm, dHq[..., None])[..., 0]
            qq = np.sum(dHq * sq, axis=1)
            e = np.einsum("kj,kja->ka", dHq, D)
            with np.errstate(divide="ignore", invalid="ignore"):
                e = np.where(qq[:, None] > 0, e / np.where(qq > 0, qq, 1.0)[:, None], 0.0)
            D = D - sq[:, :, None] * e[:, None, :]
            R1 = R1 + np.einsum("kja,ka->kj", D, Nu)
            R4 = g1
        return (np.concatenate([R1, R2, R3, R4], axis=1), h * np.sum(hm * Lam, axis=1),
                terms)

    def _scale(self, q0, p0, lam):
        """The unknowns' scales, one each (the finite differences' steps and the update's
        test): 1 + |q0_i|, 1 + |p0_i|, 1 + |lambda_a|, and 1 + max |q0| for nu."""
        return np.concatenate([1.0 + np.abs(q0), 1.0 + np.abs(p0), 1.0 + np.abs(lam),
                               np.full(self.k, 1.0 + np.max(np.abs(q0), initial=0.0))])

    def _row_size(self, y0, p0):
        """The size of each equation's terms, its rounding relative to it: 1 + |q0_i| for
        the positions', 1 + |p0_i| for the momenta's, 1 + |mu v0| + |h| for a constraint's,
        1 + max |q0| for g's. Per row: a roll of 1e-6 beside a wheel angle of 500 rad is
        solved to its own rounding."""
        n = self.n
        q0, v0 = y0[:n], y0[n:]
        _, mu, hh, _ = self.model.geometry(q0)
        return np.concatenate([1.0 + np.abs(q0), 1.0 + np.abs(p0),
                               1.0 + np.abs(mu) @ np.abs(v0) + np.abs(hh),
                               np.full(self.k, 1.0 + np.max(np.abs(q0), initial=0.0))])

    def _block_size(self, size):
        """Each row's block's largest size (positions, momenta, constraints, g)."""
        n, m = self.n, self.m
        out = size.copy()
        for lo, hi in ((0, n), (n, 2 * n), (2 * n, 2 * n + m), (2 * n + m, out.size)):
            if hi > lo:
                out[lo:hi] = np.max(size[lo:hi])
        return out

    # -------------------------------------------------------------- step
    def step(self, y0, h):
        """(y1, reactions' work over the step) after one step of size h from y0 (q, v);
        where Newton's method does not converge from the extrapolated guess and the kept
        Jacobian, once more from the field's own guess with a new one."""
        try:
            return self._step(y0, h)
        except NumericalFailure as exc:
            if exc.status != Status.NOT_CONVERGED:
                raise
            self._history.clear()
            self._J = None
            return self._step(y0, h)

    def _step(self, y0, h):
        n, m = self.n, self.m
        q0 = y0[:n]
        p0 = self.momentum(y0)
        H0 = float(self.model.energy(y0))
        z = self._guess(y0, q0, p0, h)
        scale, size = self._scale(q0, p0, z[2 * n:2 * n + m]), self._row_size(y0, p0)
        block = self._block_size(size)

        def resid(Z):
            return self.residual(Z, q0, p0, H0, h)

        best, work, fresh = np.inf, 0.0, False
        for it in range(self.maxiter):
            r, wk, terms = resid(z[None])
            r, work = r[0], float(wk[0])
            err = float(np.max(np.abs(r) / np.maximum(size, terms[0])))
            if not math.isfinite(err):
                raise NumericalFailure(Status.NONFINITE, "non-finite residual in the Newton "
                                       "iteration of the energy-exact step; the run was stopped")
            if it > 0 and err >= 0.5 * best:   # no longer halving: at rounding, or stuck
                # rounding: against each block's largest (a roll's row takes the rounding
                # of the wheels' terms through the solve); with a Jacobian of the last
                # iterate, the floor of the rows' evaluation (sin of a wheel angle of 1e3
                # rad carries 1e3 eps), unless far from it
                errb = float(np.max(np.abs(r) / block))
                if errb <= ROUNDING or (fresh and errb <= FLOOR):
                    break
                if fresh:
                    raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the "
                                           f"energy-exact step stalled at residual {err:.3g}; "
                                           f"reduce the step")
            # The last Jacobian is kept from step to step while it contracts ten-fold an
            # iteration (a Jacobian is one batched call, about two residuals' cost)
            fresh = self._J is None or (it > 0 and err > 0.1 * best and err > ROUNDING)
            if fresh:
                eps = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(z), scale)
                R = resid(z[None, :] + np.diag(eps))[0]
                self._J = ((R - r[None, :]) / eps[:, None]).T
            best = min(best, err)
            dz = np.linalg.solve(self._J, r)
            z = z - dz
            self.newton += 1
            if np.max(np.abs(dz) / scale) <= self.tol:   # the update is at rounding
                break
        else:
            if float(np.max(np.abs(r) / block)) > FLOOR:   # still far from rounding
                raise NumericalFailure(Status.NOT_CONVERGED, f"Newton iteration of the "
                                       f"energy-exact step did not converge (residual "
                                       f"{err:.3g}); reduce the step")
        q1, p1 = z[:n], z[n:2 * n]
        W1 = self.model.geometry(q1)[0]
        v1 = np.linalg.solve(W1, p1 - self.offset(q1))
        y1 = np.concatenate([q1, v1])
        self._remember(h, y1, z)
        return y1, work

    def _guess(self, y0, q0, p0, h):
        """(q1, p1, lambda, nu) extrapolated from the last grid points (a quadratic through
        three, a line through two) where the run continues at y0 with the same h; else a
        Taylor step of the field (q' = v, v' = a) with its multipliers."""
        n, m, k = self.n, self.m, self.k
        hist = self._history
        if hist and (hist[-1][0] != h or not np.array_equal(hist[-1][1], y0)):
            hist.clear()
        if len(hist) >= 2:
            zs = [entry[2] for entry in hist[-3:]]
            if len(zs) == 3:
                return 3.0 * zs[2] - 3.0 * zs[1] + zs[0]
            return 2.0 * zs[1] - zs[0]
        dy, lam, _, status = self.model.evaluate(y0)
        self.nfev += 1
        if status:
            raise NumericalFailure(Status.SINGULAR, "the field is not defined at the initial "
                                   "state of the energy-exact step")
        q1 = q0 + h * y0[n:] + 0.5 * h * h * dy[n:]
        p1 = self.momentum(np.concatenate([q1, y0[n:] + h * dy[n:]]))
        return np.concatenate([q1, p1, np.asarray(lam, dtype=float)[:m], np.zeros(k)])

    def _remember(self, h, y1, z):
        """Keep (h, y1, z) of the last three steps for the next guesses."""
        self._history.append((h, y1, z))
        del self._history[:-3]


def energy_exact_step(model, y0, h):
    """One step of :func:`energy_exact` from y0 (2n,); returns y1 (2n,) (for tests of
    symmetry: the step with -h from y1 returns to y0)."""
    return EnergyExactStepper(model).step(np.asarray(y0, dtype=float), h)[0]


def energy_exact(model, y0, t0, t1, h, *, save_every: int = 1, tol=None, recorder=None,
                 progress: bool = False, deadline=None) -> Run:
    """Integrate with the energy-exact discrete-gradient scheme (module docstring).

    Parameters
    ----------
    model : NumericModel
        L quadratic in v, autonomous, constraints affine in v (linear ones keep the
        energy; affine ones its balance with the reactions' work, which ``Run.work``
        carries).
    y0 : ndarray, shape (2n,)
        A state on M_1.
    t0, t1, h : float
        Interval and requested step (the grid uses (t1 - t0)/N, N = ceil((t1 - t0)/h)).
    save_every, tol, recorder, progress, deadline
        As :func:`nhham.numerics.integrators.rattle`.

    Returns
    -------
    Run
        ``y`` of shape (2n, K), ``work`` (K,) the reactions' work since t0.

    Examples
    --------
    >>> import numpy as np
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> y0 = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5,
    ...                       theta_dot=1.0))
    >>> run = energy_exact(model, y0, 0.0, 10.0, 0.1)
    >>> E = model.energy(run.y.T)
    >>> bool(np.max(np.abs(E - E[0])) < 1e-14 * abs(E[0]))
    True
    """
    st = EnergyExactStepper(model, tol=tol)
    n = model.n
    recorder = fixed_recorder(recorder, 2 * n + 1, save_every)
    if model.compiled is not None and model.compiled.has_dgrad():
        return _compiled(model, st, y0, t0, t1, h, recorder, progress, deadline)
    total = [0.0]

    def step(y, hh):
        y1, work = st.step(y[:2 * n], hh)
        total[0] += work
        return np.concatenate([y1, [total[0]]])

    _, status, msg, nsteps, hh = run_fixed(step, recorder, np.concatenate([y0, [0.0]]),
                                            t0, t1, h, progress, deadline)
    t, y, work = recorder.result(2 * n)
    return Run(t, y, work, status, msg, st.nfev, nsteps, newton_iterations=st.newton, step=hh)


def _compiled(model, st, y0, t0, t1, h, recorder, progress, deadline) -> Run:
    """The compiled loop (``nhham_dgrad`` in ``nhham/numerics/c/dgrad.c``: the same
    equations, guesses and Newton iterations), called until done: it returns every few
    milliseconds (signals, the deadline) and when the recorder's room is full."""
    N, h = step_grid(t0, t1, h)
    n, m, k = model.n, model.m, model.k
    y = np.append(np.asarray(y0, dtype=float), 0.0)
    recorder.add(t0, y)
    nz = 2 * n + m + k
    wsp = np.zeros(3 * nz + nz * nz)
    info = np.zeros(5, dtype=np.int64)
    pointer = model.parameter_block().pointer

    def call(z_room):
        return model.compiled.dgrad(y, h, N, recorder.stride, z_room, pointer, wsp, st.tol,
                                    st.maxiter, PAUSE_SECONDS, info)

    status, msg, done, newton = drive_compiled(call, recorder, y, t0, t1, h, info, progress,
                                               deadline, "energy-exact")
    T, Y, work = recorder.result(2 * n)
    # a step costs about four residuals (three kernel calls each) and a Jacobian
    return Run(T, Y, work, status, msg, 3 * (newton + done), done, newton_iterations=newton,
               step=h)
