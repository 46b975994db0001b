"""The first/second-class split read off the bracket matrix at floating-point points.

The bracket matrix B_ab = {chi_a, chi_b} at seeded points of M_f (numbers from the
numeric layer, or the Lagrangian bracket at float points): its rank from singular
values, a principal second-class set R with B_RR invertible, and the coefficients
of the first-class combinations at the points.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from nhham.errors import ComputationError
from nhham.hamiltonian.brackets import connected_blocks
from nhham.hamiltonian.classes import ConstraintClasses
from nhham.lagrangian.decision import Decision

__all__ = ["classes_from_samples", "principal_pivots"]


def principal_pivots(Br: sp.Matrix, samples, r: int, tol, nonzero=None) -> list:
    """A principal index set R, |R| = r, with B_RR invertible (grown two at a time).

    Invertibility is read off the samples; where they cannot show it (the parameter
    values put every sample on the exceptional set of a generic decision), ``nonzero``
    decides det B_RR exactly, as the generic rank was decided."""
    if r == 0:
        return []
    k = Br.rows
    exact = not Br.free_symbols
    tol = 1e-9 if tol is None else tol

    # Only samples where B has its generic rank r decide (Newton projection can
    # land on a singular set, e.g. the snakeboard at phi = +-pi/2).
    def generic_rank(S):
        s = np.linalg.svd(S, compute_uv=False)
        return int(sum(x > tol * max(np.abs(S).max(), 1.0) for x in s))

    samples = [S for S in samples if generic_rank(S) == r] or list(samples)

    def invertible(idx):
        if exact:
            return Br.extract(idx, idx).rank() == len(idx)
        for S in samples:
            sub = S[np.ix_(idx, idx)]
            s = np.linalg.svd(sub, compute_uv=False)
            scale = max(np.abs(S).max(), 1.0)
            if s[-1] <= tol * scale:
                return False
        return True

    R: list = []
    while len(R) < r:
        grown = False
        for a in range(k):
            if a in R:
                continue
            for b in range(a + 1, k):
                if b in R:
                    continue
                trial = sorted(R + [a, b])
                if invertible(trial):
                    R = trial
                    grown = True
                    break
            if grown:
                break
        if not grown and nonzero is not None:
            found = next((sorted(R + [a, b]) for a in range(k) for b in range(a + 1, k)
                          if a not in R and b not in R
                          and nonzero(Br.extract(sorted(R + [a, b]), sorted(R + [a, b])).det())),
                         None)
            if found is not None:
                R, grown = found, True
        if not grown:
            raise ComputationError(
                f"classification: no principal {len(R) + 2}x{len(R) + 2} block of the bracket "
                f"matrix is invertible at the samples although its rank on M_f is {r}")
    return R


def classes_from_samples(side, cons_tq, labels, analysis, mats, be, tol, resid, what):
    """ConstraintClasses from the bracket matrix B at seeded points of M_f."""
    k = len(cons_tq)
    points = mats
    tol_ = be.default_tol() if tol is None else tol
    fmats = [np.array(S, dtype=float) for S in mats]
    ranks, svals = [], []
    for S in mats:
        s = _svals(S, be)
        svals.append(tuple(float(x) for x in s))
        top = max(float(s[0]) if len(s) else 0.0, 1.0)
        ranks.append(int(sum(float(x) > tol_ * top for x in s)))
    r = max(ranks) if ranks else 0
    warnings = []
    if len(set(ranks)) > 1:
        warnings.append(f"rank is not constant on M_f: ranks {ranks} at the samples")
    decisions = {"rank": Decision(
        r, "sampled", f"rank {r} of {what} at {len(points)} seeded points "
                      f"of M_f (relative tolerance {tol_:g})",
        precision=be.label, samples=len(points), singular_values=tuple(svals),
        point_residual=resid, warnings=tuple(warnings))}
    scale = max([np.abs(S).max() for S in fmats] + [1.0])
    nonzero = np.zeros((k, k), dtype=bool)
    for S in fmats:
        nonzero |= np.abs(S) > tol_ * scale
    R = principal_pivots(sp.Matrix(k, k, lambda a, b: sp.Symbol("b")), fmats, r, tol_) \
        if r else []
    coeff_dicts = []
    for kk in (i for i in range(k) if i not in R):
        per_point = []
        worst = 0.0
        for S in mats:
            c = be.zeros(k)
            c[kk] = be.scalar(1)
            if R:
                cR = -be.solve(S[np.ix_(R, R)], S[np.ix_(R, [kk])].reshape(len(R)))
                for i, a in enumerate(R):
                    c[a] = cR[i]
            worst = max(worst, float(be.norm(S @ c)))
            per_point.append(c)
        coeff_dicts.append({labels[a]: tuple(float(c[a]) for c in per_point)
                            for a in range(k) if any(c[a] != 0 for c in per_point)})
        decisions[f"gamma[{labels[kk]}]"] = Decision(
            worst <= tol_ * scale, "sampled",
            f"largest |B c| {worst:.3g} at {len(points)} seeded points of M_f",
            precision=be.label, samples=len(points), max_abs=worst, point_residual=resid)
    alone = tuple(labels[a] for a in range(k) if not nonzero[a].any())
    blocks = tuple(tuple(labels[a] for a in blk) for blk in connected_blocks(nonzero)) if k else ()
    return ConstraintClasses(
        labels=tuple(labels), constraints_TQ=cons_tq, constraints=None, bracket_matrix=None,
        bracket_samples=tuple(fmats), rank=r, first_class=k - r, second_class=r,
        second_class_set=tuple(labels[a] for a in R), first_class_combinations=None,
        combination_coefficients=tuple(coeff_dicts), individually_first_class=alone,
        blocks=blocks, decisions=decisions, method="sampled", manifold=None, side=side,
        analysis=analysis)


def _svals(S, be):
    if be.precision is None:
        return np.linalg.svd(np.asarray(S, dtype=float), compute_uv=False) if S.size else []
    import mpmath
    with mpmath.workdps(be.precision):
        A = mpmath.matrix(S.tolist())
        if not S.size:
            return []
        return sorted((abs(x) for x in mpmath.svd_r(A, compute_uv=False)), reverse=True)
