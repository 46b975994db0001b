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

from dataclasses import dataclass, replace
from functools import cached_property
from typing import cast

import sympy as sp

from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import NotExact, evaluate, minor_degree
from nhham.lagrangian.engine import Policy, decide
from nhham.lagrangian.formulas import bordered_matrix, bordered_system, vertical_rows
from nhham.lagrangian.linalg import ListMatrix, exact_rank
from nhham.lagrangian.points import jacobian_row
from nhham.lagrangian.submanifold import Submanifold

__all__ = ["Tangency", "TangencyVerdict", "tangency_at_points", "tangency_sampled"]



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
                       target: float | None = None) -> TangencyVerdict:
    """Decide stage 1 of the constraint algorithm at exact points of M_1.

    The exact steps of :func:`~nhham.lagrangian.engine.decide` for :class:`Tangency`
    (a proof modulo p, else rational points with the Schwartz–Zippel bound).

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
        Stop drawing points once every probabilistic verdict's error bound is below
        (default: :attr:`Policy.target_error <nhham.lagrangian.engine.Policy>`).

    Raises
    ------
    NotExact
        When M_1 has no exact points or an entry cannot be evaluated exactly.
    """
    M1 = Submanifold(system, tuple(primary), seed=seed)
    policy = Policy(seed=seed, closed_form_size=system.n)  # exact points only
    if target is not None:
        policy = replace(policy, target_error=target)
    verdict = decide(Tangency(system, hessian, forcing, primary), M1, policy)
    if verdict is None:
        raise NotExact("no exact point of M_1 where the entries are defined")
    return verdict


class Tangency:
    """Stage 1 of the constraint algorithm as a question for
    :func:`~nhham.lagrangian.engine.decide`: the ranks of K, [K | c] and the Jacobian
    of the constraints on M_1 (the data: :func:`nhham.lagrangian.formulas.bordered_system`).

    The answer is a :class:`TangencyVerdict`. No exact reduction: where M_1 has no
    exact points, systems up to ``policy.closed_form_size`` coordinates are left to
    the symbolic constraint algorithm (``sampled`` gives None), larger ones are
    decided at floating-point points.
    """

    what = "rank (Z_i(chi_j)) on M_1"
    residues = True  # decided at smooth points over F_p of a curved M_1 too

    def __init__(self, system, hessian, forcing, primary):
        self.system, self.v = system, tuple(system.velocities)
        self.n, self.m = len(system.coordinates), len(system.phi)
        # forcing: the matrix F, or a function forming it: a proof modulo p reads K and
        # J only, so F (the derivatives of W) is formed only where c is read
        self.hessian, self._forcing = hessian, forcing
        self.chis = [sp.sympify(c) for c in primary]
        self.best_K = self.best_aug = self.best_J = -1
        self.block: tuple = ((), ())

    # The data at points, formed once the manifold has exact points (the sampled step
    # forms its own sympy matrices).
    @cached_property
    def mu(self) -> list:
        return [list(self.system.mu.row(i)) for i in range(self.m)]

    @cached_property
    def Jq(self) -> list:
        return [jacobian_row(c, self.system.coordinates) for c in self.chis]

    @cached_property
    def Jt(self) -> list | None:
        """∂χ/∂t of each constraint when the system depends on the time, else None."""
        t = getattr(self.system, "time", None)
        return None if t is None else [sp.diff(c, t) for c in self.chis]

    @cached_property
    def Jv(self) -> list:
        rows_of = {f: i for i, f in enumerate(self.system.phi)}
        return [self.mu[rows_of[c]] if c in rows_of else jacobian_row(c, self.v)
                for c in self.chis]

    @cached_property
    def W(self) -> list:
        return [list(self.hessian.row(i)) for i in range(self.n)]

    @cached_property
    def forcing(self):
        return self._forcing() if callable(self._forcing) else self._forcing

    @cached_property
    def F(self) -> list:
        return list(self.forcing)

    def value(self, env, degrees: bool = False):
        """(K, c, J) at a point: the bordered matrix, the right-hand side and the
        Jacobian [∂χ/∂q, ∂χ/∂v] of the constraints (Degree bounds with a Degree ``env``:
        the arithmetic is the values')."""
        cache: dict = {}

        def rows(matrix):
            return [evaluate(row, env, cache) for row in matrix]

        W, mu, Jv = rows(self.W), rows(self.mu), rows(self.Jv)
        vel = [env[s] for s in self.v]
        n = self.n
        # dchi/dq (its symbolic derivatives: the 64-link snake's 64 x 66) only when read
        Jq = _Deferred(lambda: rows(self.Jq))

        def rhs():
            F = evaluate(self.F, env, cache)
            Jt = None if self.Jt is None else _column(evaluate(self.Jt, env, cache))
            _, c = bordered_system(ListMatrix(W), ListMatrix(mu, n), _column(F),
                                   ListMatrix(list(Jq), n) * _column(vel), ListMatrix(Jv, n),
                                   Jt)
            return [x for x, in c.rows]

        K = bordered_matrix(ListMatrix(W), ListMatrix(mu, n), ListMatrix(Jv, n))
        J = _Deferred(lambda: [a + b for a, b in zip(Jq, Jv)])
        return K.rows, _Deferred(rhs), J

    # ------------------------------------------------------------ modulo p
    @property
    def proved_modulo_p(self):
        """What a point over F_p proves; None when it could prove nothing (a holonomic
        row whose lift is not among the constraints, or fewer moving rows than
        multipliers)."""
        return None if self.moving is None else self._proved_modulo_p

    @cached_property
    def moving(self):
        """The rows with dχ/dv ≠ 0 when the others are complete lifts already among the
        constraints and the moving rows are as many as the multipliers; else None."""
        return self._moving_rows()

    def _proved_modulo_p(self, value):
        """The verdict proved at one point over F_p, else None.

        Rows of K with dχ/dv = 0 (holonomic g) are set aside: their condition is
        dg/dq · v, which vanishes on M_1 by construction when it is one of the
        constraints (the complete lift). If the remaining rows of K have full row
        rank at a point modulo p, they have it over Q at the same rational point, so
        C is regular on M_1 (proof), there is no λ-free combination among them
        (proof), and a Jacobian of full rank proves dim M_1 = 2n − (number of
        constraints).
        """
        moving = self.moving
        K, _, J = value
        n, m = self.n, self.m
        rK, _, _ = exact_rank(K[:n] + [K[n + j] for j in moving])
        if rK != n + m:
            return None
        # Those rows of K independent, the rows dchi/dv of the moving constraints are: when
        # every constraint moves, the Jacobian [dchi/dq, dchi/dv] has full row rank.
        rJ = len(self.chis) if len(moving) == len(self.chis) else exact_rank(list(J))[0]
        if rJ != len(self.chis):
            return None
        how = "at a random point modulo the prime 2^61 - 1 (proof)"
        still = len(moving) < len(self.chis)
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

    def _moving_rows(self):
        """The rows with dχ/dv ≠ 0 when the others are complete lifts already among the
        constraints and the moving rows are as many as the multipliers; else None."""
        moving = [j for j, row in enumerate(self.Jv) if any(x != 0 for x in row)]
        still = [j for j in range(len(self.chis)) if j not in moving]
        # The system's own lifts are recognised as written (expand does not bring a
        # lift with sqrt to one normal form: the bicycle's differs by 10^4 characters).
        lifts = dict(zip(self.system.holonomic, getattr(self.system, "complete_lifts", ())))
        chis = set(self.chis)
        still = [j for j in still if lifts.get(self.chis[j]) not in chis]
        known = {sp.expand(c) for c in self.chis} if still else set()
        for j in still:
            lift = sp.expand(sum((a * b for a, b in zip(self.Jq[j], self.v)),
                                 self.Jt[j] if self.Jt is not None else sp.S.Zero))
            if lift != 0 and lift not in known and -lift not in known:
                return None
        return moving if len(moving) == self.m else None

    # ----------------------------------------------------- rational points
    def observe(self, value) -> bool:
        K, c, J = value
        n = self.n
        if exact_rank([row[:n] for row in K[:n]])[0] < n:
            raise NotExact("W is singular at an exact point of M_1")
        rK, _, _ = exact_rank(K)
        rAug, _, _ = exact_rank([row + [x] for row, x in zip(K, c)])
        rJ, _, _ = exact_rank(list(J))
        if rK > self.best_K:
            self.best_K = rK
            self.block = _block(K, n)
        self.best_aug, self.best_J = max(self.best_aug, rAug - rK), max(self.best_J, rJ)
        return False

    def pending_error(self, degrees, count, bound):
        pending = [e for e in self._errors(degrees, count, bound)
                   if e is not None]
        return max(pending) if pending else None

    def _errors(self, degrees, count, error_bound):
        """Error bounds of: rank deficiency of K, vanishing conditions, Jacobian
        deficiency (None where the verdict is a proof)."""
        K, c, J = degrees[0], degrees[1], list(degrees[2])
        aug = [row + [x] for row, x in zip(K, c)]
        n, m = self.n, self.m

        def bound(rows, rank):
            return error_bound(minor_degree(rows, rank + 1), count)

        rK, extra, rJ = self.best_K, self.best_aug, self.best_J
        return [None if rK >= min(len(K), n + m) else bound(K, rK),
                None if extra > 0 or rK >= len(K) else bound(aug, rK),
                None if rJ >= min(len(J), 2 * n) else bound(J, rJ)]

    def conclude(self, count, degrees, bound) -> TangencyVerdict:
        n, m, chis = self.n, self.m, self.chis
        errors = self._errors(degrees, count, bound)
        rank = self.best_K - n
        full = min(len([r for r in self.Jv if any(x != 0 for x in r)]), m)
        rank_dec = _rank_decision(rank, full, errors[0], count,
                                  "rank (Z_i(chi_j)) = rank [[W, mu^T], [dchi/dv, 0]] - n")
        consistent = self.best_aug == 0
        if self.best_K == n + len(chis):
            # K has full row rank: there is no lambda-free combination at all.
            cons_dec = Decision(True, "exact", "every constraint row is in the regular "
                                "block: no lambda-free condition (K has full row rank at an "
                                "exact point)", precision="exact", samples=count,
                                error_bound=0.0)
        else:
            cons_dec = Decision(
                consistent, "exact at points" if consistent else "exact",
                ("rank [K | c] = rank K at every point: every lambda-free condition vanishes"
                 if consistent else "rank [K | c] > rank K at an exact point: a lambda-free "
                 "condition is nonzero"),
                precision="exact", samples=count, error_bound=errors[1] if consistent else 0.0)
        jac_dec = _rank_decision(self.best_J, min(len(chis), 2 * n), errors[2], count,
                                 "rank of the Jacobian of the constraints of M_1")
        rows, cols = self.block
        return TangencyVerdict(rank_dec, cons_dec, jac_dec, rows, cols, count)

    # ------------------------------------------------------ sampled points
    def sampled(self, manifold, policy):
        """Stage 1 at floating-point points of M_1 (None up to ``closed_form_size``
        coordinates: the symbolic algorithm decides those exactly)."""
        if self.n <= policy.closed_form_size:
            return None
        return tangency_sampled(self.system, self.hessian, self.forcing, self.chis,
                                manifold.sampled_only())


class _Deferred:
    """A list formed on first use: a point's right-hand side c, dchi/dq and Jacobian,
    which a proof modulo p need not read."""

    def __init__(self, make):
        self._make = make

    @cached_property
    def items(self) -> list:
        return self._make()

    def __iter__(self):
        return iter(self.items)

    def __len__(self):
        return len(self.items)


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


def _block(K, n):
    """Rows (constraints) and columns (multipliers) of a regular block of A at a point.

    A = −J_v W⁻¹ μᵀ at the point, computed exactly; the block is the first
    independent rows and columns.
    """
    Km = ListMatrix(K)
    m, k = Km.shape[1] - n, Km.shape[0] - n
    if not m or not k:
        return (), ()
    A = vertical_rows(Km.extract(range(n), range(n)), Km.extract(range(n), range(n, n + m))
                      .transpose(), Km.extract(range(n, n + k), range(n))).rows
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
    t = getattr(system, "time", None)
    Jt = None if t is None or not chis else ListMatrix([[sp.diff(c, t)] for c in chis], 1)
    K, c = (sp.Matrix(part.rows) for part in bordered_system(
        ListMatrix(hessian.tolist(), n), ListMatrix(mu.tolist(), n),
        ListMatrix(forcing.tolist(), 1), ListMatrix(Jq.tolist(), n) * _column(v),
        ListMatrix(Jv.tolist(), n), Jt))
    # One lambdified function for the three matrices (K is inside [K | c]).
    rK, rAug, jac = manifold.sampled_ranks([K, sp.Matrix.hstack(K, c),
                                            sp.Matrix.hstack(Jq, Jv) if chis else sp.zeros(0, 0)])
    rank = _shifted(rK, -n, "rank (Z_i(chi_j)) = rank [[W, mu^T], [dchi/dv, 0]] - n")
    consistent = Decision(rAug.value == rK.value, rAug.method,
                          f"rank [K | c] = {rAug.value}, rank K = {rK.value} at the sample points",
                          precision=rAug.precision, samples=rAug.samples,
                          singular_values=rAug.singular_values,
                          point_residual=rAug.point_residual,
                          warnings=tuple(rK.warnings) + tuple(rAug.warnings))
    if not chis:
        jac = Decision(0, "exact", "none")
    moving = [j for j in range(len(chis)) if any(x != 0 for x in Jv.row(j))]
    return TangencyVerdict(rank, consistent, jac, tuple(moving), tuple(range(m)),
                           rK.samples)


def _column(values) -> ListMatrix:
    """The values as an (k, 1) column."""
    return ListMatrix([[x] for x in values], 1)


def _shifted(decision: Decision, shift: int, what: str) -> Decision:
    return Decision(int(cast(int, decision.value)) + shift, decision.method, f"{what}: {decision.detail}",
                    precision=decision.precision, samples=decision.samples,
                    singular_values=decision.singular_values,
                    point_residual=decision.point_residual, warnings=decision.warnings)
