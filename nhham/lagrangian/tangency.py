"""The tangency equations on M_1 without W⁻¹: the bordered system at exact points.

For constraints χ_j(q, v) defining M_1 (holonomic g, their lifts, the affine φ),
a field X = ξ_L + λ^i Z_i is tangent to M_1 when, with accelerations a,

    W a + μᵀ λ = F                      (the Euler–Lagrange equations, DESIGN §2)
    (∂χ_j/∂v) a = −(∂χ_j/∂q) v          (d/dt χ_j = 0)

that is K [a; λ] = c with the bordered matrix K = [[W, μᵀ], [J_v, 0]] and
c = [F; −J_q v]. Eliminating a (W regular) gives back A λ + b = 0 with
A_ji = Z_i(χ_j) = −(J_v W⁻¹ μᵀ)_ji, so

* rank A = rank K − n (the rank of the paper's (Z_i(χ_j)), C's rank when χ = φ);
* the λ-free conditions vanish on M_1 exactly when rank [K | c] = rank K.

Both are decided at random exact points of M_1 (:mod:`nhham.lagrangian.points`):
a rank found at an exact point is a lower bound that is proved; a rank deficiency
or a vanishing seen at k points holds with the Schwartz–Zippel error bound
computed from the degrees of the minors involved. Nothing here forms W⁻¹, the
Euler–Lagrange field or a multiplier in closed form.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import NotExact, evaluate, minor_degree, schwartz_zippel_bound
from nhham.lagrangian.formulas import bordered_matrix
from nhham.lagrangian.linalg import ListMatrix, exact_rank, exact_solve
from nhham.lagrangian.points import PointSampler, jacobian_row

__all__ = ["TangencyVerdict", "tangency_at_points", "tangency_sampled", "TARGET_ERROR"]

# Default bound on the probability that a "vanishes"/"rank deficient" verdict is wrong.
TARGET_ERROR = 1e-30
MAX_POINTS = 12


@dataclass(frozen=True)
class TangencyVerdict:
    """Stage 1 of the constraint algorithm decided at exact points of M_1.

    Attributes
    ----------
    rank : Decision
        rank of (Z_i(χ_j)) on M_1 (= rank K − n).
    consistent : Decision
        ``True`` when every λ-free condition vanishes on M_1.
    jacobian_rank : Decision
        Rank of the Jacobian of the constraints defining M_1 (dim M_1 = 2n − it).
    rows, cols : tuple of int
        A regular block of A = (Z_i(χ_j)) at the points: constraint rows and
        multiplier columns.
    points : int
        Number of exact points used.
    """

    rank: Decision
    consistent: Decision
    jacobian_rank: Decision
    rows: tuple
    cols: tuple
    points: int


def tangency_at_points(system, hessian, forcing, primary, *, seed: int,
                       target: float = TARGET_ERROR) -> TangencyVerdict:
    """Decide stage 1 of the constraint algorithm at exact points of M_1.

    Parameters
    ----------
    system
        Supplies ``coordinates``, ``velocities``, ``parameters``,
        ``parameter_values``, ``holonomic`` and ``phi`` (lifts included).
    hessian : sympy.Matrix, shape (n, n)
        W.
    forcing : sympy.Matrix, shape (n, 1)
        F, with W a + μᵀ λ = F.
    primary : sequence of sympy.Expr
        The constraints χ_j defining M_1 (rows of the tangency system).
    seed : int
        Seed of the random points.
    target : float, optional
        Stop drawing points once every probabilistic verdict's error bound is below.

    Raises
    ------
    NotExact
        When M_1 has no exact points or an entry cannot be evaluated exactly.
    """
    q, v = tuple(system.coordinates), tuple(system.velocities)
    n, m = len(q), len(system.phi)
    chis = [sp.sympify(c) for c in primary]
    mu = [list(system.mu.row(i)) for i in range(m)]
    sampler = PointSampler.on_M1(system, seed)
    Jq = [jacobian_row(c, q) for c in chis]
    rows_of = {f: i for i, f in enumerate(system.phi)}
    Jv = [mu[rows_of[c]] if c in rows_of else jacobian_row(c, v) for c in chis]
    W = [list(hessian.row(i)) for i in range(n)]
    F = list(forcing)
    proof = _proof_modulo_p(system, chis, W, F, mu, Jq, Jv, seed)
    if proof is not None:
        return proof

    best_K = best_aug = best_J = -1
    first_K = None
    count = 0
    state = dict(rows=(), cols=())
    degrees = None
    while count < MAX_POINTS:
        pt = sampler.point()
        try:
            K, c, J = _bordered(pt.env, W, F, mu, Jq, Jv, v)
        except ZeroDivisionError:
            continue
        count += 1
        if exact_rank([row[:n] for row in K[:n]])[0] < n:
            raise NotExact("W is singular at an exact point of M_1")
        rK, _, _ = exact_rank(K)
        rAug, _, _ = exact_rank([row + [x] for row, x in zip(K, c)])
        rJ, _, _ = exact_rank(J)
        if rK > best_K:
            best_K, first_K = rK, pt
            state.update(zip(("rows", "cols"), _block(K, n)))
        best_aug, best_J = max(best_aug, rAug - rK), max(best_J, rJ)
        if degrees is None:
            degrees = _degrees(pt.degrees, W, F, mu, Jq, Jv, v, sampler)
        pending = [e for e in _errors(degrees, best_K, best_aug, best_J, count, n, m)
                   if e is not None]
        if not pending or max(pending) < target:
            break
    if first_K is None:
        raise NotExact("no exact point of M_1 where the entries are defined")
    errors = _errors(degrees, best_K, best_aug, best_J, count, n, m)
    rank = best_K - n
    full = min(len([r for r in Jv if any(x != 0 for x in r)]), m)
    rank_dec = _rank_decision(rank, full, errors[0], count,
                              "rank (Z_i(chi_j)) = rank [[W, mu^T], [dchi/dv, 0]] - n")
    consistent = best_aug == 0
    if best_K == n + len(chis):
        # K has full row rank: there is no lambda-free combination at all.
        cons_dec = Decision(True, "exact", "every constraint row is in the regular block: "
                            "no lambda-free condition (K has full row rank at an exact point)",
                            precision="exact", samples=count, error_bound=0.0)
    else:
        cons_dec = Decision(
            consistent, "exact at points" if consistent else "exact",
            ("rank [K | c] = rank K at every point: every lambda-free condition vanishes"
             if consistent else "rank [K | c] > rank K at an exact point: a lambda-free "
             "condition is nonzero"),
            precision="exact", samples=count, error_bound=errors[1] if consistent else 0.0)
    jac_dec = _rank_decision(best_J, min(len(chis), 2 * n), errors[2], count,
                             "rank of the Jacobian of the constraints of M_1")
    return TangencyVerdict(rank_dec, cons_dec, jac_dec, state["rows"], state["cols"], count)


def _proof_modulo_p(system, chis, W, F, mu, Jq, Jv, seed, tries: int = 3):
    """The verdict when it can be proved at one point over F_p, else None.

    Rows of K with dχ/dv = 0 (holonomic g) are set aside: their condition is
    dg/dq · v, which vanishes on M_1 by construction when it is one of the
    constraints (the complete lift). If the remaining rows of K have full row rank
    at a point modulo p, they have it over Q at the same rational point, so C is
    regular on M_1 (proof), there is no λ-free combination among them (proof),
    and a Jacobian of full rank proves dim M_1 = 2n − (number of constraints).
    """
    q, v = tuple(system.coordinates), tuple(system.velocities)
    n, m = len(q), len(mu)
    moving = [j for j, row in enumerate(Jv) if any(x != 0 for x in row)]
    still = [j for j in range(len(chis)) if j not in moving]
    known = {sp.expand(c) for c in chis} if still else set()
    for j in still:
        lift = sp.expand(sum((a * b for a, b in zip(Jq[j], v)), sp.S.Zero))
        if lift != 0 and lift not in known and -lift not in known:
            return None
    if len(moving) != m:
        return None
    sampler = PointSampler.on_M1(system, seed, modular=True)
    for _ in range(tries):
        try:
            pt = sampler.point()
            K, c, J = _bordered(pt.env, W, F, mu, [Jq[j] for j in range(len(chis))],
                                Jv, v)
        except (ZeroDivisionError, NotExact):
            continue
        Kmov = K[:n] + [K[n + j] for j in moving]
        rK, _, _ = exact_rank(Kmov)
        rJ, _, _ = exact_rank(J)
        if rK == n + m and rJ == len(chis):
            how = "at a random point modulo the prime 2^61 - 1 (proof)"
            rank = Decision(m, "exact", f"rank (Z_i(chi_j)) = rank [[W, mu^T], [mu, 0]] - n = "
                            f"{m}, full, {how}", precision="exact", samples=1, error_bound=0.0)
            cons = Decision(True, "exact", "no lambda-free condition: the rows of the "
                            "velocity constraints are independent in K " + how
                            + ("; the holonomic rows give their complete lifts, which are "
                               "constraints of M_1" if still else ""),
                            precision="exact", samples=1, error_bound=0.0)
            jac = Decision(rJ, "exact", f"Jacobian of the constraints of full rank {rJ} {how}",
                           precision="exact", samples=1, error_bound=0.0)
            return TangencyVerdict(rank, cons, jac, tuple(moving), tuple(range(m)), 1)
    return None


def _rank_decision(rank, full, error, count, what) -> Decision:
    if rank >= full:
        return Decision(rank, "exact", f"{what}: full rank {rank} at an exact point (proof)",
                        precision="exact", samples=count, error_bound=0.0)
    if error == 0.0:
        # The minors have degree 0: constant entries, so one point decides.
        return Decision(rank, "exact", f"{what}: rank {rank}; the minors are constants",
                        precision="exact", samples=count, error_bound=0.0)
    return Decision(rank, "exact at points",
                    f"{what}: rank {rank} at {count} random exact points",
                    precision="exact", samples=count, error_bound=error)


def _bordered(env, W, F, mu, Jq, Jv, v):
    cache = {}
    Wv = [evaluate(row, env, cache) for row in W]
    Fv = evaluate(F, env, cache)
    muv = [evaluate(row, env, cache) for row in mu]
    Jqv = [evaluate(row, env, cache) for row in Jq]
    Jvv = [evaluate(row, env, cache) for row in Jv]
    vel = [env[s] for s in v]
    n = len(Wv)
    K = bordered_matrix(ListMatrix(Wv), ListMatrix(muv, n), ListMatrix(Jvv, n)).rows
    c = Fv + [-sum((a * b for a, b in zip(row, vel)), 0) for row in Jqv]
    J = [a + b for a, b in zip(Jqv, Jvv)]
    return K, c, J


def _degrees(deg_env, W, F, mu, Jq, Jv, v, sampler):
    """Minor-degree data of K, [K | c] and the Jacobian from Degree arithmetic."""
    K, c, J = _bordered(deg_env, W, F, mu, Jq, Jv, v)
    aug = [row + [x] for row, x in zip(K, c)]
    return {"K": K, "aug": aug, "J": J, "den": sampler.denominator_degree}


def _errors(degrees, rK, extra, rJ, count, n, m):
    """Error bounds of: rank deficiency of K, vanishing conditions, Jacobian deficiency."""
    den = degrees["den"]

    def bound(rows, rank):
        return schwartz_zippel_bound(minor_degree(rows, rank + 1), count,
                                     denominator_degree=den)

    out = []
    size_K = min(len(degrees["K"]), n + m)
    out.append(None if rK >= size_K else bound(degrees["K"], rK))
    out.append(None if extra > 0 or rK >= len(degrees["K"]) else bound(degrees["aug"], rK))
    size_J = min(len(degrees["J"]), 2 * n)
    out.append(None if rJ >= size_J else bound(degrees["J"], rJ))
    return out


def _block(K, n):
    """Rows (constraints) and columns (multipliers) of a regular block of A at a point.

    A = −J_v W⁻¹ μᵀ at the point, computed exactly; the block is the first
    independent rows and columns.
    """
    Wp = [row[:n] for row in K[:n]]
    muT = [row[n:] for row in K[:n]]
    Jv = [row[:n] for row in K[n:]]
    if not muT or not muT[0] or not Jv:
        return (), ()
    X = exact_solve(Wp, muT)  # W^{-1} mu^T, n x m
    A = [[-sum((Jv[j][k] * X[k][i] for k in range(n)), 0) for i in range(len(X[0]))]
         for j in range(len(Jv))]
    _, _, cols = exact_rank(A)
    # the independent rows restricted to those columns: pivot columns of the transpose
    _, _, rows = exact_rank([[A[j][i] for j in range(len(A))] for i in cols])
    return tuple(rows), tuple(cols)


def tangency_sampled(system, hessian, forcing, primary, manifold) -> TangencyVerdict:
    """Stage 1 decided at floating-point sample points of M_1 (no exact points).

    For M_1 without exact points (a holonomic constraint that is not linear in a
    coordinate, a parameter with a value inside sin/cos) the same bordered
    matrices are handed to the manifold's sampled rank decision (Newton-projected
    points in float64 or mpmath, singular values, doubtful values warned about).
    Still no W⁻¹: the entries of K are W, μ and dχ/dv.

    Parameters
    ----------
    manifold : Submanifold
        M_1 with ``exact=False`` and the caller's precision, samples and seed.
    """
    q, v = tuple(system.coordinates), tuple(system.velocities)
    n, m = len(q), len(system.phi)
    chis = [sp.sympify(c) for c in primary]
    mu = system.mu
    Jv = sp.Matrix([jacobian_row(c, v) for c in chis]) if chis else sp.zeros(0, n)
    Jq = sp.Matrix([jacobian_row(c, q) for c in chis]) if chis else sp.zeros(0, n)
    K = sp.Matrix.vstack(sp.Matrix.hstack(hessian, mu.T),
                         sp.Matrix.hstack(Jv, sp.zeros(len(chis), m)))
    c = sp.Matrix.vstack(forcing, -Jq * sp.Matrix(v))
    rK = manifold.rank(K)
    rAug = manifold.rank(sp.Matrix.hstack(K, c))
    rank = _shifted(rK, -n, "rank (Z_i(chi_j)) = rank [[W, mu^T], [dchi/dv, 0]] - n")
    consistent = Decision(rAug.value == rK.value, rAug.method,
                          f"rank [K | c] = {rAug.value}, rank K = {rK.value} at the sample points",
                          precision=rAug.precision, samples=rAug.samples,
                          singular_values=rAug.singular_values,
                          point_residual=rAug.point_residual,
                          warnings=tuple(rK.warnings) + tuple(rAug.warnings))
    jac = manifold.rank(sp.Matrix.hstack(Jq, Jv)) if chis else Decision(0, "exact", "none")
    moving = [j for j in range(len(chis)) if any(x != 0 for x in Jv.row(j))]
    return TangencyVerdict(rank, consistent, jac, tuple(moving), tuple(range(m)),
                           rK.samples)


def _shifted(decision: Decision, shift: int, what: str) -> Decision:
    return Decision(int(decision.value) + shift, decision.method, f"{what}: {decision.detail}",
                    precision=decision.precision, samples=decision.samples,
                    singular_values=decision.singular_values,
                    point_residual=decision.point_residual, warnings=decision.warnings)
