"""Projection onto M_1 with nonlinear (Chetaev) constraints (``DESIGN.md`` §2).

With phi(q, v) not affine in v the generated geometry kernel reads (q, v) and returns
mu = d phi/d v there and h = phi - mu v (so that mu v + h = phi); the velocities are
brought onto phi = 0 by Newton steps in the kinetic metric instead of one linear solve.
"""

from __future__ import annotations

import numpy as np

from nhham.numerics.nullspace import solve_null_space

__all__ = ["velocities_newton", "padded"]


def padded(q, nonlinear: bool):
    """``q``, or (q, 0) where the geometry kernel reads (q, v) (the holonomic rows and
    their complete lifts do not depend on v).

    Examples
    --------
    >>> padded(np.array([1.0, 2.0]), True).tolist(), padded(np.array([1.0]), False).tolist()
    ([1.0, 2.0, 0.0, 0.0], [1.0])
    """
    return np.concatenate([q, np.zeros_like(q)]) if nonlinear else q


def velocities_newton(geometry, q, v, maxiter: int = 50):
    """The velocities v (n,) or (K, n) at q brought onto phi(q, v) = 0.

    Newton steps in the kinetic metric, dv = -W^{-1} mu^T (mu W^{-1} mu^T)^{-1} phi with
    mu = d phi/d v at the current v, until phi is 0 or stops decreasing (round-off).

    Parameters
    ----------
    geometry : callable
        ``NumericModel.geometry``: (q, v) -> W, mu, h, g with mu v + h = phi.
    q, v : numpy.ndarray

    Examples
    --------
    The unit circle x'^2 + y'^2 = 1 (phi/2, mu = (x', y'), h = -(x'^2 + y'^2 + 1)/2) from
    v = (2, 0): Newton on the speed, 2 -> 1.25 -> 1.025 -> ... -> 1.

    >>> def geometry(y):
    ...     v = y[2:]
    ...     return np.eye(2), v[None], np.array([-(v @ v + 1) / 2]), np.zeros(0)
    >>> velocities_newton(geometry, np.zeros(2), np.array([2.0, 0.0])).tolist()
    [1.0, 0.0]
    """
    best = np.inf
    for _ in range(maxiter):
        y = np.concatenate([np.broadcast_to(q, v.shape), v], axis=-1)
        W, mu, h, _ = geometry(y)
        r = (mu @ v[..., None])[..., 0] + h
        err = float(np.max(np.abs(r), initial=0.0))
        if err == 0.0 or err >= best:
            break
        best = err
        dv, _ = solve_null_space(W, mu, np.zeros_like(v), -r)
        v = v + dv
    return v
