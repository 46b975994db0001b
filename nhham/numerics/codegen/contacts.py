"""The numbers a contact force needs, from sympy: the bridge for
:mod:`nhham.numerics.contact_forces`.

For K states, μ (the one-forms of φ, shape (K, m, n)) and, per contact point, J_P = ∂v_P/∂v
(shape (K, 3, n)) and the rows of φ it carries (:mod:`nhham.system.contacts`).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from nhham.system.contacts import contact_rows, velocity_jacobian

__all__ = ["contact_arrays"]


def contact_arrays(system, contacts, states, parameters) -> tuple:
    """``(mu, [(rows, J_P) per contact])`` at the states.

    Parameters
    ----------
    system : nhham.System
    contacts : sequence of ContactPoint
    states : ndarray, shape (K, 2n)
    parameters : mapping
        Parameter symbol -> value, every parameter of the system.
    """
    params = [float(parameters[p]) for p in system.parameters]
    args = (*system.coordinates, *system.velocities, *system.parameters)
    count = len(states)
    columns = [*states.T, *(np.full(count, v) for v in params)]
    mu = _batch(args, system.mu, columns, count)
    return mu, [(contact_rows(system, c), _batch(args, velocity_jacobian(system, c), columns,
                                                  count)) for c in contacts]


def _batch(args, matrix, columns, count) -> np.ndarray:
    """A sympy matrix evaluated at K states: shape (K, rows, cols)."""
    matrix = sp.Matrix(matrix)
    fn = sp.lambdify(args, list(matrix), modules="numpy")
    values = [np.broadcast_to(np.asarray(x, dtype=float), (count,)) for x in fn(*columns)]
    return np.stack(values, axis=1).reshape(count, matrix.rows, matrix.cols)
