"""The saddle-point solve of the constrained field, in numpy and for one state.

``[[W, mu^T], [mu, 0]] [x; y] = [top; bottom]`` after a symmetric scaling (unit diagonal
of W, unit rows of mu): :func:`solve_saddle` for any batch shape,
:class:`SingleStateSolver` for one state with as few numpy calls as possible. The compiled
path solves the same system in C (``ksolve`` in ``nhham/numerics/c/linalg.c``). Where W's
diagonal spans more than :data:`~nhham.numerics.nullspace.KKT_RATIO` (extreme mass
ratios) every one of them solves by the null-space method instead
(:mod:`nhham.numerics.nullspace`: one decision, :func:`needs_null_space`). No sympy here.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg.lapack import dgesv

from nhham.numerics.nullspace import (KKT_RATIO, REFINE_RATIO, constraint_error,
                                      diagonal_scaling, needs_null_space, solve_null_space)
from nhham.numerics.status import Status

EPS = float(np.finfo(float).eps)

__all__ = ["solve_saddle", "SingleStateSolver", "gauss", "cond_each", "condition"]


def solve_saddle(W, mu, top, bottom, *, null_space: bool | None = None):
    """Solve [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] after symmetric scaling.

    Parameters
    ----------
    W : ndarray, shape (..., n, n)
    mu : ndarray, shape (..., m, n)
    top : ndarray, shape (..., n)
    bottom : ndarray, shape (..., m)
    null_space : bool, optional
        None (default): the null-space solve where
        :func:`~nhham.numerics.nullspace.needs_null_space` says so; False: the saddle
        solve everywhere (the velocity-level solve of RATTLE).

    Returns
    -------
    x : ndarray, shape (..., n)
    y : ndarray, shape (..., m)

    Notes
    -----
    With S = diag(d, e), d_A = |W_AA|^{-1/2} and e_i = 1/|mu_i diag(d)|, the
    scaled matrix S K S has unit diagonal in its W block and unit rows in its
    mu block; LU with partial pivoting on it, and one step of iterative
    refinement where the residual is above rounding (the multipliers can be
    1e8 times the accelerations), meet every row to rounding. Accuracy is
    backward, not relative per component: at mass ratios of 1e16 an
    acceleration that is the difference of nearly equal terms
    (x'' = (1 - lambda)/a with lambda = 1 - 1e-16) keeps only its absolute
    accuracy. Such states (:func:`~nhham.numerics.nullspace.needs_null_space`) are
    solved by :func:`~nhham.numerics.nullspace.solve_null_space` instead. Raises
    numpy.linalg.LinAlgError if exactly singular.
    """
    ill = needs_null_space(W) if null_space is None else False
    if np.any(ill):
        if np.ndim(ill) == 0:
            return solve_null_space(W, mu, top, bottom)
        top = np.broadcast_to(top, W.shape[:-1])
        bottom = np.broadcast_to(bottom, mu.shape[:-1])
        x, y = np.empty(top.shape), np.empty(bottom.shape)
        x[ill], y[ill] = solve_null_space(W[ill], mu[ill], top[ill], bottom[ill])
        if np.any(~ill):
            x[~ill], y[~ill] = _solve_scaled(W[~ill], mu[~ill], top[~ill], bottom[~ill])
        return x, y
    return _solve_scaled(W, mu, top, bottom)


def _solve_scaled(W, mu, top, bottom):
    """:func:`solve_saddle` by scaled LU (with one refinement step where needed)."""
    n, m = W.shape[-1], mu.shape[-2]
    d, Ws = diagonal_scaling(W)
    rhs_top = top * d
    if m == 0:
        x = np.linalg.solve(Ws, rhs_top[..., None])[..., 0]
        return x * d, np.zeros(top.shape[:-1] + (0,))
    mus = mu * d[..., None, :]
    norms = np.sqrt(np.sum(mus * mus, axis=-1))
    e = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
    mus = mus * e[..., :, None]
    K = np.zeros(W.shape[:-2] + (n + m, n + m))
    K[..., :n, :n] = Ws
    K[..., :n, n:] = np.swapaxes(mus, -1, -2)
    K[..., n:, :n] = mus
    rhs = np.concatenate([rhs_top, bottom * e], axis=-1)
    z = _refined(K, rhs, np.linalg.solve(K, rhs[..., None])[..., 0], n)
    return z[..., :n] * d, z[..., n:] * e


def _refined(K, rhs, z, n):
    """``z`` after one step of iterative refinement where the backward error of its
    constraint rows (from ``n``) is above REFINE_RATIO eps
    (:func:`~nhham.numerics.nullspace.constraint_error` of the scaled system K z = rhs).

    When the multipliers are much larger than the accelerations (mass ratios of 1e8),
    the accelerations come out of the LU solve with an absolute error of eps |lambda|,
    a relative error up to 1e-8, and the constraint rows are met only to that; one
    refinement step, on those states only, brings the residual back to rounding.
    """
    r = rhs - np.einsum("...ij,...j->...i", K, z)
    bad = np.asarray(constraint_error(K[..., n:, :n], z[..., :n], rhs[..., n:], r[..., n:])
                     > REFINE_RATIO)
    if np.any(bad):
        z = z.copy()
        z[bad] += np.linalg.solve(K[bad], r[bad][..., None])[..., 0]
    return z


class SingleStateSolver:
    """The saddle solve for one state with as few numpy calls as possible.

    Index maps place the flat kernel output (W, F, mu, drift, h, g) into the
    (n+m) x (n+m) saddle matrix once; the scaling is that of
    :func:`solve_saddle`.
    """

    def __init__(self, layout):
        n, m, k = layout["n"], layout["m"], layout["k"]
        N = n + m
        self.n, self.m, self.k, self.N = n, m, k, N
        src, dst = [], []
        for i in range(n):
            for j in range(n):
                src.append(i * n + j)
                dst.append(i * N + j)
        base = n * n + n
        for c in range(m):
            for j in range(n):
                src += [base + c * n + j, base + c * n + j]
                dst += [(n + c) * N + j, j * N + n + c]
        self.src, self.dst = np.array(src, dtype=np.intp), np.array(dst, dtype=np.intp)
        self.diag = np.arange(n) * (n + 1)
        self.diag_list = self.diag.tolist()
        self.F = slice(n * n, n * n + n)
        self.mu = slice(base, base + m * n)
        self.drift = slice(base + m * n, base + m * n + m)
        self.h = slice(base + m * n + m, base + m * n + 2 * m)
        self.g = slice(base + m * n + 2 * m, base + m * n + 2 * m + k)
        # with forces the kernel ends with the applied power Q . v
        self.forced = bool(layout.get("forced", False))

    def __call__(self, flat, y, a2, b2):
        w = [abs(flat[i]) for i in self.diag_list]
        if w and max(w) > KKT_RATIO * min(w):  # needs_null_space, without numpy
            return self._null_space(flat, y, a2, b2)
        if self.N <= 10:
            return self._python(flat, y, a2, b2)
        return self._numpy(flat, y, a2, b2)

    def _bottom(self, out, v, a2, b2):
        """(mu, mu v, the constraint rows' right-hand side) from the kernel's output."""
        mu = out[self.mu].reshape(self.m, self.n)
        muv = mu @ v
        bottom = -out[self.drift]
        if a2:
            bottom -= a2 * (muv + out[self.h])
        if b2 and self.k:
            bottom[:self.k] -= b2 * out[self.g]
        return mu, muv, bottom

    def _null_space(self, flat, y, a2, b2):
        """The solve of :func:`~nhham.numerics.nullspace.solve_null_space` (W's diagonal
        spans more than KKT_RATIO)."""
        n, m = self.n, self.m
        out = np.array(flat, dtype=float)
        v = y[n:]
        mu, muv, bottom = self._bottom(out, v, a2, b2)
        try:
            with np.errstate(all="ignore"):
                a, lam = solve_null_space(out[:n * n].reshape(n, n), mu, out[self.F], bottom)
        except np.linalg.LinAlgError:
            return np.full(2 * n, np.nan), np.full(m, np.nan), math.nan, Status.SINGULAR
        power = -float(lam @ muv) + (float(out[-1]) if self.forced else 0.0)
        dy = np.concatenate((v, a))
        ok = math.isfinite(power) and bool(np.isfinite(dy).all())
        return dy, lam, power, (Status.SUCCESS if ok else Status.NONFINITE)

    def _python(self, out, y, a2, b2):
        """Pure-Python scaled elimination: for small systems each numpy call on a
        tiny array costs more than the whole solve."""
        n, m, k, N = self.n, self.m, self.k, self.N
        v = y[n:].tolist()
        d = [0.0] * N
        for i in range(n):
            w = abs(out[i * n + i])
            d[i] = 1.0 / math.sqrt(w) if w > 0 else 1.0
        base = n * n + n
        K = [[0.0] * (N + 1) for _ in range(N)]  # last column: right-hand side
        for i in range(n):
            row, di = K[i], d[i]
            for j in range(n):
                row[j] = out[i * n + j] * di * d[j]
            row[N] = out[n * n + i] * di
        muv = [0.0] * m
        for c in range(m):
            r = out[base + c * n: base + (c + 1) * n]
            s = math.sqrt(sum((r[j] * d[j]) ** 2 for j in range(n)))
            e = 1.0 / s if s > 0 else 1.0
            d[n + c] = e
            muv[c] = sum(r[j] * v[j] for j in range(n))
            rhs = -out[base + m * n + c]
            if a2:
                rhs -= a2 * (muv[c] + out[base + m * n + m + c])
            if b2 and c < k:
                rhs -= b2 * out[base + m * n + 2 * m + c]
            row = K[n + c]
            for j in range(n):
                t = r[j] * d[j] * e
                row[j] = t
                K[j][n + c] = t
            row[N] = rhs * e
        K0 = [row[:] for row in K]   # gauss works in place; the residual needs K
        z = gauss(K, N)
        if z is None:
            return np.full(2 * n, np.nan), np.full(m, np.nan), math.nan, Status.SINGULAR
        z = _refined_python(K0, z, n, N)
        a = [z[i] * d[i] for i in range(n)]
        lam = [z[n + c] * d[n + c] for c in range(m)]
        power = -sum(lam[c] * muv[c] for c in range(m))
        if self.forced:
            power += out[-1]
        dy = np.array(v + a)
        ok = math.isfinite(power) and all(math.isfinite(x) for x in a)
        return dy, np.array(lam), power, (Status.SUCCESS if ok else Status.NONFINITE)

    def _numpy(self, flat, y, a2, b2):
        n, m, N = self.n, self.m, self.N
        out = np.array(flat, dtype=float)
        w = np.abs(out[self.diag])
        w[w == 0] = 1.0
        d = np.ones(N)
        d[:n] = 1.0 / np.sqrt(w)
        v = y[n:]
        mu, muv, bottom = self._bottom(out, v, a2, b2)
        rhs = np.empty(N)
        rhs[:n] = out[self.F]
        rhs[n:] = bottom
        if m:
            norms = np.sqrt(((mu * d[:n]) ** 2).sum(axis=1))
            norms[norms == 0] = 1.0
            d[n:] = 1.0 / norms
        K = np.zeros(N * N)
        K[self.dst] = out[self.src]
        K = K.reshape(N, N) * np.multiply.outer(d, d)
        rhs *= d
        _, _, z, info = dgesv(K, rhs)
        if info != 0:
            return np.full(2 * n, np.nan), np.full(m, np.nan), np.nan, Status.SINGULAR
        z = _refined(K, rhs, z, n) * d
        dy = np.concatenate((v, z[:n]))
        lam = z[n:]
        power = -float(lam @ muv) + (float(out[-1]) if self.forced else 0.0)
        return dy, lam, power, (Status.SUCCESS if np.isfinite(dy).all() else Status.NONFINITE)


def _refined_python(K, z, n, N) -> list:
    """:func:`_refined` without numpy, for the scaled augmented N x (N+1) system K
    (constraint rows from n) and its solution z."""
    def residual(row):
        return row[N] - sum(row[j] * z[j] for j in range(N))

    # the constraint rows on every call (their terms are their first n); the others only
    # where a refinement step needs them
    r = [residual(row) for row in K[n:]]
    top = max((abs(v) for v in z[:n]), default=0.0)
    worst = 0.0
    for row, rc in zip(K[n:], r):
        if rc:
            terms = abs(row[N]) + sum(abs(row[j] * z[j]) for j in range(n))
            den = max(terms, max(abs(v) for v in row[:n]) * top)
            worst = max(worst, abs(rc) / den if den else math.inf)
    if worst <= REFINE_RATIO * EPS:
        return z
    r = [residual(row) for row in K[:n]] + r
    dz = gauss([row[:N] + [ri] for row, ri in zip(K, r)], N)
    return z if dz is None else [zi + di for zi, di in zip(z, dz)]


def gauss(K, N):
    """Solve the augmented N x (N+1) list-of-lists system in place; None if singular."""
    for c in range(N):
        piv = max(range(c, N), key=lambda r: abs(K[r][c]))
        if K[piv][c] == 0.0:
            return None
        if piv != c:
            K[c], K[piv] = K[piv], K[c]
        rc = K[c]
        inv = 1.0 / rc[c]
        for r in range(c + 1, N):
            row = K[r]
            f = row[c] * inv
            if f != 0.0:
                for j in range(c + 1, N + 1):
                    row[j] -= f * rc[j]
    z = [0.0] * N
    for r in range(N - 1, -1, -1):
        row = K[r]
        s = row[N]
        for j in range(r + 1, N):
            s -= row[j] * z[j]
        z[r] = s / row[r]
    return z


def cond_each(W, mu):
    out = np.empty(W.shape[0])
    for i in range(W.shape[0]):  # only after a batched solve failed: isolate bad states
        try:
            C = -mu[i] @ np.linalg.solve(W[i], mu[i].T)
            out[i] = condition(C)
        except np.linalg.LinAlgError:
            out[i] = np.inf
    return out


def condition(A):
    """The 2-norm condition number of a matrix, or of each of a batch (..., k, k): inf
    where an entry is not finite (numpy's SVD of one does not converge: a state where
    the Lagrangian leaves its domain) or the matrix is singular.

    Examples
    --------
    >>> condition(np.diag([1.0, 4.0])), condition(np.array([[np.inf]]))
    (4.0, inf)
    >>> condition(np.array([np.eye(2), [[1.0, 0.0], [0.0, np.nan]]])).tolist()
    [1.0, inf]
    """
    A = np.asarray(A, dtype=float)
    finite = np.all(np.isfinite(A), axis=(-2, -1))
    with np.errstate(all="ignore"):
        c = np.linalg.cond(np.where(finite[..., None, None], A, 0.0))
    c = np.where(finite & np.isfinite(c), c, np.inf)
    return float(c) if np.ndim(c) == 0 else c

