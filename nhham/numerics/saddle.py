"""The saddle-point solve, and the one-state solve of the constrained field.

``[[W, mu^T], [mu, 0]] [x; y] = [top; bottom]``: :func:`solve_saddle` solves it as it
stands, by LU after a symmetric scaling (unit diagonal of W, unit rows of mu) and one
step of refinement where its constraint rows are not met to rounding; RATTLE's
velocity-level solve is its use (its unknown is the O(1) velocity). Every constrained
acceleration and every projection onto the constraints is solved by the null-space
method instead (:mod:`nhham.numerics.nullspace`, free of units, to rounding at any mass
ratio): :class:`SingleStateSolver` for one state; the compiled path in C (``ksolve`` in
``nhham/numerics/c/linalg.c``). No sympy here.
"""

from __future__ import annotations

import math

import numpy as np

from nhham.numerics.nullspace import diagonal_scaling, solve_null_space_one
from nhham.numerics.status import Status

EPS = float(np.finfo(float).eps)

#: Above this backward error of the saddle solve's constraint rows (:func:`constraint_error`,
#: in units of eps; free of units) :func:`solve_saddle` takes one step of iterative
#: refinement: where the multipliers are 1e8 times the unknowns the LU solve meets its
#: constraint rows only to eps |lambda|.
REFINE_RATIO = 4096.0

__all__ = ["solve_saddle", "SingleStateSolver", "constraint_error", "cond_each", "condition",
           "REFINE_RATIO"]


def solve_saddle(W, mu, top, bottom):
    """Solve [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] after symmetric scaling.

    Parameters
    ----------
    W : ndarray, shape (..., n, n)
    mu : ndarray, shape (..., m, n)
    top : ndarray, shape (..., n)
    bottom : ndarray, shape (..., m)

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
    1e8 times the unknowns), meet every row to rounding. Accuracy is
    backward, not relative per component: at mass ratios of 1e16 an
    unknown that is the difference of nearly equal terms
    (x'' = (1 - lambda)/a with lambda = 1 - 1e-16) keeps only its absolute
    accuracy, which is why the accelerations are solved by
    :func:`~nhham.numerics.nullspace.solve_null_space`. Raises
    numpy.linalg.LinAlgError if exactly singular.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = solve_saddle(np.eye(2), np.array([[1.0, 1.0]]), np.zeros(2), np.ones(1))
    >>> x.tolist(), y.tolist()
    ([0.5, 0.5], [-0.5])
    """
    return _solve_scaled(np.asarray(W, dtype=float), np.asarray(mu, dtype=float),
                         np.asarray(top, dtype=float), np.asarray(bottom, dtype=float))


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
    (:func:`constraint_error` of the scaled system K z = rhs).

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
    """The constrained field at one state from the flat kernel output (W, F, mu, drift,
    h, g[, applied power]): the null-space solve
    (:func:`~nhham.numerics.nullspace.solve_null_space_one`) with the Baumgarte terms.
    """

    def __init__(self, layout):
        n, m, k = layout["n"], layout["m"], layout["k"]
        self.n, self.m, self.k = n, m, k
        base = n * n + n
        self.F = slice(n * n, n * n + n)
        self.mu = slice(base, base + m * n)
        self.drift = slice(base + m * n, base + m * n + m)
        self.h = slice(base + m * n + m, base + m * n + 2 * m)
        self.g = slice(base + m * n + 2 * m, base + m * n + 2 * m + k)
        # with forces the kernel ends with the applied power Q . v
        self.forced = bool(layout.get("forced", False))

    def __call__(self, flat, y, a2, b2):
        """(dy (2n,), lambda (m,), the constraints' power, status)."""
        n, m = self.n, self.m
        out = np.array(flat, dtype=float)
        v = y[n:]
        mu = out[self.mu].reshape(m, n)
        muv = mu @ v
        bottom = -out[self.drift]
        if a2:
            bottom -= a2 * (muv + out[self.h])
        if b2 and self.k:
            bottom[:self.k] -= b2 * out[self.g]
        try:
            with np.errstate(all="ignore"):
                a, lam = solve_null_space_one(out[:n * n].reshape(n, n), mu, out[self.F], bottom)
        except np.linalg.LinAlgError:
            return np.full(2 * n, np.nan), np.full(m, np.nan), math.nan, Status.SINGULAR
        power = -float(lam @ muv) + (float(out[-1]) if self.forced else 0.0)
        dy = np.concatenate((v, a))
        ok = math.isfinite(power) and bool(np.isfinite(dy).all())
        return dy, lam, power, (Status.SUCCESS if ok else Status.NONFINITE)


def constraint_error(mu_s, x_s, b_s, r=None):
    """The backward error of a solution of the saddle-point system over its constraint
    rows, in units of eps, from the scaled system: ``mu_s`` (..., m, n) the rows mu D
    (any row scaling: the ratio is free of it), ``x_s`` (..., n) the scaled unknowns
    D^-1 x (D = diag(W)^-1/2), ``b_s`` (..., m) the right-hand sides, ``r`` the residual
    b_s - mu_s x_s when it is at hand.

    Row c's residual is measured against its terms |mu_s,c| |x_s| + |b_s,c|, and at least
    against max_j |mu_s,cj| max_j |x_s,j|: a row whose terms are all at rounding, beside
    unknowns of size (a heading of exactly 0, where sin rounds to 1e-16), meets only
    rounding. Free of units: a change of units scales a row's residual and its terms
    alike, and not D^-1 x or mu D.

    Examples
    --------
    >>> import numpy as np
    >>> # x' + y' = 1, W = diag(1, 1e16), unit force on x: x'' = 1e-16 lost to 0 (y'' = -1e-16)
    >>> d = np.array([1.0, 1e-8])
    >>> x = np.array([0.0, -1e-16])
    >>> round(constraint_error(np.array([[1.0, 1.0]]) * d, x / d, np.zeros(1)))
    45035996
    """
    if r is None:
        r = b_s - np.einsum("...ij,...j->...i", mu_s, x_s)
    amu, ax = np.abs(mu_s), np.abs(x_s)
    terms = np.abs(b_s) + np.einsum("...ij,...j->...i", amu, ax)
    floor = amu.max(axis=-1, initial=0.0) * ax.max(axis=-1, initial=0.0)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        each = np.where(r == 0, 0.0, np.abs(r) / np.maximum(terms, floor))
    out = np.max(np.where(np.isfinite(each), each, np.inf), axis=-1,
                 initial=0.0) / EPS
    return float(out) if np.ndim(out) == 0 else out


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

