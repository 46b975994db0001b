"""The generic rank of a matrix of functions, decided at sample points whatever the units.

A rank decided in float64 against a tolerance relative to the largest entry depends on the
units: W = diag(m, m, I1, I2) with m = 1e-16 and the rest 1 "has rank 2", and a constraint
row [1, 0, 0, -R cos(theta)] with R = 1e12 "is a multiple" of its neighbour. A change of
units is a diagonal scaling of rows and columns, which leaves the rank unchanged. So a
deficiency seen in float64 is checked again in high precision, on the matrix equilibrated
by rows and columns (Ruiz's scaling), where only an entry that is zero by cancellation
could mislead: such an entry is recognised because its value does not repeat when the
evaluation is redone with more digits (a true value keeps its leading digits), and it is
set to zero before scaling.

The decision is unit-free over a dynamic range of about ``10**SEPARATION`` between the
largest and smallest entries that matter.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import mpmath
import numpy as np
import sympy as sp

__all__ = ["float_rank", "precise_ranks"]

#: Digits of the confirming evaluation (a second one uses twice as many).
DIGITS = 60
#: A singular value of the equilibrated matrix below 10**-SEPARATION of the largest is 0.
SEPARATION = 40
#: Float64 rank tolerance relative to the largest entry (below: confirm precisely).
FLOAT_RTOL = 1e-9


def float_rank(S: np.ndarray) -> int:
    """Rank of a float64 matrix, tolerance ``FLOAT_RTOL`` times its largest entry (at least 1).

    A full rank here is final; a deficiency may be an artefact of the units.
    """
    S = np.asarray(S, dtype=float)
    if not S.size:
        return 0
    return int(np.linalg.matrix_rank(S, tol=FLOAT_RTOL * max(1.0, float(np.abs(S).max()))))


def precise_ranks(matrix: sp.Matrix, points: Sequence[Mapping], rows: Sequence[Sequence[int]]
                  ) -> list[int]:
    """For each set of row indices, the largest rank of ``matrix[rows]`` over ``points``.

    Parameters
    ----------
    matrix : sympy.Matrix, shape (r, c)
    points : sequence of mappings
        Numeric values (floats) of every free symbol of ``matrix``; exact binary values,
        so the two evaluations see the same point.
    rows : sequence of sequences of int
        Row subsets whose ranks are wanted (one evaluation serves them all).
    """
    values = [_stable_values(matrix, pt) for pt in points]
    out = []
    for subset in rows:
        out.append(max((_equilibrated_rank([vals[i] for i in subset]) for vals in values),
                       default=0))
    return out


def _stable_values(matrix, point) -> list[list]:
    """Entries at ``point`` in DIGITS digits, those that change at 2 DIGITS set to 0."""
    lo = _evaluate(matrix, point, DIGITS)
    hi = _evaluate(matrix, point, 2 * DIGITS)
    with mpmath.workdps(2 * DIGITS):
        return [[b if b and abs(a - b) <= mpmath.mpf(10) ** (-DIGITS // 2) * abs(b) else
                 mpmath.mpf(0) for a, b in zip(ra, rb)] for ra, rb in zip(lo, hi)]


def _evaluate(matrix, point, digits) -> list[list]:
    sub = {s: sp.Float(float(x), digits) for s, x in point.items()}
    out = []
    with mpmath.workdps(2 * DIGITS):  # mpf() rounds to the working precision
        for i in range(matrix.rows):
            row = []
            for j in range(matrix.cols):
                value = sp.re(matrix[i, j].xreplace(sub).evalf(digits))
                row.append(mpmath.mpf(sp.Float(value, digits)._mpf_))
            out.append(row)
    return out


def _equilibrated_rank(rows: list[list]) -> int:
    if not rows or not rows[0]:
        return 0
    with mpmath.workdps(2 * DIGITS):
        A = mpmath.matrix(rows)
        for _ in range(12):  # Ruiz: rows and columns to unit max-norm
            for i in range(A.rows):
                s = max(abs(A[i, j]) for j in range(A.cols))
                if s:
                    for j in range(A.cols):
                        A[i, j] /= mpmath.sqrt(s)
            for j in range(A.cols):
                s = max(abs(A[i, j]) for i in range(A.rows))
                if s:
                    for i in range(A.rows):
                        A[i, j] /= mpmath.sqrt(s)
        if not any(A[i, j] for i in range(A.rows) for j in range(A.cols)):
            return 0
        s = mpmath.svd_r(A, compute_uv=False)
        top = max(abs(x) for x in s)
        return sum(1 for x in s if abs(x) > top * mpmath.mpf(10) ** (-SEPARATION))
