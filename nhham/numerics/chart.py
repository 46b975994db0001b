"""Independent coordinates on M_1 and the complex-step Jacobian of the field in them.

A chart (:class:`Chart`) splits the coordinates and velocities into independent ones and
dependent ones solved from the constraints (Newton's method for the holonomic ones, a
linear solve for the velocities). :func:`reduced_field` is the constrained field in the
chart (the dependent velocities of a nonlinear (Chetaev) constraint by Newton's method from
the state's own: its branch), evaluated on complex states through the generated kernels
(:class:`ComplexField`), so that :func:`chart_jacobians` differentiates it by the complex
step dF/dx_j = Im F(x + i h e_j) / h: exact to rounding. Shared by
:mod:`nhham.numerics.linearization` (one state) and
:mod:`nhham.numerics.batch_linearization` (many). No sympy.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from nhham.errors import ComputationError, InconsistentInitialDataError, InputError
from nhham.numerics.kernels import columns, read_parameters
from nhham.numerics.nullspace import solve_null_space

__all__ = ["BATCH_STATES", "STEP", "Chart", "ComplexField", "chart_jacobian", "chart_jacobians",
           "chart_gradients", "choose_chart", "dependent_velocities", "greedy_columns",
           "input_jacobians", "lift", "lifted_states", "reduced_field"]

#: Imaginary step of the complex-step derivative.
STEP = 1e-30

# States per batch of the generated numpy kernel: large enough to spread one call's
# overhead over many states, small enough to bound its temporaries (10^4 states of the
# bicycle in one batch: 28 s for the whole sweep, a third of it in page faults; in
# batches of 16, 32, 64, 128, 256: 17.4, 17.7, 17.6, 16.1, 15.5 s).
BATCH_STATES = 256


class ComplexField:
    """The constrained field on complex states, through the generated kernels: the
    compiled complex ones (:class:`~nhham.numerics.kernels.ComplexKernels`) when they
    are in the compile cache or ``build`` (compiled now: worth it for thousands of
    states, not for one linearisation), else the numpy batch kernels on complex arrays
    (the same expressions)."""

    def __init__(self, model, build: bool = False):
        self.n, self.m, self.k = model.n, model.m, model.k
        self.names = tuple(model.names)
        # a nonlinear (Chetaev) constraint: mu and h read (q, v), the dependent velocities
        # are solved by Newton's method (dependent_velocities)
        self.nonlinear = bool(getattr(model, "nonlinear", False))
        # and W of a Lagrangian not quadratic in v: the geometry kernel reads (q, v)
        self.geometry_reads_v = bool(getattr(model, "geometry_reads_v", self.nonlinear))
        try:
            self._batch = model.kernels.functions["saddle"][1]
            self._geometry_batch = model.kernels.functions["geometry"][1]
        except (AttributeError, KeyError, IndexError, TypeError):  # pragma: no cover
            raise ComputationError("linearize: the numeric model has no numpy saddle kernel "
                                   "for complex-step differentiation") from None
        from nhham.numerics.codegen.build import complex_kernels

        self._compiled = complex_kernels(model, build_now=build)
        self._p = [float(x) for x in model.parameter_values]
        self._used = read_parameters(model.layout)   # what the compiled kernels read
        n, m, k = self.n, self.m, self.k
        self.size = n * n + n + m * n + 3 * m + k + int(model.forced)

    @property
    def backend(self) -> str:
        """``"c"`` (compiled complex kernels) or ``"numpy"``."""
        return "numpy" if self._compiled is None else "c"

    def _outputs(self, name, Y, p):
        """The kernel's outputs at the complex rows Y (K, width), shape (K, outputs)."""
        p = self._p if p is None else p
        # the compiled kernels take real parameters as rows (K, parameters) or one row
        # (B differentiates in the inputs' parameter slots: complex ones, through numpy);
        # a study passes rows already (no restacking under the GIL at every call)
        rows = isinstance(p, np.ndarray) and p.ndim == 2
        if self._compiled is not None and not (np.iscomplexobj(p) if rows else
                                               any(np.iscomplexobj(v) for v in p)):
            if rows or all(np.ndim(v) == 0 for v in p):
                P = np.asarray(p, dtype=float)
            else:
                P = np.column_stack([np.broadcast_to(np.asarray(v, dtype=float),
                                                     (Y.shape[0],)) for v in p])
            if self._used is not None:
                P = P[..., self._used]
            with np.errstate(all="ignore"):
                return self._compiled.complex_batch(name, Y, P)
        if rows:
            p = list(p.T)
        size = self.size if name == "saddle" else self.n * self.n + self.m * self.n + \
            self.m + self.k
        YT = np.ascontiguousarray(Y.T.astype(complex))
        out = np.zeros((size, YT.shape[1]), dtype=complex)
        with np.errstate(all="ignore"):
            (self._batch if name == "saddle" else self._geometry_batch)(YT, p, out)
        return out.T

    def pieces(self, Q, V, p=None):
        """W, F, mu, drift, h, g at complex states (rows of Q, V: shape (K, n)); ``p``:
        the parameter values, one number each or one array of K values each, or an array
        of shape (K, parameters) (a row's own parameters)."""
        n, m, k = self.n, self.m, self.k
        out = self._outputs("saddle", np.concatenate([Q, V], axis=1), p)
        K = out.shape[0]
        W, F, mu, drift, h, g = columns(out, (n * n, n, m * n, m, m, k))
        return W.reshape(K, n, n), F, mu.reshape(K, m, n), drift, h, g

    def geometry(self, Q, p=None, V=None):
        """mu, h, g at complex coordinates (rows of Q: shape (K, n)): the kernel of the
        coordinates only (no F, no drift), for lifting points onto M_1; where the kernel
        reads (q, v) (a nonlinear constraint, an L not quadratic in v) the velocities V
        (K, n) too."""
        n, m, k = self.n, self.m, self.k
        out = self._outputs("geometry", np.concatenate([Q, V], axis=1)
                            if self.geometry_reads_v else Q, p)
        _, mu, h, g = columns(out, (n * n, m * n, m, k))
        return mu.reshape(out.shape[0], m, n), h, g

    def accelerations(self, Q, V, p=None):
        """The accelerations at the complex states of the complex step (imaginary parts of
        the order of its h), by the null-space solve (:mod:`nhham.numerics.nullspace`, as
        every solve of the accelerations) of K0 z0 = r0 and K0 z1 = r1 - K1 z0 for
        K = K0 + i K1, z = z0 + i z1, dropping K1 z1 (h^2 = 1e-60 against z0: below
        rounding). A complex LU would lose the derivative of a small acceleration at
        extreme mass ratios as the real one loses the acceleration."""
        W, F, mu, drift, _, _ = self.pieces(Q, V, p)
        try:
            with np.errstate(all="ignore"):
                return _split_null_space(W, F, mu, drift)
        except np.linalg.LinAlgError:
            raise ComputationError("linearize: the saddle-point matrix [[W, mu^T], [mu, 0]] is "
                                   "singular at the state (C singular: M_f is not M_1 here)") from None


def _split_null_space(W, F, mu, drift):
    """The same by the null-space solve of the real part and of the first-order imaginary
    part (see :meth:`ComplexField.accelerations`)."""
    W0, mu0 = W.real, mu.real
    a0, lam0 = solve_null_space(W0, mu0, F.real, -drift.real)
    top1 = F.imag - _mv(W.imag, a0) - _mv(np.swapaxes(mu.imag, 1, 2), lam0)
    a1, _ = solve_null_space(W0, mu0, top1, -drift.imag - _mv(mu.imag, a0))
    return a0 + 1j * a1


def _mv(A, x):
    return np.einsum("...ij,...j->...i", A, x)


@dataclass(frozen=True)
class Chart:
    iq: tuple   # independent coordinate indices
    dq: tuple   # dependent coordinate indices
    iv: tuple   # independent velocity indices
    dv: tuple   # dependent velocity indices


def greedy_columns(M, count, order, tol=1e-8):
    """``count`` columns of M (tried in ``order``) that are independent."""
    chosen = []
    scale = max(1.0, float(np.abs(M).max(initial=0.0)))
    for j in order:
        trial = chosen + [j]
        s = np.linalg.svd(M[:, trial], compute_uv=False)
        if s.size and s[-1] > tol * scale:
            chosen.append(j)
        if len(chosen) == count:
            break
    return chosen


def choose_chart(model, y0, independent) -> Chart:
    n, m, k = model.n, model.m, model.k
    names = model.names
    _, mu, _, _ = model.geometry(y0)
    if not np.all(np.isfinite(mu)):
        raise InconsistentInitialDataError(
            "steady: the constraints are not finite at the state (a function of theirs "
            "outside its domain there); choose a [steady] state where they are", key="steady")
    G = mu[:k]  # rows of the complete lifts: dg/dq
    if independent is not None:
        unknown = [s for s in independent if s not in names]
        if unknown:
            raise InputError(f"linearize: independent: unknown name(s) {', '.join(unknown)} "
                             f"(state names: {', '.join(names)})")
        iq = [i for i in range(n) if names[i] in independent]
        iv = [i for i in range(n) if names[n + i] in independent]
        dq = [i for i in range(n) if i not in iq]
        dv = [i for i in range(n) if i not in iv]
        if len(dq) != k or len(dv) != m:
            raise InputError(f"linearize: independent: need {n - k} coordinates and {n - m} "
                             f"velocities, got {len(iq)} and {len(iv)}")
        if k and np.linalg.matrix_rank(G[:, dq]) < k or m and np.linalg.matrix_rank(mu[:, dv]) < m:
            raise InputError("linearize: independent: the constraints cannot be solved for the "
                             "other coordinates or velocities at this state")
        return Chart(tuple(iq), tuple(dq), tuple(iv), tuple(dv))
    dq = greedy_columns(G, k, range(n)) if k else []
    # the user's state: no chart of M_1 there is bad input, said with what to change
    if len(dq) < k:
        raise InconsistentInitialDataError(
            "steady: the holonomic constraints are singular at the state (their gradients "
            "dependent: no coordinates solve them there); choose another [steady] state",
            key="steady")
    order = list(dq) + [i for i in range(n) if i not in dq]
    dv = greedy_columns(mu, m, order) if m else []
    if len(dv) < m:
        raise InconsistentInitialDataError(
            "steady: the constraint one-forms are dependent at the state (no velocities "
            "solve them there); choose another [steady] state", key="steady")
    iq = [i for i in range(n) if i not in dq]
    iv = [i for i in range(n) if i not in dv]
    return Chart(tuple(iq), tuple(sorted(dq)), tuple(iv), tuple(sorted(dv)))


def reduced_field(cf, chart, q0, X, p=None, positions=True, v0=None, shift=None):
    """F(x) for chart points X (K, d) complex, lifted onto M_1; q0: the coordinates the
    dependent ones start from, (n,) or one row per point (K, n); p: as for
    :meth:`ComplexField.pieces`. ``positions=False``: the points' coordinates are those of
    q0 (already on Q_1: only velocities moved), so no Newton iteration is needed. ``v0``:
    the velocities Newton's method starts the dependent ones from, with a nonlinear
    constraint (its branch). ``shift``: ``shift(Q, V) -> (K, 2n)``, a field on the lifted
    states subtracted from the constrained one (w Xi of a relative equilibrium:
    :mod:`nhham.numerics.relative`), in the chart's components."""
    n = cf.n
    iq, iv = list(chart.iq), list(chart.iv)
    Q, V = lifted_states(cf, chart, q0, X, p, positions, v0)
    a = cf.accelerations(Q, V, p)
    if shift is not None:
        s = shift(Q, V)
        return np.concatenate([V[:, iq] - s[:, iq], a[:, iv] - s[:, [n + i for i in iv]]],
                              axis=1)
    return np.concatenate([V[:, iq], a[:, iv]], axis=1)


def lifted_states(cf, chart, q0, X, p=None, positions=True, v0=None) -> tuple:
    """(Q, V) (K, n) complex: the chart points X (K, d) lifted onto M_1 (the arguments as
    for :func:`reduced_field`): the dependent coordinates by Newton's method on the
    holonomic constraints, the dependent velocities from the velocity constraints."""
    n = cf.n
    K = X.shape[0]
    iq, dq, iv, dv = (list(a) for a in (chart.iq, chart.dq, chart.iv, chart.dv))
    Q = np.array(np.broadcast_to(q0, (K, n)), dtype=complex)
    Q[:, iq] = X[:, :len(iq)]
    V = np.zeros((K, n), dtype=complex) if v0 is None else np.array(
        np.broadcast_to(v0, (K, n)), dtype=complex)
    V[:, iv] = X[:, len(iq):]
    geometry = None
    if dq and positions:
        for _ in range(30):
            geometry = mu, _, g = cf.geometry(Q, p, V)
            G = mu[:, :cf.k, :][:, :, dq]
            step = np.linalg.solve(G, g[..., None])[..., 0]
            Q[:, dq] -= step
            if np.abs(step).max() <= 1e-15 * max(1.0, np.abs(Q[:, dq].real).max()):
                break
        else:
            raise ComputationError("linearize: Newton iteration for the dependent coordinates "
                                   "did not converge")
    if dv and cf.nonlinear:
        V[:, dv], singular = dependent_velocities(cf, Q, V, dv, p)
        if singular.any():
            raise ComputationError("linearize: Newton's method for the dependent velocities "
                                   "(a nonlinear constraint) did not converge")
    elif dv:
        # the last Newton iterate's mu and h: the step after it was below rounding
        mu, h, _ = cf.geometry(Q, p, V) if geometry is None else geometry
        rhs = -(np.einsum("kij,kj->ki", mu[:, :, iv], V[:, iv]) + h)
        V[:, dv] = np.linalg.solve(mu[:, :, dv], rhs[..., None])[..., 0]
    return Q, V


def lift(cf, chart, Y, P=None, iterations: int = 30) -> tuple:
    """The states Y (N, 2n) moved onto M_1 in the chart: the dependent coordinates solved
    from the holonomic constraints by Newton's method from their values in Y (the
    independent ones held), then the dependent velocities from the velocity constraints.

    Parameters
    ----------
    cf : ComplexField
    chart : Chart
    Y : ndarray, shape (N, 2n)
    P : ndarray, shape (N, parameters), optional
        Each state's parameters (default: the model's).
    iterations : int, optional

    Returns
    -------
    (ndarray, ndarray)
        The lifted states, shape (N, 2n), and ``ok`` (N,): False where Newton's method did
        not converge or a constraint matrix was singular (no state of M_1 near Y's, in
        this chart); those rows are returned as given.
    """
    n, k = cf.n, cf.k
    Y = np.asarray(Y, dtype=float)
    N = Y.shape[0]
    Q = Y[:, :n].astype(complex)
    V = Y[:, n:].astype(complex)
    ok = np.isfinite(Y).all(axis=1)
    dq, iv, dv = list(chart.dq), list(chart.iv), list(chart.dv)
    if dq:
        done = ~ok
        for _ in range(iterations):
            mu, _, g = cf.geometry(Q, P, V)
            G = mu[:, :k, :][:, :, dq]
            step = np.zeros((N, len(dq)), dtype=complex)
            todo = ~done
            step[todo], singular = _solve_rows(G[todo], g[todo])
            bad = np.flatnonzero(todo)[singular]
            ok[bad] = False
            done[bad] = True
            Q[:, dq] -= step
            small = np.abs(step).max(axis=1, initial=0.0) <= 1e-14 * np.maximum(
                1.0, np.abs(Q[:, dq]).max(axis=1, initial=0.0))
            done |= small & np.isfinite(Q).all(axis=1)
            if done.all():
                break
        ok &= done & np.isfinite(Q).all(axis=1)
    if dv and cf.nonlinear:
        V[:, dv], singular = dependent_velocities(cf, Q, V, dv, P, iterations)
        ok[singular] = False
    elif dv:
        mu, h, _ = cf.geometry(Q, P, V)
        rhs = -(np.einsum("kij,kj->ki", mu[:, :, iv], V[:, iv]) + h)
        sol, singular = _solve_rows(mu[:, :, dv], rhs)
        V[:, dv] = sol
        ok[singular] = False
    out = np.concatenate([Q.real, V.real], axis=1)
    out[~ok] = Y[~ok]
    return out, ok


def dependent_velocities(cf, Q, V, dv, p=None, iterations: int = 30) -> tuple:
    """The dependent velocities of a nonlinear (Chetaev) constraint phi(q, v) = 0, by
    Newton's method from their values in V (the branch they start on): phi = mu v + h
    with mu = d phi/d v, so each step solves mu_dv dv = -phi. On complex states (the
    complex step) the iteration converges in both parts. Returns (V[:, dv] (K, len(dv)),
    singular (K,)): rows where a step was singular or the iteration did not converge."""
    V = np.array(V, dtype=complex)
    singular = np.zeros(V.shape[0], dtype=bool)
    for _ in range(iterations):
        mu, h, _ = cf.geometry(Q, p, V)
        phi = np.einsum("kij,kj->ki", mu, V) + h
        step, bad = _solve_rows(mu[:, :, dv], phi)
        singular |= bad
        V[:, dv] -= step
        if np.abs(step).max(initial=0.0) <= 1e-15 * max(1.0, np.abs(V[:, dv]).max(initial=0.0)):
            return V[:, dv], singular
    return V[:, dv], np.ones(V.shape[0], dtype=bool)


def _solve_rows(A, b):
    """x with A x = b row by row (A (N, r, r), b (N, r)), and a mask of singular rows
    (their x is 0)."""
    x = np.zeros(b.shape, dtype=np.result_type(A, b))
    singular = np.zeros(A.shape[0], dtype=bool)
    with np.errstate(all="ignore"):
        try:
            x = np.linalg.solve(A, b[..., None])[..., 0]
        except np.linalg.LinAlgError:
            for i in range(A.shape[0]):
                try:
                    x[i] = np.linalg.solve(A[i], b[i])
                except np.linalg.LinAlgError:
                    singular[i] = True
    singular |= ~np.isfinite(x).all(axis=1)
    x[singular] = 0
    return x, singular


def input_jacobians(cf, chart, Y, step, model, P=None):
    """B at each state of Y (N, 2n): the complex-step derivative of the chart's field in
    each input's parameter slot, shape (N, d, r)."""
    names = model.parameter_names
    slots = [names.index(u) for u in model.input_names]
    n, N, r = cf.n, Y.shape[0], len(slots)
    d = len(chart.iq) + len(chart.iv)
    if not r:
        return np.zeros((N, d, 0))
    P = np.array([model.parameter_values] * N, dtype=float).T if P is None else np.asarray(P)
    cols = list(chart.iq) + [n + i for i in chart.iv]
    X = np.repeat(Y[:, cols].astype(complex), r, axis=0)
    p = [np.repeat(v.astype(complex), r) for v in P]
    for j, slot in enumerate(slots):
        p[slot] = p[slot].copy()
        p[slot][j::r] += 1j * step
    F = reduced_field(cf, chart, np.repeat(Y[:, :n], r, axis=0), X, p,
                      v0=np.repeat(Y[:, n:], r, axis=0))
    return np.swapaxes(F.imag.reshape(N, r, d), 1, 2) / step


def chart_jacobian(cf, chart, y, step, moving=None):
    """The complex-step Jacobian of the chart's field at the state y (of X - w Xi with
    ``moving = (generator, w)``)."""
    rates = None if moving is None else np.array([moving[1]])
    return chart_jacobians(cf, chart, y[None, :], step, generator=None if moving is None
                           else moving[0], rates=rates)[0]


def chart_jacobians(cf, chart, Y, step, P=None, columns=None, generator=None, rates=None):
    """The complex-step Jacobians of the chart's field at the states Y (N, 2n), in
    batches of up to BATCH_STATES states (d points each).

    Parameters
    ----------
    P : sequence of arrays, optional
        Each parameter's N values (None: the model's).
    columns : sequence of int, optional
        The chart variables to differentiate in (default all d): the result has one
        column per entry, shape (N, d, len(columns)).
    generator : nhham.numerics.relative.Generator, optional
        With ``rates`` (N,): the Jacobians of X - w Xi, w each state's rate (a relative
        equilibrium in co-moving variables).
    """
    # each state's parameters as a row (the layout of the compiled kernels)
    rows = None if P is None else np.array(
        [np.broadcast_to(np.asarray(v, dtype=float), (Y.shape[0],)) for v in P],
        dtype=float).reshape(-1, Y.shape[0]).T
    if Y.shape[0] > BATCH_STATES:
        return np.concatenate([_jacobians(cf, chart, Y[i:i + BATCH_STATES], step,
                                          None if rows is None else rows[i:i + BATCH_STATES],
                                          columns, generator,
                                          None if rates is None else rates[i:i + BATCH_STATES])
                               for i in range(0, Y.shape[0], BATCH_STATES)])
    return _jacobians(cf, chart, Y, step, rows, columns, generator, rates)


def _jacobians(cf, chart, Y, step, rows, columns, generator=None, rates=None, function=None):
    """:func:`chart_jacobians` on one batch; ``rows``: (N, parameters) or None;
    ``function``: ``function(Q, V, P) -> (K, r)`` evaluated at the lifted states in place
    of the field (its derivatives in the chart, shape (N, r, len(columns)))."""
    n, N = cf.n, Y.shape[0]
    cols = list(chart.iq) + [n + i for i in chart.iv]
    d = len(cols)
    columns = list(range(d)) if columns is None else list(columns)
    out = None
    # coordinate columns move the dependent coordinates (Newton); velocity columns do not
    for group, positions in (([j for j in columns if j < len(chart.iq)], True),
                             ([j for j in columns if j >= len(chart.iq)], False)):
        if not group:
            continue
        c = len(group)
        X = (np.repeat(Y[:, cols].astype(complex), c, axis=0)
             + 1j * step * np.tile(np.eye(d)[group], (N, 1)))
        p = None if rows is None else np.repeat(rows, c, axis=0)
        q0, v0 = np.repeat(Y[:, :n], c, axis=0), np.repeat(Y[:, n:], c, axis=0)
        if function is not None:
            Q, V = lifted_states(cf, chart, q0, X, p, positions, v0)
            F = np.asarray(function(Q, V, p)).reshape(N * c, -1)
        else:
            shift = None
            if generator is not None:
                w = np.repeat(np.asarray(rates, dtype=float), c)[:, None]
                shift = functools.partial(_moving, generator, w, p)
            F = reduced_field(cf, chart, q0, X, p, positions, v0=v0, shift=shift)
        if out is None:
            out = np.empty((N, F.shape[1], len(columns)))
        out[:, :, [columns.index(j) for j in group]] = np.swapaxes(
            F.imag.reshape(N, c, F.shape[1]), 1, 2) / step
    return np.empty((N, d if function is None else 0, 0)) if out is None else out


def chart_gradients(cf, chart, Y, step, P=None, function=None, columns=None):
    """The complex-step derivatives in the chart's variables of ``function(Q, V, P) ->
    (K,)`` (complex-analytic, numpy) along M_1 at the states Y (N, 2n): each chart
    variable moved, the dependent coordinates and velocities following it (the lift).
    Shape (N, len(columns)); ``P``, ``columns`` as for :func:`chart_jacobians`."""
    rows = None if P is None else np.array(
        [np.broadcast_to(np.asarray(v, dtype=float), (Y.shape[0],)) for v in P],
        dtype=float).reshape(-1, Y.shape[0]).T
    return _jacobians(cf, chart, Y, step, rows, columns, function=function)[:, 0, :]


def _moving(generator, w, p, Q, V):
    """w Xi at the lifted states (rows of Q, V), each row its own rate w (K, 1)."""
    return w * generator.lifted(Q, V, p)
