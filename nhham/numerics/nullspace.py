"""The constrained accelerations: the null-space solve of the saddle-point system.

The saddle-point system ``[[W, mu^T], [mu, 0]] [a; lambda] = [F; b]`` solved as it stands,
by the range-space method (Cholesky of W and of mu W^-1 mu^T) or by LU on the scaled
matrix, is backward stable, yet obtains an acceleration of a light coordinate
tied by a constraint to a heavy one as a difference of nearly equal terms. With
L = (a x'^2 + b y'^2)/2 + x and x' + y' = 1 (the model problem of this module):

    x'' = (1 - lambda)/a,   lambda = b/(a + b),   so   x'' = 1/(a + b);

lambda carries an absolute error of about eps, so x'' carries eps/a against its value
1/(a + b): a relative error of eps (1 + b/a). In general the saddle solve's relative error
in an acceleration is bounded by about eps * max_A W_AA / min_A W_AA (the ratio of the
largest to the smallest diagonal entry of W, :func:`diagonal_ratio`), and reached when
the force falls on the light coordinates.

The null-space solve never forms lambda first. After the symmetric scaling D = diag(W)^-1/2
(unit diagonal of D W D, as the saddle solve scales), the QR factorisation with row
pivoting (mu D)^T = [Q1 Q2] [R; 0] (:func:`householder_rows`) gives an orthonormal basis
Q2 of the kernel of mu D, and

    a = D (Q1 R^-T b + Q2 z),   (Q2^T D W D Q2) z = Q2^T D (F - W D Q1 R^-T b),
    R lambda = Q1^T D (F - W a):

the reduced matrix is D W D restricted to the kernel, no worse conditioned than D W D
(interlacing), and the model problem's x'' = 1/(a + b) comes out to rounding.

It is the solve of every constrained acceleration (the batched numpy solve
:func:`solve_null_space`, the one-state solve of :mod:`nhham.numerics.saddle`, the
complex step of :class:`nhham.numerics.chart.ComplexField` and ``ksolve`` in
``nhham/numerics/c/linalg.c``): a choice between it and the saddle solve would have to
be made from W and mu at one state, and none made there is free of units. The diagonal
ratio moves with them (x in millimetres multiplies W_xx by 1e-6); in the scaled system
(D W D, mu D), which a change of units leaves as it is, a light coordinate tied to a
heavy one is the same as a coordinate almost walled by the geometry (a row [1, eps] of
mu D), so a unit-free test flags both, and on the Whipple bicycle 99% of the states.
Solving by null space everywhere is free of units by construction and costs a QR
factorisation (bench/RESULTS.md, "One solve in any units": the bicycle's compiled
right-hand side 1.95 -> 2.4 us a state, the 8-link snake's 1.07 -> 1.7 us, whole commands
unchanged within their spread; the bicycle's accelerations 1.3e-12 -> 1.3e-14 of their
size in C, the isokinetic particle's 4.2e-13 -> 6.6e-16). :func:`diagonal_ratio` stays a
reported diagnostic (the spread of the masses in the scene's units), deciding nothing.
RATTLE's velocity-level solve keeps the saddle solve (``solve_saddle``,
``ksolve_saddle``): its unknown is the O(1) velocity, whose small step increments the
null-space solve kept no better (3-10x worse at a mass ratio of 1e16).

No sympy here.
"""

from __future__ import annotations

import numpy as np

__all__ = ["diagonal_ratio", "diagonal_scaling", "solve_null_space", "solve_null_space_one",
           "householder_rows", "sorted_rows_qr", "KKT_SOLVE", "RANK_TOLERANCE"]

#: A saddle-point matrix singular to rounding: a diagonal entry of R (the rows of mu D of
#: unit length) at or below RANK_TOLERANCE n, or the reduced matrix's smallest |eigenvalue|
#: at or below RANK_TOLERANCE n times its largest (64 eps: a few roundings of each of n
#: terms). The LU of the saddle matrix it replaces tested for an exact zero pivot.
RANK_TOLERANCE = 64 * float(np.finfo(float).eps)

#: What results report as ``kkt_solve`` (also in the JSON): the solve of the constrained
#: accelerations, the same at every state.
KKT_SOLVE = "null-space"


def diagonal_ratio(W):
    """max_A |W_AA| / min_A |W_AA| of W (..., n, n): inf where a diagonal entry is 0 beside
    a nonzero one, 1 where the diagonal is 0 or n = 0. A diagnostic (the spread of the
    masses in the scene's units): no solve depends on it."""
    d = np.abs(np.diagonal(np.asarray(W, dtype=float), axis1=-2, axis2=-1))
    if d.shape[-1] == 0:
        return np.ones(d.shape[:-1]) if d.ndim > 1 else 1.0
    hi, lo = d.max(axis=-1), d.min(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(lo > 0, hi / np.where(lo > 0, lo, 1.0), np.where(hi > 0, np.inf, 1.0))
    return float(out) if np.ndim(out) == 0 else out


def diagonal_scaling(W) -> tuple:
    """(d, D W D) with D = diag(d), d = |W_AA|^(-1/2) (1 where W_AA = 0): W with a unit
    diagonal, the scaling both solves of the accelerations start from."""
    diag = np.abs(np.diagonal(W, axis1=-2, axis2=-1))
    d = np.where(diag > 0, 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0)), 1.0)
    return d, W * d[..., :, None] * d[..., None, :]


def solve_null_space(W, mu, top, bottom, *, qr=None):
    """Solve [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] by the null-space method.

    Parameters
    ----------
    W : ndarray, shape (..., n, n), symmetric
    mu : ndarray, shape (..., m, n), full row rank
    top : ndarray, shape (..., n)
    bottom : ndarray, shape (..., m)
    qr : callable, optional
        ``qr(A) -> (Q (..., n, n), R (..., m, m))`` of A = (mu D)^T with unit columns:
        :func:`householder_rows` by default (a row pivot per column);
        :func:`solve_null_space_one` passes LAPACK's QR after row sorting.

    Returns
    -------
    x : ndarray, shape (..., n)
    y : ndarray, shape (..., m)

    Raises
    ------
    numpy.linalg.LinAlgError
        If mu is rank deficient or the reduced matrix singular, to rounding
        (:data:`RANK_TOLERANCE`), at any state of the batch.

    Notes
    -----
    The rows of mu D are scaled to unit length first (the multipliers scaled back), so
    that |R_cc| <= 1 measures how far row c is from the span of the others; the reduced
    matrix H = Q2^T D W D Q2 (symmetric) is solved by LU, and its smallest |eigenvalue|
    against the largest says how near it is to singular. Either
    below ``RANK_TOLERANCE`` is a saddle-point matrix singular to rounding (the
    constraints dependent, or C = 0: a free multiplier), which an exact test would miss
    where the kernel's basis is irrational (1/sqrt(2)).
    """
    W, mu = np.asarray(W, dtype=float), np.asarray(mu, dtype=float)
    top, bottom = np.asarray(top, dtype=float), np.asarray(bottom, dtype=float)
    n, m = W.shape[-1], mu.shape[-2]
    d, Ws = diagonal_scaling(W)
    ts = top * d
    if m == 0:
        return np.linalg.solve(Ws, ts[..., None])[..., 0] * d, np.zeros(top.shape[:-1] + (0,))
    mus, e = _unit_rows(mu * d[..., None, :])
    Q, R1 = (qr or householder_rows)(np.swapaxes(mus, -1, -2))
    Q1, Q2 = Q[..., :, :m], Q[..., :, m:]
    if np.any(np.abs(np.diagonal(R1, axis1=-2, axis2=-1)) <= RANK_TOLERANCE * n):
        raise np.linalg.LinAlgError("the constraints' one-forms are dependent")
    # the particular solution of (mu D) s = bottom of least length: s = Q1 R1^-T bottom
    s = _mv(Q1, np.linalg.solve(np.swapaxes(R1, -1, -2), (bottom * e)[..., None])[..., 0])
    Q2T = np.swapaxes(Q2, -1, -2)
    xs = s + _mv(Q2, _symmetric_solve(Q2T @ Ws @ Q2, _mv(Q2T, ts - _mv(Ws, s)), n)) \
        if n > m else s
    # R1 y = Q1^T (D top - D W D xs): the multipliers from the force the motion leaves
    y = np.linalg.solve(R1, _mv(np.swapaxes(Q1, -1, -2), ts - _mv(Ws, xs))[..., None])[..., 0]
    return xs * d, y * e


def _unit_rows(A):
    """(A with rows of unit length, the factors): rows of zeros stay (factor 1)."""
    norms = np.sqrt(np.sum(A * A, axis=-1))
    e = 1.0 / np.where(norms > 0, norms, 1.0)
    return A * e[..., None], e


def _symmetric_solve(H, r, n):
    """H z = r for symmetric H (..., k, k) by LU; LinAlgError where min |eigenvalue| <=
    RANK_TOLERANCE n max |eigenvalue| (the eigenvalues only tell: the eigenvector solve
    is several eps less accurate than LU). NaN states give NaN."""
    finite = np.all(np.isfinite(H), axis=(-2, -1))
    if not np.all(finite):
        H = np.where(finite[..., None, None], H, np.eye(H.shape[-1]))
    aw = np.abs(np.linalg.eigvalsh(H))
    if np.any(finite & (aw.min(axis=-1) <= RANK_TOLERANCE * n * aw.max(axis=-1))):
        raise np.linalg.LinAlgError("the saddle-point matrix is singular (C singular)")
    z = np.linalg.solve(H, r[..., None])[..., 0]
    return np.where(finite[..., None], z, np.nan)


def solve_null_space_one(W, mu, top, bottom):
    """:func:`solve_null_space` for one state (W (n, n), mu (m, n), top (n,), bottom (m,)),
    its QR by LAPACK after sorting the rows by size (:func:`sorted_rows_qr`) rather than
    a numpy call per column: the solve of :class:`~nhham.numerics.saddle.SingleStateSolver`.

    Examples
    --------
    >>> import numpy as np
    >>> # x' + y' = 1, W = diag(1, 1e16), a unit force on x: x'' = 1/(1 + 1e16)
    >>> x, y = solve_null_space_one(np.diag([1.0, 1e16]), np.array([[1.0, 1.0]]),
    ...                             np.array([1.0, 0.0]), np.zeros(1))
    >>> float(x[0] * (1 + 1e16))
    1.0
    """
    return solve_null_space(W, mu, top, bottom, qr=sorted_rows_qr)


def sorted_rows_qr(A):
    """(Q (n, n), R (m, m)) with A = Q [R; 0] for one A (n, m), n >= m: LAPACK's Householder
    QR of A with its rows sorted by their largest entry (Bjoerck's row sorting, which
    keeps the small components of a kernel direction near a coordinate axis as
    :func:`householder_rows`' pivoting does)."""
    from scipy.linalg.lapack import dgeqrf, dorgqr   # here: 0.2 s of import few runs need

    n, m = A.shape
    order = np.argsort(-np.abs(A).max(axis=1), kind="stable")
    qr, tau, _, _ = dgeqrf(A[order])
    Qs, _, _ = dorgqr(np.hstack([qr, np.zeros((n, n - m))]), np.concatenate([tau, np.zeros(n - m)]))
    Q = np.empty((n, n))
    Q[order] = Qs
    return Q, np.triu(qr[:m])


def _mv(A, x):
    return np.einsum("...ij,...j->...i", A, x)


def householder_rows(A):
    """A = Q [R; 0] by Householder reflections with row pivoting: (Q (..., n, n), R
    (..., m, m)) for A (..., n, m), n >= m.

    Each step reflects onto the row of the largest remaining entry of its column (the
    row sorting of Powell and Reid for graded least squares). Without it a kernel
    direction close to a coordinate axis, the light coordinate's, comes out as
    1 - (1 - t) and keeps only the absolute accuracy eps of its small components t
    (a relative error of eps / t: 1e-10 for a mass ratio of 1e12); with it they keep
    their relative accuracy. The same steps as ``nullspace_solve`` in
    ``nhham/numerics/c/linalg.c``.
    """
    A = np.array(A, dtype=float)
    n, m = A.shape[-2], A.shape[-1]
    lead = A.shape[:-2]
    A = A.reshape((-1, n, m))
    K = A.shape[0]
    rows = np.arange(K)
    V = np.zeros((K, m, n))
    beta = np.zeros((K, m))
    piv = np.zeros((K, m), dtype=np.intp)
    for c in range(m):
        p = c + np.argmax(np.abs(A[:, c:, c]), axis=1)
        piv[:, c] = p
        A[rows, c], A[rows, p] = A[rows, p], A[rows, c].copy()
        x = A[:, c:, c]
        norm = np.sqrt(np.sum(x * x, axis=1))
        alpha = np.where(x[:, 0] >= 0, -norm, norm)
        v = x.copy()
        v[:, 0] -= alpha                  # no cancellation: alpha has the other sign
        vv = np.sum(v * v, axis=1)
        b = np.where(vv > 0, 2.0 / np.where(vv > 0, vv, 1.0), 0.0)
        V[:, c, c:], beta[:, c] = v, b
        rest = A[:, c:, c + 1:]
        A[:, c:, c + 1:] = rest - (b[:, None] * np.einsum("ki,kij->kj", v, rest))[:, None, :] \
            * v[:, :, None]
        A[:, c, c] = alpha
        A[:, c + 1:, c] = 0.0
    Q = np.broadcast_to(np.eye(n), (K, n, n)).copy()
    for c in range(m - 1, -1, -1):       # Q = P_0 H_0 P_1 H_1 ... P_{m-1} H_{m-1}
        v = V[:, c]
        Q -= (beta[:, c, None] * np.einsum("ki,kij->kj", v, Q))[:, None, :] * v[:, :, None]
        p = piv[:, c]
        Q[rows, c], Q[rows, p] = Q[rows, p], Q[rows, c].copy()
    return Q.reshape(lead + (n, n)), A[:, :m, :].reshape(lead + (m, m))
