"""The constrained accelerations where the saddle-point solve loses them: the null-space solve.

The saddle-point system ``[[W, mu^T], [mu, 0]] [a; lambda] = [F; b]`` is solved by the
range-space method (C: Cholesky of W and of mu W^-1 mu^T) or by LU on the scaled matrix
(numpy). Both are backward stable, yet both obtain an acceleration of a light coordinate
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
(interlacing), and the model problem's x'' = 1/(a + b) comes out to rounding. It costs a
QR factorisation more than the saddle solve, so it is used only where the saddle solve's
bound eps * ratio exceeds ``KKT_RATIO * eps`` (:func:`needs_null_space`, the one
decision: :mod:`nhham.numerics.saddle` (the batched and the one-state solves), the complex
step of :class:`nhham.numerics.chart.ComplexField` and ``ksolve`` in
``nhham/numerics/c/linalg.c``, which reads the same threshold as ``NHHAM_KKT_RATIO``).
The diagonal ratio moves with the units of the coordinates (x in millimetres multiplies
W_xx by 1e-6) and misses a loss where W's diagonal is even (the isokinetic particle); the
saddle solve's own residual does neither: every solve of the accelerations (the numpy
ones, the one-state solve and ``ksolve``) is refined once where the backward error of its
constraint rows (:func:`constraint_error`) passes ``REFINE_RATIO``. A null-space decision
free of units that is neither blind nor costly is still to be found (issue 43's note;
``bench/RESULTS.md``).
RATTLE's velocity-level solve keeps the saddle solve (``solve_saddle(...,
null_space=False)``, ``ksolve_saddle``): its unknown is the O(1) velocity, whose small
step increments the null-space solve kept no better (3-10x worse at a mass ratio of 1e16).

No sympy here.
"""

from __future__ import annotations

import numpy as np

__all__ = ["KKT_RATIO", "REFINE_RATIO", "diagonal_ratio", "diagonal_scaling", "needs_null_space",
           "solve_null_space", "householder_rows", "constraint_error", "kkt_solve_name",
           "describe_kkt_solve", "KKT_SOLVES"]

#: Largest max W_AA / min W_AA solved by the saddle-point (range-space or LU) solve.
#: There its relative error in an acceleration stays below about eps * KKT_RATIO
#: = 2^-52 * 2^12 = 2^-40 ~ 9e-13 (measured on the model problem: 2e-12 at 1e4): under
#: the adaptive methods' default rtol 1e-9 by three orders and at the scale of their
#: default atol 1e-12. Every example scene lies below it (the differential drive,
#: 3.1e3, the largest; the Whipple bicycle 7.8e2, the 8-link snake 24), so their solves
#: and their speed are unchanged; above it the null-space solve keeps the accelerations
#: to a few eps (the model problem at ratios 1e4 .. 1e16).
KKT_RATIO = 4096.0

#: Above this backward error of the saddle solve's constraint rows (:func:`constraint_error`,
#: in units of eps; free of units) every solve of the accelerations takes one step of
#: iterative refinement: the promise of KKT_RATIO (2^-40) where the diagonal ratio does
#: not see the loss. The isokinetic particle (W = I, ratio 1) reaches 1.4e7: its compiled
#: accelerations lost 1.2e-8 of their size, the single-state ones 3e-9 (``python
#: bench/kkt_units.py``); the Whipple bicycle's compiled range-space solve reaches 1.4e3
#: and stays as it is (1.4e-12).
REFINE_RATIO = 4096.0

#: What results report (``kkt_solve``, also in the JSON): the one solve used at every
#: state considered, or both ("mixed").
KKT_SOLVES = ("saddle", "null-space", "mixed")


def diagonal_ratio(W):
    """max_A |W_AA| / min_A |W_AA| of W (..., n, n): inf where a diagonal entry is 0 beside
    a nonzero one, 1 where the diagonal is 0 or n = 0; ``ratio > KKT_RATIO`` exactly
    where :func:`needs_null_space` (finite entries)."""
    d = np.abs(np.diagonal(np.asarray(W, dtype=float), axis1=-2, axis2=-1))
    if d.shape[-1] == 0:
        return np.ones(d.shape[:-1]) if d.ndim > 1 else 1.0
    hi, lo = d.max(axis=-1), d.min(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(lo > 0, hi / np.where(lo > 0, lo, 1.0), np.where(hi > 0, np.inf, 1.0))
    return float(out) if np.ndim(out) == 0 else out


def needs_null_space(W):
    """True where the saddle solve may lose an acceleration: max |W_AA| > KKT_RATIO
    min |W_AA| (see :data:`KKT_RATIO`; a zero diagonal entry beside a nonzero one
    counts, NaN does not). A bool, or a boolean array over the leading dimensions of W
    (..., n, n). The C solve and :class:`~nhham.numerics.saddle.SingleStateSolver` test
    the same inequality."""
    d = np.abs(np.diagonal(np.asarray(W), axis1=-2, axis2=-1))
    if d.shape[-1] == 0:
        return np.zeros(d.shape[:-1], dtype=bool) if d.ndim > 1 else False
    out = d.max(axis=-1) > KKT_RATIO * d.min(axis=-1)
    return bool(out) if np.ndim(out) == 0 else out


def kkt_solve_name(null_space) -> str:
    """``"saddle"``, ``"null-space"`` or ``"mixed"`` (some states each) from the
    decisions at a set of states (booleans: True for the null-space solve)."""
    null_space = np.asarray(null_space, dtype=bool).ravel()
    if not null_space.size or not null_space.any():
        return "saddle"
    return "null-space" if null_space.all() else "mixed"


def describe_kkt_solve(name: str, ratio: float) -> str:
    """One clause: which solve gave the constrained accelerations, and why."""
    how = {"saddle": "the saddle-point solve", "null-space": "the null-space solve",
           "mixed": "the saddle-point solve and, where W's diagonal spans more, the "
                    "null-space solve"}[name]
    return (f"constrained accelerations by {how} (largest max W_AA / min W_AA "
            f"{ratio:.3g}; the null-space solve above {KKT_RATIO:.0f})")


def constraint_error(mu_s, x_s, b_s, r=None):
    """The backward error of a solution of the saddle-point system over its constraint
    rows, in units of eps, from the scaled system: ``mu_s`` (..., m, n) the rows mu D
    (any row scaling: the ratio is free of it), ``x_s`` (..., n) the scaled accelerations
    D^-1 x (D = diag(W)^-1/2, :func:`diagonal_scaling`), ``b_s`` (..., m) the right-hand
    sides, ``r`` the residual b_s - mu_s x_s when it is at hand.

    Row c's residual is measured against its terms |mu_s,c| |x_s| + |b_s,c|, and at least
    against max_j |mu_s,cj| max_j |x_s,j|: a row whose terms are all at rounding, beside
    accelerations of size (a heading of exactly 0, where sin rounds to 1e-16), meets only
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
                 initial=0.0) / np.finfo(float).eps
    return float(out) if np.ndim(out) == 0 else out


def diagonal_scaling(W) -> tuple:
    """(d, D W D) with D = diag(d), d = |W_AA|^(-1/2) (1 where W_AA = 0): W with a unit
    diagonal, the scaling both solves of the accelerations start from."""
    diag = np.abs(np.diagonal(W, axis1=-2, axis2=-1))
    d = np.where(diag > 0, 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0)), 1.0)
    return d, W * d[..., :, None] * d[..., None, :]


def solve_null_space(W, mu, top, bottom):
    """Solve [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] by the null-space method.

    Parameters
    ----------
    W : ndarray, shape (..., n, n)
    mu : ndarray, shape (..., m, n), full row rank
    top : ndarray, shape (..., n)
    bottom : ndarray, shape (..., m)

    Returns
    -------
    x : ndarray, shape (..., n)
    y : ndarray, shape (..., m)

    Raises
    ------
    numpy.linalg.LinAlgError
        If mu is rank deficient or the reduced matrix singular (exactly).
    """
    W, mu = np.asarray(W, dtype=float), np.asarray(mu, dtype=float)
    top, bottom = np.asarray(top, dtype=float), np.asarray(bottom, dtype=float)
    n, m = W.shape[-1], mu.shape[-2]
    d, Ws = diagonal_scaling(W)
    ts = top * d
    if m == 0:
        return np.linalg.solve(Ws, ts[..., None])[..., 0] * d, np.zeros(top.shape[:-1] + (0,))
    Q, R1 = householder_rows(np.swapaxes(mu * d[..., None, :], -1, -2))
    Q1, Q2 = Q[..., :, :m], Q[..., :, m:]
    if np.any(np.abs(np.diagonal(R1, axis1=-2, axis2=-1)) == 0):
        raise np.linalg.LinAlgError("the constraints' one-forms are dependent")
    # the particular solution of (mu D) s = bottom of least length: s = Q1 R1^-T bottom
    s = _mv(Q1, np.linalg.solve(np.swapaxes(R1, -1, -2), bottom[..., None])[..., 0])
    Q2T = np.swapaxes(Q2, -1, -2)
    H = Q2T @ Ws @ Q2
    z = np.linalg.solve(H, _mv(Q2T, ts - _mv(Ws, s))[..., None])[..., 0] if n > m else \
        np.zeros(s.shape[:-1] + (0,))
    xs = s + _mv(Q2, z)
    # R1 y = Q1^T (D top - D W D xs): the multipliers from the force the motion leaves
    y = np.linalg.solve(R1, _mv(np.swapaxes(Q1, -1, -2), ts - _mv(Ws, xs))[..., None])[..., 0]
    return xs * d, y


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
