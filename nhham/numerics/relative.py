"""Relative equilibria: a steady motion along a symmetry group, linearised in co-moving
variables (``DESIGN.md`` §2, "Relative equilibria").

A vector field xi on Q whose tangent lift Xi = xi^A d/dq^A + (d xi^A/d q^B) v^B d/dv^A
leaves L, the constraints and the forces invariant commutes with the constrained field X
on M_1. A state y0 with X(y0) = w Xi(y0) (the motion q(t) = exp(t w xi) q0) is then an
equilibrium of X - w Xi, whose flow is X's followed by the group motion: the stability of
the relative equilibrium modulo the group is that of X - w Xi at y0, linearised in the
chart of M_1 as :mod:`nhham.numerics.linearization` does. For a cyclic coordinate
(xi = d/ds) Xi has no derivative and X - w Xi has X's Jacobian.

:class:`Generator` evaluates Xi at (complex) states from functions the symbolic side
made (no sympy here); :func:`spin_rate` finds w from v0 = w xi(q0) + the rest;
:func:`group_block` finds the chart coordinates the others do not depend on (the group
directions, which turn among themselves in co-moving variables: a translation (x, y)
rotates at the rate w).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Generator", "RelativeMotion", "spin_rate", "spin_rates", "group_block"]

# xi^A(q0) below this (relative to max |xi(q0)|) is a component xi does not move.
_ZERO_TOL = 1e-12


@dataclass(frozen=True)
class Generator:
    """The tangent lift Xi of a vector field xi on Q, evaluated numerically.

    Attributes
    ----------
    components : tuple of (str, str)
        ``(coordinate, expression)`` for every coordinate xi moves (the scene's
        ``[symmetry]`` entries), for reports.
    evaluate : callable
        ``evaluate(Q, P) -> (xi, D)``: at the rows of Q (K, n), complex or real, and the
        parameter rows P (K, parameters) or None (the values of :attr:`parameters`),
        xi (K, n) and its Jacobian D (K, n, n), D[k, A, B] = d xi^A / d q^B.
    parameters : tuple of float
        The parameter values used where ``P`` is None (the model's order).
    constant : bool
        xi's components do not depend on the coordinates (a translation of cyclic
        coordinates): Xi has no derivative, X - w Xi has X's Jacobian, and a motion along
        xi is the steady motion of cyclic coordinates that ``linearize`` always took.
    checked : tuple of (str, str)
        ``(what, how it was decided)`` for each invariance the symbolic side checked
        (``("lagrangian", "exact")``, ``("constraints[0]", "exact")``...); empty when
        unchecked.
    momentum : callable or None
        ``momentum(Q, V, P) -> (K,)``: J = (dL/dv) . xi at the rows of Q, V (complex
        welcome) with the parameter rows P (or None), where J is conserved (xi in the
        constraint distribution, no force along it: Noether); None otherwise.

    Examples
    --------
    The rotation about the vertical of the plane (x, y) with the heading theta:

    >>> import numpy as np
    >>> from nhham.numerics.relative import Generator
    >>> def rotation(Q, P):
    ...     K = Q.shape[0]
    ...     xi = np.stack([-Q[:, 1], Q[:, 0], np.ones(K)], axis=1)
    ...     D = np.zeros((K, 3, 3)); D[:, 0, 1] = -1.0; D[:, 1, 0] = 1.0
    ...     return xi, D
    >>> G = Generator((("x", "-y"), ("y", "x"), ("theta", "1")), rotation, ())
    >>> G.lifted(np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 2.0, 0.0]]))
    array([[-0.,  1.,  1., -2.,  0.,  0.]])
    """

    components: tuple
    evaluate: Callable
    parameters: tuple = ()
    constant: bool = False
    checked: tuple = ()
    momentum: Callable | None = None

    def lifted(self, Q, V, P=None) -> np.ndarray:
        """Xi at the states (Q, V) (K, n) each: (xi(q), D(q) v), shape (K, 2n)."""
        Q = np.atleast_2d(Q)
        xi, D = self.evaluate(Q, P)
        xi = np.broadcast_to(np.asarray(xi), Q.shape)
        lift = np.einsum("kab,kb->ka", np.broadcast_to(np.asarray(D), Q.shape + Q.shape[1:]),
                         np.atleast_2d(V))
        return np.concatenate([xi, lift], axis=1)

    def text(self) -> str:
        """``xi = 1 d/dyaw - y d/dx + x d/dy`` (the components as declared)."""
        return " + ".join(f"({e}) d/d{q}" for q, e in self.components) or "0"

    def to_dict(self) -> dict:
        """``{coordinate: expression}``."""
        return dict(self.components)


@dataclass(frozen=True)
class RelativeMotion:
    """A steady state's motion along a generator: y0's velocity is w xi(q0) + rest.

    Attributes
    ----------
    rate : float
        w (least squares over the components xi moves).
    rest : ndarray, shape (n,)
        v0 - w xi(q0): what moves besides the group (cyclic coordinates only, checked by
        the linearisation).
    lifted : ndarray, shape (2n,)
        Xi(y0).
    """

    rate: float
    rest: np.ndarray
    lifted: np.ndarray


def spin_rate(generator: Generator, y0, n: int, P=None) -> RelativeMotion:
    """w with v0 = w xi(q0) + rest, from the components xi(q0) moves.

    Examples
    --------
    >>> import numpy as np
    >>> from nhham.numerics.relative import Generator, spin_rate
    >>> spin = Generator((("psi", "1"),), lambda Q, P: (np.array([[1.0, 0.0]]),
    ...                                                np.zeros((1, 2, 2))))
    >>> motion = spin_rate(spin, np.array([0.0, 0.0, 3.0, 0.5]), 2)
    >>> motion.rate, motion.rest.tolist()
    (3.0, [0.0, 0.5])
    """
    y0 = np.asarray(y0, dtype=float)
    Xi = generator.lifted(y0[None, :n], y0[None, n:], P)[0].real
    xi = Xi[:n]
    top = float(np.abs(xi).max(initial=0.0))
    v0 = y0[n:]
    if top == 0.0:
        return RelativeMotion(0.0, v0.copy(), Xi)
    moved = np.abs(xi) > _ZERO_TOL * top
    w = float(np.dot(xi[moved], v0[moved]) / np.dot(xi[moved], xi[moved]))
    return RelativeMotion(w, v0 - w * xi, Xi)


def spin_rates(generator: Generator, Y, n: int, P=None) -> tuple:
    """:func:`spin_rate` at many states: (w (N,), Xi (N, 2n)), each row's parameters P
    (N, parameters) or None.

    Examples
    --------
    >>> import numpy as np
    >>> from nhham.numerics.relative import Generator, spin_rates
    >>> spin = Generator((("psi", "1"),), lambda Q, P: (np.tile([1.0, 0.0], (len(Q), 1)),
    ...                                                np.zeros((len(Q), 2, 2))))
    >>> spin_rates(spin, np.array([[0.0, 0.0, 3.0, 0.5], [0.0, 0.0, -1.0, 0.0]]), 2)[0]
    array([ 3., -1.])
    """
    Y = np.atleast_2d(np.asarray(Y, dtype=float))
    Xi = generator.lifted(Y[:, :n], Y[:, n:], P).real
    xi = Xi[:, :n]
    top = np.abs(xi).max(axis=1, initial=0.0)
    moved = np.abs(xi) > _ZERO_TOL * top[:, None]
    num = np.where(moved, xi * Y[:, n:], 0.0).sum(axis=1)
    den = np.where(moved, xi * xi, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return w, Xi


def group_block(J, names, coordinates, keep, tol) -> list:
    """The largest set S of chart coordinates (among ``keep``) whose Jacobian columns
    vanish outside S's rows: the others' motion does not depend on them, so S is
    divided out (the group directions in co-moving variables). Returns S (indices).

    Examples
    --------
    x' = w y, y' = -w x (a translation seen from a frame turning at w), a velocity u with
    u' = -u + x: the others do not depend on x, y:

    >>> import numpy as np
    >>> from nhham.numerics.relative import group_block
    >>> J = np.array([[0.0, 2.0, 0.0], [-2.0, 0.0, 0.0], [1.0, 0.0, -1.0]])
    >>> group_block(J, ("x", "y", "u"), ("x", "y"), [0, 1, 2], 1e-12)
    []
    >>> J[2, 0] = 0.0
    >>> group_block(J, ("x", "y", "u"), ("x", "y"), [0, 1, 2], 1e-12)
    [0, 1]
    """
    S = [j for j in keep if names[j] in coordinates]
    changed = True
    while changed:
        changed = False
        for j in list(S):
            outside = [i for i in keep if i not in S]
            if outside and np.abs(J[np.ix_(outside, [j])]).max(initial=0.0) > tol:
                S.remove(j)
                changed = True
    return S
