"""The first/second-class split decided at exact points of M_f = M_1.

The bracket matrix B_ab = {chi_a, chi_b} is evaluated through the Lagrangian bracket
(:func:`nhham.lagrangian.formulas.lagrangian_bracket`) at random exact points: a rank
modulo p as large as an antisymmetric matrix can have is a proof; otherwise ranks at
rational points with the Schwartz–Zippel bound. The coefficients of the first-class
combinations are given at points.
"""

from __future__ import annotations

from functools import cached_property
from typing import cast

import numpy as np
import sympy as sp

from nhham.errors import BudgetExceeded, ComputationError, InputError, NhhamError
from nhham.hamiltonian.brackets import connected_blocks
from nhham.hamiltonian.classes import ConstraintClasses
from nhham.hamiltonian.classes_sampled import classes_from_samples
from nhham.lagrangian.analysis import ConstraintAnalysis
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import NotExact, evaluate, minor_degree
from nhham.lagrangian.formulas import lagrangian_bracket
from nhham.lagrangian.geometry import LagrangianGeometry, lagrangian_geometry
from nhham.lagrangian.linalg import (
    FloatMatrix,
    ListMatrix,
    degree_solve,
    exact_rank,
    exact_solve,
    field_solve,
)
from nhham.lagrangian.points import PointSampler, jacobian_row
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.evaluation import Backend

__all__ = ["BracketRank", "float_brackets"]


class BracketRank:
    """The first/second-class split on M_f = M_1 as a question for
    :func:`~nhham.lagrangian.engine.decide`: the rank of B_ab = {chi_a, chi_b}_L
    (:func:`nhham.lagrangian.formulas.lagrangian_bracket`), its maximal second-class set
    and the first-class combinations at the points (the answer:
    :class:`~nhham.hamiltonian.classes.ConstraintClasses`).

    No exact reduction here (the symbolic classification is
    ``classify_constraints(method="exact")``); sampled:
    the Lagrangian bracket at floating-point points.
    """

    what = "rank of the bracket matrix on M_f"

    def __init__(self, side, cons, labels, analysis, policy):
        self.side, self.analysis, self.labels = side, analysis, tuple(labels)
        self.policy = policy
        self.cons = [sp.sympify(c) for c in cons]
        self.best, self.pivots, self.mats = -1, [], []

    @cached_property
    def data(self) -> tuple:
        """(W, mixed Hessian, dchi/dq, dchi/dv) as rows, formed once M has exact points."""
        system = self.side.system
        geo = _geometry(system, self.analysis)
        n = system.n
        return ([list(geo.hessian.row(i)) for i in range(n)],
                [list(geo.mixed_hessian.row(i)) for i in range(n)],
                [jacobian_row(c, system.coordinates) for c in self.cons],
                [jacobian_row(c, system.velocities) for c in self.cons])

    def value(self, env, degrees: bool = False):
        W, Mx, Jq, Jv = self.data
        return _bracket_at(env, W, Mx, Jq, Jv, degrees=degrees)

    def proved_modulo_p(self, Bp):
        """The rank of B proved at a point over F_p where it is the largest B can have;
        else None.

        B is antisymmetric, so its rank is at most k for k even and k - 1 for k odd. A
        rank r modulo p at a point of M_1 is a lower bound of its rank over Q at a
        rational point (no inverse taken was of a multiple of p), hence of its generic
        rank on M_1: where r is that largest rank, the rank is proved. The r pivot rows
        R are independent, so B_RR is invertible (a principal submatrix of an
        antisymmetric matrix on a maximal independent set of rows); for k odd the one
        first-class combination is chi_k - sum_R (B_RR^-1 B_Rk)_a chi_a, its
        coefficients given at seeded float points of M_1 (rational arithmetic at
        n = 19 took 5 s a point).
        """
        k, labels, side, cons = len(self.cons), self.labels, self.side, self.cons
        if k == 0:
            return None
        r, rows, _ = exact_rank(Bp)
        if r < k - k % 2:
            return None
        rank_d = Decision(r, "exact", f"bracket matrix of rank {r} at a random point of "
                          f"M_f modulo the prime 2^61 - 1, the largest an antisymmetric "
                          f"{k} x {k} matrix has (proof)", samples=1, error_bound=0.0)
        nonzero = np.array([[bool(x) for x in row] for row in Bp], dtype=bool).reshape(k, k)
        blocks = tuple(tuple(labels[a] for a in blk) for blk in connected_blocks(nonzero))
        R = list(rows) if r < k else list(range(k))
        decisions = {"rank": rank_d}
        coeff_dicts: tuple = ()
        if r < k:
            (kk,) = [a for a in range(k) if a not in R]
            coeff_dicts = (_coefficients_at_a_point(side, cons, labels, self.analysis,
                                                     self.policy, R, kk, self.data),)
            decisions[f"gamma[{labels[kk]}]"] = Decision(
                True, "exact", "B_RR of rank r modulo p at the point: the combination with "
                "coefficient 1 on this constraint and -B_RR^-1 B_Rk on R is first class (its "
                "coefficients depend on the point)", samples=1)
        return ConstraintClasses(
            labels=labels, constraints_TQ=tuple(cons), constraints=None,
            bracket_matrix=None, bracket_samples=(), rank=r, first_class=k - r,
            second_class=r, second_class_set=tuple(labels[a] for a in R),
            first_class_combinations=() if r == k else None,
            combination_coefficients=coeff_dicts,
            individually_first_class=tuple(labels[a] for a in range(k)
                                           if not nonzero[a].any()),
            blocks=blocks, decisions=decisions, method="exact at points", manifold=None,
            side=side, analysis=self.analysis)

    def observe(self, Bp) -> bool:
        k = len(self.cons)
        self.mats.append(Bp)
        r, rows, _ = exact_rank(Bp) if k else (0, [], [])
        if r > self.best:
            self.best, self.pivots = r, rows
        return self.best >= k  # full rank at a rational point: proved

    def pending_error(self, degrees, count, bound):
        if self.best >= len(self.cons):
            return None
        return bound(minor_degree(degrees, self.best + 1), count)

    def conclude(self, count, degrees, bound) -> ConstraintClasses:
        k, labels, mats, r = len(self.cons), self.labels, self.mats, self.best
        if r >= k:
            rank_d = Decision(r, "exact", f"bracket matrix of full rank {r} at an exact "
                              f"point of M_f (proof)", samples=count, error_bound=0.0)
        else:
            error = self.pending_error(degrees, count, bound)
            rank_d = Decision(r, "exact at points", f"rank {r} of the bracket matrix at "
                              f"{count} random exact points of M_f", samples=count,
                              error_bound=error)
        decisions = {"rank": rank_d}
        R = list(self.pivots) if r else []
        nonzero = np.zeros((k, k), dtype=bool)
        for Bp in mats:
            nonzero |= np.array([[x != 0 for x in row] for row in Bp],
                                dtype=bool).reshape(k, k)
        coeff_dicts = []
        for kk in (i for i in range(k) if i not in R):
            per_point = [_exact_combination(Bp, R, kk) for Bp in mats]
            coeff_dicts.append({labels[a]: tuple(float(c[a]) for c in per_point)
                                for a in range(k) if any(c[a] != 0 for c in per_point)})
            decisions[f"gamma[{labels[kk]}]"] = Decision(
                True, "exact", "B c = 0 exactly at each point (c solved from the regular "
                "block of B at that point); the coefficients depend on the point",
                samples=count)
        alone = tuple(labels[a] for a in range(k) if not nonzero[a].any())
        blocks = tuple(tuple(labels[a] for a in blk)
                       for blk in connected_blocks(nonzero)) if k else ()
        return ConstraintClasses(
            labels=labels, constraints_TQ=tuple(self.cons), constraints=None,
            bracket_matrix=None,
            bracket_samples=tuple(np.array([[float(x) for x in row] for row in Bp],
                                           dtype=float).reshape(k, k) for Bp in mats),
            rank=r, first_class=k - r, second_class=r,
            second_class_set=tuple(labels[a] for a in R), first_class_combinations=None,
            combination_coefficients=tuple(coeff_dicts), individually_first_class=alone,
            blocks=blocks, decisions=decisions, method="exact at points", manifold=None,
            side=self.side, analysis=self.analysis)

    def sampled(self, manifold, policy) -> ConstraintClasses:
        """B = {chi_a, chi_b}_L at seeded float points of M_f = M_1 (no exact points).

        The Lagrangian bracket needs only W, the mixed Hessian and the gradients of
        the constraints at each point (numbers), never H or Leg^-1 symbolically.
        """
        mats, resid = float_brackets(self.side, self.cons, self.analysis, policy.precision,
                                     policy.samples, policy.seed)
        return classes_from_samples(self.side, tuple(self.cons), self.labels, self.analysis,
                                    mats, Backend(None), policy.tol, resid,
                                    "the bracket matrix {chi_a, chi_b}_L")


def _exact_combination(Bp, R, kk) -> list:
    """c with c_kk = 1, c_R = -B_RR^-1 B_Rk and 0 elsewhere (B c = 0 where rank B = |R|),
    B exact at one point (ZeroDivisionError where B_RR is singular there)."""
    c = [0] * len(Bp)
    c[kk] = 1
    if R:
        cR = exact_solve([[Bp[a][b] for b in R] for a in R], [[-Bp[a][kk]] for a in R])
        for i, a in enumerate(R):
            c[a] = cR[i][0]
    return c


def _coefficients_at_a_point(side, cons, labels, analysis, policy, R, kk, data) -> dict:
    """The coefficients of chi_kk - sum_R (B_RR^-1 B_Rk)_a chi_a: label -> values.

    At one random rational point of M_1 (exact, then rounded) up to
    ``policy.combination_size`` coordinates or when float points cannot be found (parameters
    of very different sizes); beyond, and on a curved M_1 (no rational points), at seeded
    float points (rational arithmetic at n = 19 takes seconds a point).
    """
    if not R:
        return {labels[kk]: (1.0,)}
    mats: list = []
    seed = policy.seed
    try:
        sampler = PointSampler.on_M1(side.system, seed)
    except NotExact:
        sampler = None  # a curved M_1 has no rational points: float points only
    if side.system.n > policy.combination_size or sampler is None:
        try:
            mats, _ = float_brackets(side, cons, analysis, None, 3, seed)
        except BudgetExceeded:  # an expiry is not a lack of float points
            raise
        except NhhamError as exc:
            if sampler is None:
                raise NotExact(f"no points for the coefficients of the combination: "
                               f"{exc}") from None
            # no float points (parameters of very different sizes): a rational one
    if not mats and sampler is not None:
        for _ in range(policy.max_points):
            try:
                c = _exact_combination(_bracket_at(sampler.point().env, *data), R, kk)
            except ZeroDivisionError:
                continue
            return {labels[a]: (float(c[a]),) for a in range(len(cons)) if c[a] != 0}
        raise ComputationError(f"B_RR singular at {policy.max_points} random points of M_1 though "
                               f"it is regular modulo p at one")
    per_point = []
    for S in mats:
        x = np.zeros(len(cons))
        x[kk] = 1.0
        x[R] = -np.linalg.solve(S[np.ix_(R, R)], S[R, kk])
        per_point.append(x)
    return {labels[a]: tuple(float(c[a]) for c in per_point)
            for a in range(len(cons)) if any(c[a] != 0 for c in per_point)}


def _geometry(system, analysis) -> LagrangianGeometry:
    """The analysis' geometry (its sampling settings), else the system's shared one."""
    if isinstance(analysis, ConstraintAnalysis):
        return cast(LagrangianGeometry, analysis.geometry)
    return lagrangian_geometry(system)


def float_brackets(side, cons, analysis, precision, samples, seed) -> tuple:
    """B = {chi_a, chi_b}_L (float64 arrays, k x k) at seeded float points of M_f = M_1,
    with the points' residual."""
    system = side.system
    geo = _geometry(system, analysis)
    q, v = system.coordinates, system.velocities
    cons = [sp.sympify(c) for c in cons]
    k, n = len(cons), system.n
    Mtq = Submanifold(system, tuple(cons), precision=precision, samples=samples, seed=seed,
                      exact=False)
    _, resid = Mtq.points()
    J = sp.Matrix([jacobian_row(c, list(q) + list(v)) for c in cons])
    _, values = Mtq.finite_values([geo.hessian, geo.mixed_hessian, J])
    mats = []
    for W, Mx, Jp in values:
        Jp = np.array(Jp, dtype=float).reshape(k, 2 * n)
        try:
            B = lagrangian_bracket(FloatMatrix(Jp[:, :n]), FloatMatrix(Jp[:, n:]),
                                   FloatMatrix(W), FloatMatrix(Mx))
        except ZeroDivisionError:  # W singular at this point: the bracket is not defined
            continue
        mats.append(B.a)
    if not mats:
        raise InputError(f"the Hessian W = d2L/dv dv is singular at every one of "
                         f"{len(values)} points of M_1 where it is finite: L is not regular "
                         f"on the constraint set")
    return mats, resid


def _bracket_at(env, W, Mx, Jq, Jv, degrees: bool = False):
    """The bracket matrix {chi_a, chi_b}_L at one point (exact values or residues: the
    arithmetic of ``env``; Degree bounds with ``degrees``)."""
    if not Jq:
        return []
    cache: dict = {}
    Wp, Mp, Jqp, Jvp = (ListMatrix([evaluate(r, env, cache) for r in rows])
                        for rows in (W, Mx, Jq, Jv))
    solve = degree_solve if degrees else field_solve
    return lagrangian_bracket(Jqp, Jvp, Wp, Mp, solve=solve).to_list()
