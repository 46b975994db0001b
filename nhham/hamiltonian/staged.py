"""The cross-check when C is singular: the constraint algorithm staged at exact points.

Both sides' tangency data (Z_i(chi_j), X(chi_j)) compared at exact points of every M_k,
modulo p, then the fields on M_f.
"""

from __future__ import annotations

import dataclasses
import math
import random
from dataclasses import dataclass

import numpy as np

from nhham.hamiltonian.checks import CheckResult, stage_summaries
from nhham.hamiltonian.comparison import (
    ModularComparisonPoints,
    NumericLagrangian,
    check_form_sampled,
)
from nhham.hamiltonian.side import HamiltonianSide
from nhham.lagrangian.domains import PRIME, ModP, NotExact
from nhham.lagrangian.formulas import tangency_rows
from nhham.lagrangian.linalg import (
    FloatMatrix,
    ModularBackend,
    backend_solve,
    exact_rank,
    exact_solve,
)

__all__ = ["staged_at_points"]


# ------------------------------------------- singular C: exact points of every M_k
@dataclass(frozen=True)
class _Tangency:
    """The stage data of one side at one point: T (k, m) with T[j, i] = Z_i(chi_j) and
    xi (k,) with xi[j] = xi(chi_j), for the constraints chi of a stage."""

    T: np.ndarray
    xi: np.ndarray


def _tangency_L(lag: NumericLagrangian, be, vals, chis) -> _Tangency:
    """On TQ: Z_i = -W^{AB} mu_iB d/dv^A and xi_L = v d/dq + W^{-1} F d/dv."""
    n = lag.n
    W, F, mu = lag._W(be, vals), lag._F(be, vals), lag._mu(be, vals)
    v = np.array(vals[n:2 * n], dtype=object)
    Gq, Gv = lag.gradients(be, vals, chis)
    A, b = tangency_rows(FloatMatrix(W), FloatMatrix(mu), FloatMatrix(F), FloatMatrix(Gq @ v),
                         FloatMatrix(Gv), solve=backend_solve(be))
    return _Tangency(A.a, b.a)


def _tangency_H(num, be, hp, chis) -> _Tangency:
    """On T*Q, of chi o Leg^{-1}: Z_i^H = -mu_iA d/dp_A and X_H = (dH/dp, -dH/dq)."""
    _, dq, dp = num.gradients(be, hp, chis)
    return _Tangency(-(dp @ hp.mu.T), dq @ hp.Hp - dp @ hp.Hq)


def _solutions(t: _Tangency):
    """(rank, augmented rank, particular lambda, kernel basis) of T lambda = -xi over F_p.

    The particular solution is zero off the pivot columns; the kernel has one vector
    per non-pivot column. Both are None when the system is inconsistent.
    """
    k, m = t.T.shape
    rows = [list(r) for r in t.T]
    r, prow, pcol = exact_rank(rows) if k and m else (0, [], [])
    aug = exact_rank([row + [x] for row, x in zip(rows, t.xi)])[0] if k else 0
    if aug > r:
        return r, aug, None, None
    zero = ModularBackend().zeros(m)
    block = [[rows[i][j] for j in pcol] for i in prow]
    lam = zero.copy()
    if r:
        for j, x in zip(pcol, exact_solve(block, [[-t.xi[i]] for i in prow])):
            lam[j] = x[0]
    kernel = []
    for j in (j for j in range(m) if j not in pcol):
        vec = zero.copy()
        vec[j] = ModP(1)
        if r:
            for c, x in zip(pcol, exact_solve(block, [[rows[i][j]] for i in prow])):
                vec[c] = -x[0]
        kernel.append(vec)
    return r, aug, lam, kernel


def staged_at_points(system, side: HamiltonianSide, samples, seed, max_stages):
    """The checks of a system whose C is singular, at exact points of every M_k.

    The constraint algorithm on TQ is the inverse-free one; the T*Q algorithm is
    not run symbolically (that would need H through Leg^{-1}). Instead its data at
    Leg of exact points of each M_k, Z_i^H(chi_j^H) and X_H(chi_j^H) with chi^H =
    chi o Leg^{-1}, are computed modulo p and compared with Z_i(chi_j) and
    xi_L(chi_j): equal data give the same ranks, conditions and multipliers on both
    sides, so the T*Q algorithm's stages are the TQ ones at those points. On M_f
    each side solves its own final tangency system for lambda and the fields are
    compared at common multipliers (free multipliers given the same seeded values).

    Raises
    ------
    NotExact
        When some M_k has no exact points (a constraint neither solvable for a
        coordinate nor affine in the velocities), or the ranks at the points are not
        the algorithm's generic ones (parameter values where they drop).
    """
    from nhham.lagrangian.analysis import analyze_constraints
    from nhham.lagrangian.engine import Policy

    analysis = analyze_constraints(system, max_stages=max_stages, decompose=False,
                                   policy=Policy(samples=samples, seed=seed))
    inconsistent = analysis.status == "inconsistent"
    samplers = [ModularComparisonPoints.on(system, st.constraints, samples, seed + st.index)
                for st in analysis.stages]
    # No M_f when the run is inconsistent: the round trip, the form and the brackets of
    # the primary constraints are then checked at the points of M_1.
    if inconsistent:
        final, chis = samplers[0], tuple(system.holonomic) + tuple(system.phi)
    else:
        final = ModularComparisonPoints.on(system, analysis.final_constraints, samples, seed)
        chis = tuple(analysis.final_constraints)
    for smp in samplers + [final]:
        smp.all_points  # noqa: B018 - draws the points, or raises NotExact
    be = final.backend
    lag = NumericLagrangian(system, final.args)
    num = side.numeric
    problems, data_pairs, stages_H, dropped = _stage_data(analysis, samplers, lag, num, be)
    _, _, same_data = final.compare(data_pairs)
    if not same_data:
        problems.append("Z_i^H(chi^H), X_H(chi^H) differ from Z_i(chi), xi_L(chi) at "
                        "exact points of some M_k")
    pairs, kernel_dims, more = _pairs_on_final(system, analysis, final, lag, num, chis, seed,
                                               problems)
    dropped += more
    free = len(analysis.free_multiplier_symbols)
    if kernel_dims and kernel_dims != {free}:
        problems.append(f"{sorted(kernel_dims)} free multipliers at the points of M_f, "
                        f"{free} from the algorithm")
    if not pairs[0] and not inconsistent:
        problems.append("no generic exact point of M_f")
    checks = _checks(analysis, final, side, lag, pairs, problems, len(data_pairs) // 2, chis,
                     free)
    checks = [dataclasses.replace(c, method="points") for c in checks]
    stages_L = stage_summaries(analysis.stages)
    h_status = analysis.status if not problems else (
        "inconsistent" if inconsistent else "determined" if analysis.stages[-1].rank == system.m
        else "underdetermined")
    return (checks, stages_L, tuple(stages_H), (analysis.status, h_status),
            (len(final.all_points), dropped))


def _stage_data(analysis, samplers, lag, num, be):
    """Both sides' tangency data at the exact points of every M_k, and their ranks.

    Returns (problems, data pairs to compare, the T*Q stage summaries, points dropped).
    """
    problems, data_pairs, stages_H, dropped = [], [], [], 0
    for st, smp in zip(analysis.stages, samplers):
        seen_L, seen_H = [], []
        for pt in smp.all_points:
            vals = smp.values(pt)
            hp = num.point_from_tq(be, pt)
            tL = _tangency_L(lag, be, vals, st.constraints)
            tH = _tangency_H(num, be, hp, st.constraints)
            data_pairs += [(tL.T, tH.T), (tL.xi, tH.xi)]
            seen_L.append(_solutions(tL)[:2])
            seen_H.append(_solutions(tH)[:2])
        rank_L, rank_H = max(seen_L), max(seen_H)
        dropped += sum(1 for x in seen_L if x[0] < rank_L[0])
        stages_H.append({"index": st.index, "constraints": len(st.constraints),
                         "rank": rank_H[0], "augmented_rank": rank_H[1],
                         "labels": list(st.labels)})
        if rank_L != (st.rank, st.augmented_rank):
            # The points carry the parameter values, the algorithm's ranks are generic:
            # the values are exceptional, which the symbolic route handles.
            raise NotExact(f"stage {st.index}: ranks {rank_L[0]}/{rank_L[1]} at the points, "
                           f"{st.rank}/{st.augmented_rank} generically")
        if rank_H != rank_L:
            problems.append(f"stage {st.index}: ranks {rank_L[0]}/{rank_L[1]} (TQ) vs "
                            f"{rank_H[0]}/{rank_H[1]} (T*Q)")
    return problems, data_pairs, stages_H, dropped


def _pairs_on_final(system, analysis, final, lag, num, chis, seed, problems):
    """The pairs to compare at the points of M_f: (field, multipliers, Leg^-1, bracket),
    the kernel dimensions seen, and how many points were not generic."""
    inconsistent = analysis.status == "inconsistent"
    be, m, dropped = final.backend, system.m, 0
    # On M_f every stage's T*Q system is consistent: Leg(M_f) lies in the T*Q M_f.
    field_pairs, lam_pairs, inv_pairs, br_pairs, kernel_dims = [], [], [], [], set()
    rng = random.Random(seed + 7)
    top = analysis.stages[-1].rank
    for pt in final.all_points:
        vals = final.values(pt)
        hp = num.point_from_tq(be, pt)
        inv_pairs.append((hp.v, np.array(vals[system.n:2 * system.n], dtype=object)))
        br_pairs.append((num.bracket_matrix(be, hp, chis), lag.bracket_matrix(be, vals, chis)))
        if inconsistent:
            continue
        for st in analysis.stages:
            if _solutions(_tangency_H(num, be, hp, st.constraints))[2] is None:
                problems.append(f"stage {st.index}: the T*Q tangency equations are "
                                f"inconsistent at Leg of a point of M_f")
        tL = _tangency_L(lag, be, vals, analysis.final_constraints)
        tH = _tangency_H(num, be, hp, analysis.final_constraints)
        rL, _, lamL, kernel = _solutions(tL)
        rH, _, lamH, _ = _solutions(tH)
        if lamL is None or lamH is None or rL < top or rH < top:
            dropped += 1  # not a generic point of M_f
            continue
        kernel_dims.add(len(kernel))
        # The two sides' solutions agree when they differ by a kernel vector of T.
        lam_pairs.append((tL.T @ lamH, -tL.xi))
        lam = lamL + sum((k * ModP(rng.randrange(1, PRIME)) for k in kernel), be.zeros(m))
        field_pairs.append((lag.field(be, vals, lam), hp.X_H + hp.vertical().T @ lam))
    return (field_pairs, lam_pairs, inv_pairs, br_pairs), kernel_dims, dropped


def _checks(analysis, final, side, lag, pairs, problems, k, chis, free) -> list:
    """The CheckResults of the staged comparison."""
    field_pairs, lam_pairs, inv_pairs, br_pairs = pairs
    inconsistent = analysis.status == "inconsistent"
    checks = []
    how = "exact solves modulo p at exact points"
    checks.append(CheckResult(
        "stages", not problems, False, samples=k,
        detail="; ".join(problems) if problems else (
            f"{analysis.status} with {len(analysis.stages)} stage(s), ranks "
            f"{[st.rank for st in analysis.stages]}: Z_i^H(chi^H) and X_H(chi^H) on T*Q equal "
            f"Z_i(chi) and xi_L(chi) at {k} exact points of the M_k (so the T*Q algorithm "
            f"has the same stages, ranks and conditions there)" + (
                ", so the same inconsistency" if inconsistent else
                ", and every stage's T*Q tangency equations are consistent at Leg of the "
                "points of M_f"))))
    _, _, ok = final.compare(inv_pairs)
    checks.append(CheckResult("legendre inverse", ok, False, 0.0, 0.0, len(inv_pairs),
                              f"v -> p = dL/dv -> Leg^-1(q, p) ({how}) against v"))
    if inconsistent:
        none = ("no dynamics: the problem is inconsistent on both sides (equal stage data "
                "at the points of every M_k)" if not problems else
                "the TQ run is inconsistent and the T*Q data differ")
        checks += [CheckResult("field", not problems, False, detail=none),
                   CheckResult("multipliers", not problems, False, detail=none)]
    else:
        _, _, ok = final.compare(field_pairs)
        checks.append(CheckResult(
            "field", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
            len(field_pairs),
            f"Leg_*(xi_L + lambda^i Z_i) against X_H + lambda^i Z_i^H on M_f, lambda "
            f"solving the TQ tangency equations ({free} free multiplier(s) given the same "
            f"seeded values), by {how}"))
        _, _, ok = final.compare(lam_pairs)
        checks.append(CheckResult(
            "multipliers", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
            len(lam_pairs),
            "lambda^H (solving the T*Q tangency equations on M_f) solves the TQ ones: "
            "lambda^L - lambda^H o Leg lies in the kernel (the free multipliers)"))
    checks.append(check_form_sampled(side, final, lag))
    _, _, ok = final.compare(br_pairs)
    checks.append(CheckResult(
        "Poisson map", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
        len(br_pairs),
        f"{{f, g}} o Leg against {{Leg^* f, Leg^* g}}_L for the {len(chis)} "
        f"{'primary' if inconsistent else 'final'} constraints, by {how}"))
    return checks
