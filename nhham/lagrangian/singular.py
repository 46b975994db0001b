"""The constraint algorithm on TQ for a singular Lagrangian (Gotay–Nester, the SODE built in).

A motion is a second-order field X = v^A ∂/∂q^A + a^A ∂/∂v^A (so q' = v: the SODE
condition holds by construction) whose accelerations satisfy the Euler–Lagrange
equations with the reactions of the constraints (``DESIGN.md`` §2),

    W a + μᵀ λ = F          (F: ∂L/∂q − ∂²L/∂q∂v v, the forcing of the regular case),

and which is tangent to the constraints. With W singular these are conditions on the
motion, not a formula for a: the run is :func:`~nhham.lagrangian.algorithm.run_algorithm`
with base field (v, 0), one vertical field ∂/∂v^A per acceleration a^A (multipliers
``<q>_ddot``), one zero field per reaction λ^i, and the n rows W a + μᵀ λ − F as
``field_conditions``. Their multiplier-free combinations k·F (k in ker W) are the
Lagrangian constraints; the tangency of those fixes accelerations or adds more. For
L = B x y' − V this gives y' = V_x/B, x' = −V_y/B: the constraints the Hamiltonian chain
does not see (on T*Q they are conditions on the multipliers).
"""

from __future__ import annotations

import sympy as sp

from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.engine import Policy
from nhham.lagrangian.records import AlgorithmRun
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.naming import acceleration_symbol, multiplier_symbol

__all__ = ["lagrangian_chain"]


def lagrangian_chain(system, *, policy: Policy | None = None,
                     max_stages: int | None = None) -> AlgorithmRun:
    """The constraint algorithm on TQ of a (singular) Lagrangian: M_f and its motion.

    Parameters
    ----------
    system : nhham.System
        At the values it is to be answered at (the Dirac–Bergmann chain passes its own);
        velocity constraints (affine or Chetaev: the reaction lambda dphi/dv), holonomic
        ones, forces and t.
    policy : Policy, optional
    max_stages : int, optional
        Default 2n.

    Returns
    -------
    AlgorithmRun
        On TQ: its multipliers are the accelerations ``<q>_ddot`` then ``lambda_<i>``; the
        final constraints include the Lagrangian ones (k·F) and their descendants.

    Examples
    --------
    The lowest Landau level: W = 0, so F = 0 is two constraints on TQ, the velocity of the
    drift, and their tangency fixes both accelerations.

    >>> from nhham import System
    >>> from nhham.lagrangian.singular import lagrangian_chain
    >>> run = lagrangian_chain(System(["x", "y"], "2*x*y_dot - (x**2 + y**2)/2"))
    >>> run.status, run.final_constraints[:2], run.dimension
    ('determined', (x - 2*y_dot, 2*x_dot + y), 2)
    """
    from nhham.lagrangian.algorithm import run_algorithm

    policy = policy or Policy()
    q, v = tuple(system.coordinates), tuple(system.velocities)
    n, m = len(q), len(system.phi)
    L = system.lagrangian
    W = sp.Matrix(system.hessian)
    t = system.time   # d/dt dL/dv has the term d2L/dv dt when L depends on t
    F = sp.Matrix([sp.diff(L, qb) - sum((sp.diff(L, qc, vb) * vc for qc, vc in zip(q, v)),
                                        sp.S.Zero) - (sp.diff(L, vb, t) if t is not None else 0)
                   for qb, vb in zip(q, v)])
    acc = tuple(acceleration_symbol(c) for c in q)
    lam = tuple(multiplier_symbol(i + 1) for i in range(m))
    mu = sp.Matrix(system.mu) if m else sp.zeros(0, n)
    a, lm = sp.Matrix(acc), sp.Matrix(lam) if m else sp.zeros(0, 1)
    reaction = mu.T * lm if m else sp.zeros(n, 1)
    if system.has_forces:   # d/dt dL/dv - dL/dq = Q - dR/dv (DESIGN.md §2)
        F = F + system.generalized_forces
    euler = (W * a + reaction - F).applyfunc(cancel)
    conditions = tuple((f"euler_lagrange[{c.name}]", euler[A]) for A, c in enumerate(q))
    base = sp.Matrix(list(v) + [0] * n)
    fields = sp.Matrix([[0] * n + [1 if B == A else 0 for B in range(n)] for A in range(n)]
                       + [[0] * (2 * n) for _ in range(m)])
    primary = tuple(system.holonomic) + tuple(system.phi)

    def manifold(eqs):
        return Submanifold(system, eqs, precision=policy.precision, samples=policy.samples,
                           seed=policy.seed, exact=policy.exact)

    return run_algorithm(base, fields, primary, system.m1_labels, manifold,
                         max_stages=2 * n if max_stages is None else max_stages,
                         multiplier_symbols=acc + lam, variables=q + v,
                         secondary_prefix="lagrangian", points_are_motions=True,
                         field_conditions=conditions, time=t)
