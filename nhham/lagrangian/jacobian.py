"""Exact linearisation of the constrained dynamics about a state on M_1.

The numeric linearisation (:mod:`nhham.numerics.linearization`) differentiates
the reduced field by the complex step. For small systems the same Jacobian
can be had exactly, without ever writing W^{-1} or the closed-form field:

- the accelerations a and multipliers lambda solve the saddle-point system
  R = (W a + mu^T lambda - F, mu a + drift) = 0 (``DESIGN.md`` §2), so by
  implicit differentiation d(a, lambda)/dy = -K^{-1} dR/dy at the state, with
  K = [[W, mu^T], [mu, 0]] a matrix of numbers there;
- the chart (q_I, u_I) -> (q, v) of M_1 is differentiated the same way:
  dq_D = -(dg/dq_D)^{-1} (dg/dq_I) dq_I and
  mu_D dv_D = -((d phi/dq) dq + mu_I dv_I);
- the reduced Jacobian is J = P Df L with P picking (v_I-of-q_I, a_I).

Every derivative is symbolic; only numbers (exact rationals from the
parameter values, and whatever exact values the state has) are solved with,
so the entries of J are exact. Eigenvalues are then computed from the exact
matrix with mpmath at the requested number of digits.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import sympy as sp

from nhham.errors import ComputationError, InputError
from nhham.lagrangian.geometry import lagrangian_geometry

__all__ = ["ExactJacobian", "exact_jacobian", "exact_number", "EXACT_DIGITS"]

#: Digits of the eigenvalues computed from an exact state matrix (``nhham linearize``).
EXACT_DIGITS = 30


@dataclass(frozen=True)
class ExactJacobian:
    """The exact Jacobian of the reduced field in a chart of M_1.

    Attributes
    ----------
    chart : tuple of str
        Independent coordinates then independent velocities.
    matrix : sympy.ImmutableMatrix
        J with exact entries, rows and columns in ``chart`` order.
    accelerations : sympy.ImmutableMatrix
        The exact accelerations a at the state (zero for a steady motion).
    """

    chart: tuple
    matrix: sp.ImmutableMatrix
    accelerations: sp.ImmutableMatrix


def exact_number(value):
    """A float as the exact rational it is, or an exact sympy number unchanged."""
    if isinstance(value, sp.Basic):
        return value
    return sp.Rational(str(float(value))) if float(value) != int(value) else sp.Integer(int(value))


def exact_jacobian(system, state: Mapping[str, object], parameters: Mapping[str, object],
                   independent: Sequence[str]) -> ExactJacobian:
    """Exact Jacobian of the reduced field at ``state`` in the given chart.

    Parameters
    ----------
    system : nhham.System
    state : mapping of str to number
        Every coordinate and velocity: sympy numbers (kept exact) or floats
        (read as the exact decimal they print as).
    parameters : mapping of str to number
        A value for every parameter (same reading).
    independent : sequence of str
        Independent coordinates and velocities; the others are solved from
        the holonomic and affine constraints.

    Returns
    -------
    ExactJacobian

    Raises
    ------
    InputError
        Unknown names, or a chart the constraints cannot be solved in.
    ComputationError
        The saddle-point matrix is singular at the state.
    """
    n = system.n
    qs, vs = list(system.coordinates), list(system.velocities)
    names = [s.name for s in qs + vs]
    unknown = [s for s in independent if s not in names]
    if unknown:
        raise InputError(f"linearize: unknown name(s) {', '.join(unknown)}")
    point = {s: exact_number(state[s.name]) for s in qs + vs}
    point.update({p: exact_number(parameters[p.name]) for p in system.parameters})
    iq = [i for i in range(n) if qs[i].name in independent]
    dq = [i for i in range(n) if i not in iq]
    iv = [i for i in range(n) if vs[i].name in independent]
    dv = [i for i in range(n) if i not in iv]
    k, m = len(system.holonomic), system.m
    if len(dq) != k or len(dv) != m:
        raise InputError(f"linearize: the chart needs {n - k} independent coordinates and "
                         f"{n - m} velocities")

    ing = lagrangian_geometry(system).ingredients
    W, F, mu, drift = ing.W, ing.forcing, ing.mu, ing.drift
    K = sp.zeros(n + m, n + m)
    K[:n, :n] = W.xreplace(point)
    K[:n, n:] = mu.T.xreplace(point)
    K[n:, :n] = mu.xreplace(point)
    rhs = sp.Matrix.vstack(F.xreplace(point), -drift.xreplace(point))
    try:
        sol = K.LUsolve(rhs)
    except (ValueError, ZeroDivisionError):
        raise ComputationError("linearize: the saddle-point matrix is singular at the state") from None
    a0, lam0 = sol[:n, :], sol[n:, :]
    A = sp.Matrix(sp.symbols(f"_a0:{n}"))
    L = sp.Matrix(sp.symbols(f"_l0:{m}")) if m else sp.zeros(0, 1)
    R = sp.Matrix.vstack(W * A + mu.T * L - F, mu * A + drift) if m else W * A - F
    y = sp.Matrix(qs + vs)
    sub = dict(point)
    sub.update(dict(zip(list(A), list(a0))))
    sub.update(dict(zip(list(L), list(lam0))))
    dR = R.jacobian(y).xreplace(sub)
    dsol = -K.LUsolve(dR)          # d(a, lambda)/dy, (n + m) x 2n
    da = dsol[:n, :]
    # derivative of the chart map x = (q_I, u_I) -> y = (q, v)
    d = len(iq) + len(iv)
    Ly = sp.zeros(2 * n, d)
    for c, i in enumerate(iq):
        Ly[i, c] = 1
    if dq:
        G = sp.Matrix(system.holonomic).jacobian(sp.Matrix(qs)).xreplace(point)
        dqd = -G.extract(list(range(k)), dq).LUsolve(G.extract(list(range(k)), iq))
        for r, i in enumerate(dq):
            for c in range(len(iq)):
                Ly[i, c] = dqd[r, c]
    for c, i in enumerate(iv):
        Ly[n + i, len(iq) + c] = 1
    if dv:
        phi = sp.Matrix(system.phi)
        phiq = phi.jacobian(sp.Matrix(qs)).xreplace(point)
        mun = mu.xreplace(point)
        known = phiq * Ly[:n, :] + mun.extract(list(range(m)), iv) * Ly.extract(
            [n + i for i in iv], list(range(d)))
        dvd = -mun.extract(list(range(m)), dv).LUsolve(known)
        for r, i in enumerate(dv):
            for c in range(d):
                Ly[n + i, c] = dvd[r, c]
    Df_rows = []
    for i in iq:                      # q_I' = v[i]
        row = sp.zeros(1, 2 * n)
        row[0, n + i] = 1
        Df_rows.append(row)
    for i in iv:                      # u_I' = a[i]
        Df_rows.append(da.row(i))
    J = sp.Matrix.vstack(*Df_rows) * Ly
    chart = tuple(qs[i].name for i in iq) + tuple(vs[i].name for i in iv)
    return ExactJacobian(chart, sp.ImmutableMatrix(J), sp.ImmutableMatrix(a0))
