"""The Lagrangian <-> Hamiltonian cross-check, returned as a report.

Through the Legendre map (``DESIGN.md`` §2) the two descriptions must agree:

* ``"legendre inverse"``: Leg^{-1} o Leg = id;
* ``"field"``: Leg_*(P(xi_L)) = X o Leg, with X = X_H - (C^H)^{ij} X_H(phi_i^H) Z_j^H
  (for singular systems: the dynamics of the constraint algorithm on each side,
  free multipliers given the same values);
* ``"multipliers"``: lambda^L = Leg^* lambda^H;
* ``"symplectic form"``: Leg^* omega_Q = omega_L;
* ``"Poisson map"``: Leg^*{f, g} = {Leg^* f, Leg^* g}_L on the constraint functions;
* ``"stages"``: the constraint algorithm run on TQ and on T*Q (X_H, Z^H, phi^H,
  M_k in T*Q) gives the same stages: status, number of stages, ranks, labels,
  and each stage's constraints cut out the same submanifold (each side's
  constraints vanish on the other's M_k, decided on TQ after Leg^*).

Each check is decided exactly where the difference cancels (or reduces to
zero on M_f), and is in every case also evaluated at seeded points of M_f,
which gives the maximum absolute and relative differences. With
``method="points"`` or ``"sampled"`` nothing symbolic beyond derivatives is
formed: both sides are evaluated at the points (the Hamiltonian side through its
numeric layer, v = Leg^{-1}(q, p) solved at the point), which is what large
systems such as the N-link snake need; ``"points"`` does it in exact
arithmetic modulo p = 2^61 - 1 at exact points of M_1 (:mod:`nhham.lagrangian.points`),
so a difference is exactly zero or a disagreement, ``"sampled"`` in floating point.
Where C is singular, ``"points"`` compares the two constraint algorithms through their
data at exact points of every M_k (the T*Q algorithm is not run symbolically, which
would need H written with Leg^{-1}).

Agreement of a sampled quantity means |a - b| <= tol * max(1, |a|, |b|)
(infinity norms over the components) at every point; the reported relative
difference is |a - b| / max(1, |a|, |b|); the report states tol. Sample points
where a side is not finite (C singular there: outside the domain of the
dynamics) are skipped and counted in the check's detail.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import sympy as sp

from nhham.errors import InputError
from nhham.hamiltonian.checks import CheckResult, CrossCheckReport, stage_summaries
from nhham.hamiltonian.comparison import (
    ComparisonPoints,
    ModularComparisonPoints,
    NumericLagrangian,
    check_form_sampled,
    lag_C,
    modular_sampler,
)
from nhham.hamiltonian.legendre import canonical_form_matrix
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.hamiltonian.staged import staged_at_points
from nhham.lagrangian.engine import Policy, policy_of
from nhham.lagrangian.algebra import cancel, normal_form
from nhham.lagrangian.domains import NotExact
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.submanifold import Submanifold
from nhham import progress
from nhham.settings import SEED, Precision, check_options
from nhham.system.evaluation import Backend, Lambdified

__all__ = ["CheckResult", "CrossCheckReport", "cross_check", "METHODS"]

# "exact": symbolic differences; "points": both sides in exact arithmetic modulo p at
# seeded exact points of M_1; "sampled": both sides in floating point at sampled points.
METHODS = ("auto", "exact", "points", "sampled")


# ------------------------------------------------------------- the driver
def cross_check(system, precision: int | None = None, samples: int = 6, seed: int = SEED,
                tol: float | None = None, method: str = "auto",
                max_stages: int | None = None,
                side: HamiltonianSide | None = None,
                policy: Policy | None = None) -> CrossCheckReport:
    """Check that the Lagrangian and Hamiltonian sides agree through the Legendre map.

    Parameters
    ----------
    system : nhham.System
    precision, samples, seed, tol : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``, e.g. ``policy=Policy(samples=3)``.
    method : {"auto", "exact", "points", "sampled"}
        ``"exact"``: symbolic differences (cancelled, or reduced on M_f) plus
        the sampled numbers; ``"points"``: both sides evaluated in exact
        rational arithmetic at ``policy.samples`` seeded exact points of M_1 (no
        symbolic inverse, no compilation; every difference must be exactly 0,
        the tolerance is 0); ``"sampled"``: the same computations in floating
        point at sampled points. When C is singular, ``"points"`` runs the
        inverse-free constraint algorithm on TQ and compares the T*Q algorithm's
        data (Z_i^H(chi^H), X_H(chi^H)) with the TQ data at exact points of every
        M_k, then the fields on M_f; where some M_k has no exact points (a secondary
        constraint not solvable for a coordinate nor affine in the velocities), and
        for ``"sampled"``, the check falls back to ``"exact"`` (the report's
        ``method`` says so). ``"auto"``: exact when
        :attr:`HamiltonianSide.symbolic_affordable` (exact Legendre inverse and W
        diagonal, q-independent or n <= 3), else points when L is quadratic in
        v, ``policy.precision`` is None and M_1 has exact points, else sampled.
    max_stages : int, optional
        Bound of the constraint algorithm (default 2n).
    side : HamiltonianSide, optional
        The T*Q side of ``system`` when the caller has it (its numeric layer is
        built once for several checks).
    policy : Policy, optional
        Every setting of the decisions (:class:`~nhham.lagrangian.engine.Policy`): the
        precision (None: float64, else mpmath digits), the number and seed of the points
        of M_f for the numeric comparisons, the relative tolerance of sampled agreement
        (default 1e-9 in float64, 10**(3 - digits) in mpmath); default ``Policy()``.

    Returns
    -------
    CrossCheckReport

    Examples
    --------
    >>> from nhham import cross_check, models
    >>> report = cross_check(models.rolling_disk())
    >>> report.agree, report.exact, report.statuses
    (True, True, ('determined', 'determined'))
    """
    if method not in METHODS:
        raise InputError(f"cross_check: method must be one of {', '.join(map(repr, METHODS))}, "
                         f"got {method!r}")
    check_options("cross_check", max_stages=max_stages)
    policy = policy_of(policy, "cross_check", precision=precision, samples=samples, seed=seed,
                       tol=tol)
    precision, samples, seed, tol = policy.precision, policy.samples, policy.seed, policy.tol
    start = time.perf_counter()
    if side is None:
        # closed forms only where symbolic_affordable chose them
        side = hamiltonian_side(system, closed_form=True, policy=Policy(
            precision=precision, samples=samples, seed=seed))
    requested, tol_given = method, tol
    sampler = None
    if method == "auto":
        method = "exact" if side.symbolic_affordable else "sampled"
        if method == "sampled" and precision is None:
            sampler = modular_sampler(system, side, samples, seed)
            method = "points" if sampler is not None else "sampled"
    elif method == "points":
        sampler = modular_sampler(system, side, samples, seed, required=True)
    def float_sampler():
        return ComparisonPoints(system, tuple(system.holonomic) + tuple(system.phi), precision,
                        samples, seed, tol_given if tol_given is not None else
                        Backend(precision).default_tol(), exact=False)

    if method != "exact" and sampler is None:
        sampler = float_sampler()
    be = sampler.backend if sampler is not None else Backend(precision)
    tol = be.default_tol() if tol is None or method == "points" else float(tol)
    if method == "exact":
        with progress.part("cross-check: exact identities through Leg"):
            checks, stages_L, stages_H, statuses, (npts, skipped) = _exact(
                system, side, precision, samples, seed, tol, max_stages)
    else:
        try:
            with progress.part(f"cross-check at {method} points of M_1"):
                got = _sampled(system, side, sampler)
        except NotExact as exc:
            # The points are exact but a datum is not (a parameter value inside a sine):
            # floating-point samples instead, as where M_1 has no exact points.
            if requested == "points":
                raise InputError(f"cross_check: method 'points' is not available: {exc}") \
                    from None
            sampler, method = float_sampler(), "sampled"
            be = sampler.backend
            tol = be.default_tol() if tol_given is None else float(tol_given)
            got = _sampled(system, side, sampler)
        if got is None and method == "points":
            try:
                got = staged_at_points(system, side, samples, seed, max_stages)
            except (NotExact, ZeroDivisionError):
                got = None
        if got is None:
            # C is singular at the samples: stages need the symbolic algorithm.
            method, be = "exact", Backend(precision)
            tol = be.default_tol()
            with progress.part("cross-check: exact identities through Leg (C singular at the points)"):
                got = _exact(system, side, precision, samples, seed, tol, max_stages)
        checks, stages_L, stages_H, statuses, (npts, skipped) = got
    return CrossCheckReport(
        agree=all(c.agree for c in checks), exact=all(c.exact for c in checks),
        max_abs_difference=max((c.max_abs_difference for c in checks), default=0.0),
        max_rel_difference=max((c.max_rel_difference for c in checks), default=0.0),
        samples=npts, tolerance=tol, precision=be.label, method=method, checks=tuple(checks),
        lagrangian_stages=stages_L, hamiltonian_stages=stages_H, statuses=statuses,
        seconds=time.perf_counter() - start, skipped_points=skipped)


# ---------------------------------------------------------------- exact
def _exact(system, side: HamiltonianSide, precision, samples, seed, tol, max_stages):
    from nhham.lagrangian.analysis import analyze_constraints

    leg = side.legendre
    analysis = analyze_constraints(system, max_stages=max_stages, decompose=False,
                                   policy=Policy(precision=precision, samples=samples,
                                                 seed=seed))
    run_H = side.analysis(max_stages)
    stages_L, stages_H = stage_summaries(analysis.stages), stage_summaries(run_H.stages)
    statuses = (analysis.status, run_H.status)
    checks = [_check_stages(system, side, analysis, run_H)]
    final = analysis.final_constraints if analysis.status != "inconsistent" else (
        tuple(system.holonomic) + tuple(system.phi))
    sampler = ComparisonPoints(system, final, precision, samples, seed, tol)
    checks.append(_check_inverse_exact(side, sampler))
    free = tuple(analysis.free_multiplier_symbols)
    if analysis.status == "inconsistent" or run_H.status == "inconsistent":
        checks.append(CheckResult("field", analysis.status == run_H.status, True,
                                  detail="no dynamics: the problem is inconsistent on both "
                                         "sides" if analysis.status == run_H.status else
                                  "one side is inconsistent and the other is not"))
    else:
        if analysis.regular and not free and len(analysis.stages) == 1:
            checks += _regular_exact(system, side, sampler)
        else:
            lhs = leg.flow_map(analysis.dynamics)
            rhs = run_H.dynamics.applyfunc(leg.pullback)
            keys = sorted(analysis.multipliers, key=lambda s: s.name)
            lamL = sp.Matrix([analysis.multipliers[k] for k in keys])
            lamH = sp.Matrix([run_H.multipliers.get(k, sp.nan) for k in keys]).applyfunc(
                leg.pullback)
            what = ("Leg_* of the TQ algorithm's dynamics against the T*Q algorithm's dynamics "
                    "o Leg (free multipliers " + (", ".join(map(str, free)) or "none") + ")")
            checks.append(_compare_exact("field", lhs, rhs, sampler, free, what))
            checks.append(_compare_exact("multipliers", lamL, lamH, sampler, free,
                                         "lambda^L against Leg^* lambda^H"))
    checks.append(_check_form(side, sampler))
    chis_H = tuple(run_H.final_constraints) if run_H.status != "inconsistent" else (
        side.holonomic + side.constraints)
    checks.append(_check_poisson_exact(side, chis_H, sampler))
    return checks, stages_L, stages_H, statuses, (len(sampler.points), sampler.dropped)


def _identity(lhs, rhs, tq_everywhere) -> tuple[bool, bool, list]:
    """Is lhs - rhs = 0 on all of TQ? (holds, exact, decisions).

    Where a difference has a float in it (a decimal written in L, 0.5, and what sympy
    made of it, exp(0.125)) the two sides are compared at the sample points, relative to
    their size: the rounding cancels nothing exactly, and leaves 1e-16 exp(t) where the
    sides are (theta', 1e-16 exp(t)) and (theta', 0).
    """
    lhs, rhs = sp.Matrix(lhs), sp.Matrix(rhs)
    diff = (lhs - rhs).applyfunc(cancel)
    if any(d.has(sp.Float) for d in diff):
        decisions = [_equal_at_points(lhs, rhs, tq_everywhere)]
    else:
        decisions = [tq_everywhere.vanishes(d) for d in diff if d != 0]
    return (all(d.value for d in decisions), all(d.method == "exact" for d in decisions),
            decisions)


def _equal_at_points(lhs, rhs, manifold) -> Decision:
    """Whether the matrices ``lhs`` and ``rhs`` are equal at the sample points of
    ``manifold``, relative to the larger of the two there (a sampled Decision)."""
    points, values = manifold.finite_values([lhs, rhs])
    worst = 0.0
    for left, right in values:
        a, b = (np.asarray(x, dtype=complex) for x in (left, right))
        size = max(np.abs(a).max(initial=0.0), np.abs(b).max(initial=0.0))
        worst = max(worst, float(np.abs(a - b).max(initial=0.0)) / size if size else 0.0)
    precision = Precision(manifold.precision)
    return Decision(worst <= precision.tolerance, "sampled",
                    f"equal at {len(points)} seeded points to {worst:.3g} relative (decimals "
                    f"in the expressions: their rounding cancels nothing exactly)",
                    precision=precision.label, samples=len(points), max_abs=worst)


def _regular_exact(system, side, sampler) -> list:
    """Field and multipliers of a regular system: exact ingredients, numeric assembly.

    P(xi_L) = xi_L + lambda^j Z_j with (C^T) lambda = -xi_L(phi), and likewise on
    T*Q. So Leg_*(P(xi_L)) = X o Leg and lambda^L = lambda^H o Leg follow exactly
    from four identities on TQ, each free of C^{-1}: Leg_* xi_L = X_H o Leg,
    Leg_* Z_j = Z_j^H o Leg, C = C^H o Leg and xi_L(phi_i) = X_H(phi_i^H) o Leg.
    The assembled field and multipliers are compared at the sample points
    (numeric solves on both sides).
    """
    leg = side.legendre
    geo = lagrangian_geometry(system)
    pull = leg.pullback
    everywhere = Submanifold(system, (), precision=side.precision, samples=side.samples,
                             seed=side.seed)
    parts = [
        ("Leg_* xi_L" + (" + dLeg/dt" if system.lagrangian_depends_on_time else "")
         + " = X_H o Leg", leg.flow_map(geo.euler_lagrange_field),
         side.X_H.applyfunc(pull)),
        ("Leg_* Z_j = Z_j^H o Leg",
         sp.Matrix.hstack(*[leg.tangent_map(geo.vertical_fields.row(j).T)
                            for j in range(system.m)]) if system.m else sp.zeros(0, 1),
         (side.vertical_fields.T if system.is_affine  # Z^H in p only for Chetaev's rule
          else side.vertical_fields.T.applyfunc(pull)) if system.m else sp.zeros(0, 1)),
    ]
    lam_parts = [
        ("C = C^H o Leg", geo.constraint_matrix, side.constraint_matrix.applyfunc(pull)),
        ("xi_L(phi) = X_H(phi^H) o Leg", geo.constraint_derivatives,
         side.constraint_derivatives.applyfunc(pull)),
    ]
    field_pairs, lam_pairs = _numeric_assembly(system, side, sampler)
    out = []
    for name, group, pairs, what in (
            ("multipliers", lam_parts, lam_pairs, "lambda^L against lambda^H o Leg"),
            ("field", parts + lam_parts, field_pairs,
             f"Leg_*(P({_field_name(system)})) against X o Leg")):
        holds, exact, decisions, names = True, True, [], []
        for label, lhs, rhs in group:
            h, e, d = _identity(lhs, rhs, everywhere)
            holds, exact = holds and h, exact and e
            decisions += d
            names.append(label + ("" if h else " FAILS"))
        ab, rel, ok = sampler.compare(pairs)
        out.append(CheckResult(
            name, holds and ok, exact, ab, rel, len(pairs),
            f"{what}: exact identities on TQ ({'; '.join(names)}), assembled values compared "
            f"at the sample points{sampler.note()}", tuple(decisions)))
    return out[::-1]


def _numeric_assembly(system, side, sampler):
    """(field pairs, multiplier pairs) from the numeric layers at the sample points."""
    be = sampler.backend
    lag = NumericLagrangian(system, sampler.args)
    num = side.numeric
    field_pairs, lam_pairs = [], []
    with be.context():
        for pt in sampler.points:
            vals = sampler.values(pt)
            hp = num.point_from_tq(be, pt)
            try:
                fL, lamL, _ = lag.projected(be, vals)
                XH, lamH = num.projected_field(be, hp)
            except (np.linalg.LinAlgError, ZeroDivisionError):
                continue
            field_pairs.append((fL, XH))
            lam_pairs.append((lamL, lamH))
    return field_pairs, lam_pairs


def _split_free(expr, free):
    """Coefficients of an expression affine in the free multipliers (constant term first)."""
    if not free or not (sp.sympify(expr).free_symbols & set(free)):
        return [expr]
    expr = sp.expand(expr)
    parts = [expr.xreplace({s: 0 for s in free})]
    for s in free:
        parts.append(sp.diff(expr, s))
    return parts


def _compare_exact(name, lhs, rhs, sampler: ComparisonPoints, free, what) -> CheckResult:
    lhs, rhs = sp.Matrix(lhs), sp.Matrix(rhs)
    if lhs.shape != rhs.shape or any(e.has(sp.nan) for e in rhs):
        return CheckResult(name, False, True, detail=f"{what}: the two sides have different "
                                                     f"shapes or unknowns")
    diff = (lhs - rhs).applyfunc(cancel)
    decisions, residue = [], []
    M = sampler.manifold
    for i, d in enumerate(diff):
        if d == 0:
            continue
        for part in _split_free(d, free):
            dec = M.vanishes(part, tol=sampler.tol)
            decisions.append(dec)
            if not dec.value:
                residue.append(i)
    exact = all(dec.method == "exact" for dec in decisions)
    # Numbers at the sample points (free multipliers: the same seeded values on both sides).
    rng = np.random.default_rng(sampler.manifold.seed + 7)
    free_vals = [float(rng.uniform(-1, 1)) for _ in free]
    args = sampler.args + tuple(free)
    fl = Lambdified(args, list(lhs), (lhs.rows,))
    fr = Lambdified(args, list(rhs), (rhs.rows,))
    be = sampler.backend
    with be.context():
        pairs = [(fl(be, sampler.values(pt) + [be.scalar(x) for x in free_vals]),
                  fr(be, sampler.values(pt) + [be.scalar(x) for x in free_vals]))
                 for pt in sampler.points]
        ab, rel, ok = sampler.compare(pairs)
    agree = not residue and ok
    what = what + sampler.note()
    if all(d == 0 for d in diff):
        how = "the difference cancels identically"
    elif not residue:
        how = (f"the difference vanishes on M_f ({sum(d.method == 'exact' for d in decisions)}"
               f" exact, {sum(d.method == 'sampled' for d in decisions)} sampled decisions)")
    else:
        how = f"components {residue} of the difference do not vanish on M_f"
    return CheckResult(name, agree, exact, ab, rel, len(pairs), f"{what}: {how}",
                       tuple(decisions))


def _zero_or_not(expr):
    """``expr`` in normal form, or 0 where it cancels to 0 (coefficients in Q(e), Q(pi))."""
    form = normal_form(expr)
    return form if form == 0 or cancel(form) != 0 else sp.S.Zero


def _check_inverse_exact(side, sampler) -> CheckResult:
    leg = side.legendre
    to_p = dict(zip(leg.momentum_symbols, leg.momenta))
    # Zero modulo sin^2 + cos^2 = 1 is zero: the normal form decides it (and cancel where
    # a coefficient is an irrational number, 1/(16 e - 1), which the normal form keeps).
    back = sp.Matrix([_zero_or_not(leg.inverse[v].xreplace(to_p) - v)
                      for v in leg.velocities]) if leg.has_exact_inverse else None
    num = side.numeric
    be = sampler.backend
    with be.context():
        pairs = []
        for pt in sampler.points:
            hp = num.point_from_tq(be, pt)
            pairs.append((hp.v, be.vector([pt[s] for s in side.system.velocities])))
        ab, rel, ok = sampler.compare(pairs)
    if back is None:
        return CheckResult("legendre inverse", ok, False, ab, rel, len(pairs),
                           leg.inverse_statement + "; round trip checked numerically")
    exact_ok = all(e == 0 for e in back)
    # The normal form decides zero for rational functions of v with exact coefficients
    # (modulo sin^2 + cos^2 = 1): a linear inverse that does not cancel is wrong. A
    # closed-form branch has radicals, (x + sqrt(x^2 + 1))^(1/3) and the like, and a
    # written decimal (0.5) is a float whose rounding cancels nothing exactly: there the
    # values at the points decide.
    proved_wrong = (not exact_ok and leg.inverse_kind == "linear"
                    and not any(e.has(sp.Float) for e in back))
    return CheckResult("legendre inverse", ok and not proved_wrong, exact_ok, ab, rel,
                       len(pairs), f"Leg^-1 o Leg = id ({leg.inverse_kind} inverse): "
                       + ("cancels identically" if exact_ok else
                          f"residual {list(back)}" if proved_wrong else
                          "radicals or decimals do not cancel symbolically; the round trip "
                          "agrees at the points" if ok else f"residual {list(back)}"))


def _check_form(side, sampler) -> CheckResult:
    """Leg^* omega_Q against omega_L (exact: J^T Omega_Q J - Omega_L expands to 0)."""
    leg = side.legendre
    geo = lagrangian_geometry(side.system)
    pulled = leg.pullback_form(canonical_form_matrix(side.n))
    omega_L = geo.poincare_cartan_2form
    diff = (pulled - omega_L).applyfunc(sp.expand)
    exact_ok = all(e == 0 for e in diff)
    n2 = 2 * side.n
    fp = Lambdified(sampler.args, list(pulled), (n2, n2))
    fo = Lambdified(sampler.args, list(omega_L), (n2, n2))
    be = sampler.backend
    with be.context():
        pairs = [(fp(be, sampler.values(pt)), fo(be, sampler.values(pt)))
                 for pt in sampler.points]
        ab, rel, ok = sampler.compare(pairs)
    return CheckResult("symplectic form", exact_ok and ok, exact_ok, ab, rel, len(pairs),
                       "Leg^* omega_Q = J^T Omega_Q J against omega_L: "
                       + ("the difference expands to 0" if exact_ok else "they differ"))


def _check_poisson_exact(side, chis_H, sampler) -> CheckResult:
    """Leg^*{f, g} against {Leg^* f, Leg^* g}_L for the final constraints f, g in (q, p)."""
    leg = side.legendre
    geo = lagrangian_geometry(side.system)
    k = len(chis_H)
    pairs_idx = [(a, b) for a in range(k) for b in range(a + 1, k)]
    lhs = sp.Matrix([leg.pullback(side.algebra.bracket(chis_H[a], chis_H[b]))
                     for a, b in pairs_idx]) if pairs_idx else sp.zeros(0, 1)
    pulled = [leg.pullback(c) for c in chis_H]
    rhs = sp.Matrix([geo.bracket(pulled[a], pulled[b]) for a, b in pairs_idx]) \
        if pairs_idx else sp.zeros(0, 1)
    if not pairs_idx:
        return CheckResult("Poisson map", True, True,
                           detail="fewer than two constraint functions: nothing to compare")
    diff = (lhs - rhs).applyfunc(cancel)
    everywhere = Submanifold(side.system, (), precision=sampler.manifold.precision,
                             samples=sampler.manifold.samples, seed=sampler.manifold.seed)
    decisions = [everywhere.vanishes(d, tol=sampler.tol) for d in diff if d != 0]
    exact = all(d.method == "exact" for d in decisions)
    fl = Lambdified(sampler.args, list(lhs), (lhs.rows,))
    fr = Lambdified(sampler.args, list(rhs), (rhs.rows,))
    be = sampler.backend
    with be.context():
        nums = [(fl(be, sampler.values(pt)), fr(be, sampler.values(pt)))
                for pt in sampler.points]
        ab, rel, ok = sampler.compare(nums)
    agree = all(d.value for d in decisions) and ok
    how = ("cancels identically" if not decisions else
           f"{sum(bool(d.value) for d in decisions)} of {len(decisions)} non-cancelling "
           f"differences vanish on TQ")
    return CheckResult("Poisson map", agree, exact, ab, rel, len(nums),
                       f"Leg^*{{f, g}} against {{Leg^* f, Leg^* g}}_L for the "
                       f"{len(pairs_idx)} pairs of the {k} final constraints: {how}",
                       tuple(decisions))


def _check_stages(system, side, analysis, run_H) -> CheckResult:
    """Same status, stages, ranks, labels, and the same M_k on both sides."""
    leg = side.legendre
    problems, decisions = [], []
    if analysis.status != run_H.status:
        problems.append(f"status {analysis.status} (TQ) vs {run_H.status} (T*Q)")
    if len(analysis.stages) != len(run_H.stages):
        problems.append(f"{len(analysis.stages)} stages (TQ) vs {len(run_H.stages)} (T*Q)")
    if len(analysis.free_multiplier_symbols) != len(run_H.free_multiplier_symbols):
        problems.append(f"{len(analysis.free_multiplier_symbols)} free multipliers (TQ) vs "
                        f"{len(run_H.free_multiplier_symbols)} (T*Q)")
    for sL, sH in zip(analysis.stages, run_H.stages):
        k = sL.index
        if (sL.rank, sL.augmented_rank) != (sH.rank, sH.augmented_rank):
            problems.append(f"stage {k}: ranks {sL.rank}/{sL.augmented_rank} (TQ) vs "
                            f"{sH.rank}/{sH.augmented_rank} (T*Q)")
        if tuple(sL.labels) != tuple(sH.labels):
            problems.append(f"stage {k}: labels {list(sL.labels)} (TQ) vs {list(sH.labels)}")
        pulled = tuple(leg.pullback(c) for c in sH.constraints)
        ML = Submanifold(system, sL.constraints, precision=side.precision,
                         samples=side.samples, seed=side.seed)
        MH = Submanifold(system, pulled, precision=side.precision, samples=side.samples,
                         seed=side.seed)
        for c in pulled:
            d = ML.vanishes(c)
            decisions.append(d)
            if not d.value:
                problems.append(f"stage {k}: Leg^*({c}) does not vanish on the TQ M_{k}")
        for c in sL.constraints:
            d = MH.vanishes(c)
            decisions.append(d)
            if not d.value:
                problems.append(f"stage {k}: {c} does not vanish on Leg^{-1}(M_{k} of T*Q)")
    exact = all(d.method == "exact" for d in decisions)
    summary = (f"{analysis.status} with {len(analysis.stages)} stage(s), ranks "
               f"{[s.rank for s in analysis.stages]} on both sides; every stage's constraints "
               f"vanish on the other side's M_k")
    return CheckResult("stages", not problems, exact,
                       detail="; ".join(problems) if problems else summary,
                       decisions=tuple(decisions))


def _field_name(system) -> str:
    """xi_L, or xi_L + F^v when the system has forces (X then includes F^V)."""
    return "xi_L + F^v" if system.has_forces else "xi_L"


def _sampled(system, side: HamiltonianSide, sampler):
    """Checks at points of M_1 for a regular system, in floating point or (an
    :class:`ModularComparisonPoints`) exactly; None when C is singular there."""
    primary = tuple(system.holonomic) + tuple(system.phi)
    exactly = isinstance(sampler, ModularComparisonPoints)
    how = "exact solves modulo p" if exactly else "numeric solves"
    be = sampler.backend
    lag = NumericLagrangian(system, sampler.args)
    num = side.numeric
    field_pairs, lam_pairs, inv_pairs, br_pairs = [], [], [], []
    ranks_L, ranks_H = [], []
    m = system.m
    with be.context():
        for pt in sampler.points:
            vals = sampler.values(pt)
            hp = num.point_from_tq(be, pt)
            inv_pairs.append((hp.v, np.array(vals[system.n:2 * system.n])))
            ranks_L.append(sampler.rank(lag_C(lag, be, vals)))
            ranks_H.append(sampler.rank(hp.C))
            if ranks_L[-1] < m or ranks_H[-1] < m:
                continue
            fL, lamL, _ = lag.projected(be, vals)
            XH, lamH = num.projected_field(be, hp)
            field_pairs.append((fL, XH))
            lam_pairs.append((lamL, lamH))
            if primary:
                br_pairs.append((num.bracket_matrix(be, hp, primary),
                                 lag.bracket_matrix(be, vals, primary)))
    # The generic rank is the largest seen; a point where C drops rank is a
    # non-generic point of M_1 (outside the domain of the dynamics) and is skipped.
    regular = ranks_L and max(ranks_L) == m and max(ranks_H) == m and field_pairs
    if not regular:
        return None
    dropped = sum(1 for a, b in zip(ranks_L, ranks_H) if a < m or b < m)
    skip = (f"; {dropped} sample point(s) where C drops rank skipped" if dropped else "")
    checks = []
    stage = {"index": 1, "constraints": len(primary), "rank": m, "augmented_rank": m,
             "labels": list(system.m1_labels)}
    same = ranks_L == ranks_H
    checks.append(CheckResult(
        "stages", same, False,
        detail=(f"C (TQ) and C^H (T*Q) have the generic rank {m} at the seeded points of M_1 "
                f"on both sides (ranks {ranks_L}): one stage, determined, no free multipliers"
                if same else f"numeric ranks differ: TQ {ranks_L}, T*Q {ranks_H}")))
    ab, rel, ok = sampler.compare(inv_pairs)
    checks.append(CheckResult("legendre inverse", ok, False, ab, rel, len(inv_pairs),
                              f"v -> p = dL/dv -> Leg^-1(q, p) ({how}) against v"))
    ab, rel, ok = sampler.compare(field_pairs)
    checks.append(CheckResult("field", ok, False, ab, rel, len(field_pairs),
                              f"Leg_*(P({_field_name(system)})) against X o Leg, both by "
                              f"{how}" + skip))
    ab, rel, ok = sampler.compare(lam_pairs)
    checks.append(CheckResult("multipliers", ok, False, ab, rel, len(lam_pairs),
                              "lambda^L against lambda^H o Leg"))
    checks.append(check_form_sampled(side, sampler, lag))
    ab, rel, ok = sampler.compare(br_pairs)
    checks.append(CheckResult(
        "Poisson map", ok, False, ab, rel, len(br_pairs),
        f"{{f, g}} o Leg against {{Leg^* f, Leg^* g}}_L for the {len(primary)} constraint "
        f"functions, by {how}"))
    if exactly:
        checks = [dataclasses.replace(c, method="points") for c in checks]
    stages = (stage,)
    return checks, stages, stages, ("determined", "determined"), (len(sampler.points),
                                                                  sampler.dropped)


