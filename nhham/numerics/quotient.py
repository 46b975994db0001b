"""The neutral directions divided out of a state matrix: one sequence of steps, the same
for one linearisation and for every state of a batch (``DESIGN.md`` §2, "Relative
equilibria").

A neutral direction is one whose eigenvalue 0 says nothing about stability: a cyclic
coordinate, a neighbouring steady motion, the orbit of a symmetry, the level of a
conserved momentum. Each is divided out by a step named by a label (the ``neutral`` of
:class:`~nhham.numerics.linearization.Linearization`, in the order taken):

- a chart variable's name: its column vanishes in the rows kept (the variable is
  cyclic, or one of the group's directions in co-moving variables): its row and column
  are deleted (the quotient by the axis e_j);
- :data:`ORBIT` (``orbit(xi)``): the orbit direction Xi(y0) of the scene's
  ``[symmetry]`` in the chart, which A maps to zero (the motion commutes with the
  symmetry: a rotation of the whole robot about the vertical is another steady motion),
  a *right* kernel vector t: the quotient by it;
- ``d/d<p>``: the tangent of the steady family along the parameter p, a right kernel
  vector: the quotient by it;
- :data:`MOMENTUM` (``level(J)``): the differential l = dJ of the symmetry's momentum
  J = (dL/dv) . xi where J is conserved (xi in the constraint distribution, no force
  along it), a *left* kernel vector (l A = 0): the restriction to the level l x = 0.

The quotient by t (pivot j, the largest |t_j|) has the matrix (T^-1 A T) without row and
column j, T the identity with column j replaced by t; the restriction to l x = 0 (pivot
j) has the matrix (A E) without row j, E the embedding x_j = -sum_(i != j) l_i x_i / l_j
of the level. Each removes one eigenvalue 0 and leaves the others; B follows A. A later
vector is carried into the coordinates of the quotient (a right one: its class, v - v_j
t / t_j without j; a left one: l E).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ORBIT", "MOMENTUM", "is_axis", "divide", "KERNEL_TOL"]

#: The orbit of the scene's [symmetry] (a right kernel vector).
ORBIT = "orbit(xi)"
#: The level of the symmetry's conserved momentum (a left kernel vector).
MOMENTUM = "level(J)"

#: |A t| <= this |A| |t| (relative) counts as A t = 0.
KERNEL_TOL = 1e-7


def is_axis(label: str) -> bool:
    """Whether a label names a chart variable (a deleted row and column)."""
    return label not in (ORBIT, MOMENTUM) and not label.startswith("d/d")


def _left(label: str) -> bool:
    return label == MOMENTUM


def divide(A, B, names, steps, *, required: bool = False) -> tuple | None:
    """Divide the kernel vectors ``steps`` out of A, in order.

    Parameters
    ----------
    A : ndarray, shape (d, d)
    B : ndarray, shape (d, r) or None
    names : sequence of str
        A's variables.
    steps : sequence of (str, ndarray of shape (d,) or None)
        (label, vector in A's variables): right kernel vectors for :data:`ORBIT` and
        ``d/d<p>``, a left one for :data:`MOMENTUM`. A step whose vector is None, zero
        (in the quotient so far: e.g. an orbit along cyclic coordinates already divided
        out) or not in the kernel (|A t| > :data:`KERNEL_TOL` |A| |t|) is not taken.
    required : bool, optional
        True: a step not taken makes the result None (a batch's state where the
        reference's step does not hold).

    Returns
    -------
    (A, B, names, taken) or None
        The quotient's matrices and variables and the labels of the steps taken.

    Examples
    --------
    theta' = omega, theta2' = v (theta - theta2)/l, omega' = -k omega: turning theta and
    theta2 together (a rotation of the robot and its trailer) is the kernel vector
    (1, 1, 0); the quotient keeps -v/l and -k:

    >>> import numpy as np
    >>> from nhham.numerics.quotient import ORBIT, divide
    >>> A = np.array([[0.0, 0.0, 1.0], [0.5, -0.5, 0.0], [0.0, 0.0, -2.0]])
    >>> Aq, _, names, taken = divide(A, None, ["theta", "theta2", "omega"],
    ...                              [(ORBIT, np.array([1.0, 1.0, 0.0]))])
    >>> sorted(np.linalg.eigvals(Aq).real.round(12).tolist()), names, taken
    ([-2.0, -0.5], ['theta2', 'omega'], ['orbit(xi)'])
    """
    A = np.asarray(A, dtype=float)
    names = list(names)
    pending = [(label, None if v is None else np.asarray(v, dtype=float))
               for label, v in steps]
    taken: list = []
    while pending:
        (label, v), pending = pending[0], pending[1:]
        scale = max(1.0, float(np.abs(A).max(initial=0.0)))
        norm = 0.0 if v is None or not A.size else float(np.abs(v).max(initial=0.0))
        left = _left(label)
        residual = (np.inf if norm == 0.0 else
                    float(np.abs(v @ A if left else A @ v).max(initial=0.0)))
        if v is None or not residual <= KERNEL_TOL * scale * norm:
            if required:
                return None
            continue
        j = int(np.argmax(np.abs(v)))
        keep = [i for i in range(len(names)) if i != j]
        if left:
            E = np.eye(len(names))[:, keep]
            E[j, :] = -v[keep] / v[j]
            A = (A @ E)[keep, :]
            B = None if B is None else B[keep, :]
            pending = [(lb, None if w is None else (w @ E if _left(lb) else w[keep]))
                       for lb, w in pending]
        else:
            T = np.eye(len(names))
            T[:, j] = v
            A = np.linalg.solve(T, A @ T)[np.ix_(keep, keep)]
            B = None if B is None else np.linalg.solve(T, B)[keep, :]
            pending = [(lb, None if w is None else
                        (w[keep] if _left(lb) else (w - w[j] / v[j] * v)[keep]))
                       for lb, w in pending]
        names = [names[i] for i in keep]
        taken.append(label)
    return A, B, names, taken
