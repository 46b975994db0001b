"""Constraints nonlinear in the velocities: their kind, and Chetaev's rule's one refusal.

A velocity constraint phi(q, v) = 0 that is not affine in v is taken with Chetaev's rule
(``DESIGN.md`` §2): its reaction is lambda d phi/d v, so that mu = d phi/d v (then a
function of q and v) plays the part of the affine constraints' one-form everywhere.
The rule gives no reaction where d phi/d v vanishes; a constraint whose d phi/d v
vanishes on all of M_1 (``(x' - y')^2``: M_1 is where x' = y', and there d phi/d v = 0)
has no reaction at all and is refused, naming it. Vanishing at some points of M_1 only
(``x'^2 + y'^2 - z'^2`` at v = 0) is a singular point of C, left to the verdict.

"Vanishes on M_1" is decided at seeded random points of M_1, found by Gauss-Newton
projection of random states onto M_1 = {g = 0, phi = 0} (a least-norm step; near a
degenerate constraint the convergence is linear but sure): d phi_i/d v vanishes on M_1
when it is zero, relative to its size at the starting state, at every point reached.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from nhham.system.velocities import non_affine_terms

__all__ = ["AFFINE", "CHETAEV", "HOLONOMIC", "LINEAR", "constraint_kind", "constraint_records", "degenerate_reactions",
           "NOT_APPLICABLE"]

#: The kinds of a velocity constraint, as ``classify`` labels them.
AFFINE = "affine"
CHETAEV = "nonlinear (Chetaev)"
#: Finer kinds in ``classify``'s records: an affine constraint with h = 0, and g(q, t) = 0.
LINEAR = "linear"
HOLONOMIC = "holonomic"

#: What the Frobenius test answers for a system with nonlinear constraints.
NOT_APPLICABLE = "not applicable for nonlinear constraints"

_POINTS = 4          # random points of M_1 tried
_ITERATIONS = 200    # Gauss-Newton steps at most (linear convergence near a double root)
_RESIDUAL = 1e-13    # |g, phi| at a point of M_1
_VANISH = 1e-6       # |d phi/d v| relative to its size at the starting state


def constraint_kind(expr, velocities) -> str:
    """``"affine"`` when ``expr`` is affine in the velocities, else ``"nonlinear (Chetaev)"``.

    Examples
    --------
    >>> import sympy as sp
    >>> xd, yd = sp.symbols("x_dot y_dot")
    >>> constraint_kind(yd - 2*xd, (xd, yd)), constraint_kind(xd*yd, (xd, yd))
    ('affine', 'nonlinear (Chetaev)')
    """
    return CHETAEV if non_affine_terms(expr, velocities) else AFFINE


def constraint_records(system) -> list[dict]:
    """``[{"label", "kind", "time_dependent"}]`` for every constraint of M_1 (the holonomic
    g, then the rows of phi, their complete lifts first): ``classify``'s JSON per constraint.

    ``kind`` is ``"holonomic"`` for g(q, t) = 0; for a velocity constraint ``"linear"``
    (mu(q) v = 0), ``"affine"`` (mu(q) v + h = 0, h != 0: a lift of a g that moves with t,
    or a rheonomic constraint) or ``"nonlinear (Chetaev)"``; ``time_dependent`` whether it
    depends explicitly on t.

    Examples
    --------
    >>> from nhham import System
    >>> system = System(["x", "y", "z", "w"], "(x_dot**2 + y_dot**2 + z_dot**2 + w_dot**2)/2",
    ...                 constraints=["x_dot*y_dot", "y_dot - t"], holonomic=["z"])
    >>> for r in constraint_records(system):
    ...     print(r)
    {'label': 'holonomic[0]', 'kind': 'holonomic', 'time_dependent': False}
    {'label': 'holonomic[0].lift', 'kind': 'linear', 'time_dependent': False}
    {'label': 'constraints[0]', 'kind': 'nonlinear (Chetaev)', 'time_dependent': False}
    {'label': 'constraints[1]', 'kind': 'affine', 'time_dependent': True}
    """
    kinds = (HOLONOMIC,) * len(system.holonomic) + tuple(
        LINEAR if kind == AFFINE and vanishes else kind
        for kind, vanishes in zip(system.constraint_kinds, system.h_vanishes))
    return [{"label": lab, "kind": kind, "time_dependent": bool(dep)}
            for lab, kind, dep in zip(system.m1_labels, kinds, system.time_dependent)]


def degenerate_reactions(system, labels, rows, kinds=None) -> list[str]:
    """One problem for every nonlinear constraint whose d phi/d v vanishes on all of M_1.

    Parameters
    ----------
    system : nhham.System
        Under construction: coordinates, velocities, parameters and holonomic set.
    labels : sequence of str
        The labels of ``rows`` (``constraints[i]``).
    rows : sequence of sympy.Expr
        The velocity constraints phi of the system (complete lifts included), the
        nonlinear ones checked.
    kinds : sequence of str, optional
        Their kinds when known (:attr:`System.constraint_kinds`); read from ``rows``
        otherwise.

    Returns
    -------
    list of str
        ``"<label>: ..."`` for each refused constraint; empty when none is.

    Examples
    --------
    phi = (x' - y')^2 vanishes with its derivative in v; x'^2 + y'^2 - 1 does not:

    >>> from nhham import System
    >>> s = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...            constraints=["x_dot**2 + y_dot**2 - 1"])
    >>> sp_rows = [sp.sympify("(x_dot - y_dot)**2", locals={v.name: v for v in s.velocities})]
    >>> problem, = degenerate_reactions(s, ["constraints[0]"], sp_rows)
    >>> problem[:70]
    'constraints[0]: d phi/d v = (2*x_dot - 2*y_dot, -2*x_dot + 2*y_dot, 0)'
    >>> degenerate_reactions(s, ["constraints[0]"], s.phi)
    []
    """
    vels = system.velocities
    if kinds is None:
        kinds = [constraint_kind(f, vels) for f in rows]
    nonlinear = [i for i, kind in enumerate(kinds) if kind == CHETAEV]
    if not nonlinear:
        return []
    vanish = _vanishing_on_m1(system, list(rows), nonlinear)
    out = []
    for i in nonlinear:
        if vanish.get(i):
            grad = [sp.diff(rows[i], v) for v in vels]
            out.append(
                f"{labels[i]}: d phi/d v = ({', '.join(str(g) for g in grad)}) vanishes on M_1 "
                f"(at every sampled point of {{{rows[i]} = 0}}), so Chetaev's rule gives it no "
                f"reaction; write the constraint so that d phi/d v is not zero where phi = 0 "
                f"(e.g. x_dot - y_dot instead of (x_dot - y_dot)**2)")
    return out


def _vanishing_on_m1(system, rows, nonlinear) -> dict:
    """``{i: True}`` for the rows i whose d phi_i/d v vanished at every point of M_1
    reached (at least two); rows never decided are left out (accepted)."""
    from nhham.system.sampled_checks import VALIDATION_SEED, sample_q

    state = system.coordinates + system.velocities
    params = tuple(system.parameters)
    F = list(system.holonomic) + rows
    J = sp.Matrix(F).jacobian(state)
    dv = sp.Matrix([rows[i] for i in nonlinear]).jacobian(system.velocities)
    args = state + params
    f_F = sp.lambdify(args, F, "numpy")
    f_J = sp.lambdify(args, J, "numpy")
    f_dv = sp.lambdify(args, dv, "numpy")
    starts = sample_q(system, np.random.default_rng(VALIDATION_SEED + 5), _POINTS)
    counts = dict.fromkeys(range(len(nonlinear)), 0)
    reached = 0
    with np.errstate(all="ignore"):
        for start in starts:
            z = np.array([start[s] for s in state], dtype=float)
            p = [start[s] for s in params]
            size = np.linalg.norm(np.asarray(f_dv(*z, *p), dtype=float), axis=1)
            z = _project(f_F, f_J, z, p)
            if z is None:
                continue
            reached += 1
            grads = np.linalg.norm(np.asarray(f_dv(*z, *p), dtype=float), axis=1)
            for k in range(len(nonlinear)):
                if grads[k] <= _VANISH * max(size[k], 1.0):
                    counts[k] += 1
    if reached < 2:
        return {}
    return {nonlinear[k]: True for k, c in counts.items() if c == reached}


def _project(f_F, f_J, z, p):
    """A point of {F = 0} near ``z`` by least-norm Gauss-Newton steps, or None."""
    # Until the steps stop (not the residual: near a double root |phi| is the square of
    # the distance, and d phi/d v is judged at the point, not at the residual's first dip).
    for _ in range(_ITERATIONS):
        r = np.asarray(f_F(*z, *p), dtype=float).ravel()
        Jz = np.asarray(f_J(*z, *p), dtype=float).reshape(len(r), len(z))
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(Jz))):
            return None
        step = np.linalg.lstsq(Jz, r, rcond=None)[0]
        z = z - step
        if np.linalg.norm(step) <= 1e-15 * (1.0 + np.linalg.norm(z)):
            break
    r = np.asarray(f_F(*z, *p), dtype=float).ravel()
    return z if np.all(np.isfinite(r)) and np.linalg.norm(r) <= _RESIDUAL else None
