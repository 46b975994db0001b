"""First- and second-class final constraints, the Dirac bracket, Dirac vs projected.

Conventions (``DESIGN.md`` §2): the final constraints chi_a (a = 1..k) of M_f
are transported to T*Q (chi_a o Leg^{-1}); B_ab = {chi_a, chi_b} with the
canonical bracket. On M_f:

* rank B = r is the number of second-class constraints (B is antisymmetric,
  so r is even), k - r the number of first-class ones;
* a *maximal second-class set* is an index set R (|R| = r) with B_RR
  invertible on M_f; one always exists among principal submatrices, and it is
  grown two indices at a time (if B_RR is invertible and rank B > |R|, the
  Schur complement of B_RR is a nonzero antisymmetric matrix, so some pair
  (a, b) has S_ab != 0, and det B_{R+ab} = det B_RR S_ab^2);
* every index k outside R gives a first-class combination
  gamma_k = chi_k - sum_{a in R} (B_RR^{-1} B_Rk)_a chi_a, which brackets to
  zero with every chi on M_f (rows in R by construction, the others because
  rank B = |R|). These k - r combinations are independent (each has its own
  unit coefficient) and are reported as expressions in (q, p); a constraint
  may be second class on its own while such a combination of several is first
  class.

Decisions on M_f follow the rule of :mod:`nhham.lagrangian.submanifold` (exact reduction
first, seeded sampling second), each recorded as a Decision.

The Dirac bracket {f, g}_D = {f, g} - {f, chi_a} (B^{-1})^{ab} {chi_b, g} is
taken over the second-class set, block by block
(:class:`nhham.hamiltonian.brackets.DiracBracket`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence, cast

import numpy as np
import sympy as sp

from nhham.errors import ComputationError, InputError
from nhham.hamiltonian.brackets import connected_blocks
from nhham.hamiltonian.classes import ConstraintClasses
from nhham.hamiltonian.classes_sampled import classes_from_samples, principal_pivots
from nhham.hamiltonian.classes_at_points import (
    BracketRank,
)
from nhham.hamiltonian.combinations import NotFormed, OutOfTime, closed_form_combinations
from nhham.hamiltonian.reduced_combinations import reduced_combinations
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.lagrangian.algebra import block_inverse, cancel
from nhham.lagrangian.analysis import ConstraintAnalysis, analyze_constraints
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.engine import Policy, decide, policy_of
from nhham.lagrangian.domains import NotExact
from nhham.lagrangian.linalg import ModularBackend, exact_rank
from nhham.lagrangian.points import PointSampler
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED, check_options
from nhham.system.evaluation import Backend, Lambdified

#: A coefficient in (q, p) whose numerator has more terms than this is formed reduced on
#: M_f instead (:func:`_combinations`).
COEFFICIENT_TERMS = 300

__all__ = [
    "classify_constraints",
    "classify_on",
    "final_constraints_of",
]


# ---------------------------------------------------------------- inputs
def final_constraints_of(source, policy: Policy | None = None):
    """(system, final constraints on TQ, labels, analysis) for a source.

    Parameters
    ----------
    source : System, HamiltonianSide or ConstraintAnalysis
        A system (or a side, for its system) runs the constraint algorithm
        (:func:`nhham.lagrangian.analysis.analyze_constraints` with this policy); an
        analysis is used as it is.
    policy : Policy, optional

    Raises
    ------
    ComputationError
        When the analysis is inconsistent: there is no M_f to classify on.
    """
    if isinstance(source, HamiltonianSide):
        source = source.system
    analysis = source if isinstance(source, ConstraintAnalysis) else analyze_constraints(
        source, policy=policy or Policy())
    if analysis.status == "inconsistent":
        raise ComputationError(
            f"classify: the constraint algorithm found no dynamics (inconsistent: "
            f"{analysis.inconsistency}); there is no M_f to classify on")
    cons = tuple(sp.sympify(c) for c in analysis.final_constraints)
    return analysis.system, cons, tuple(analysis.final_labels), analysis


def _is_on_tq(expr, system):
    return bool(sp.sympify(expr).free_symbols & set(system.velocities))


# ------------------------------------------------------------ classify
def classify_constraints(source, constraints: Sequence | None = None,
                         labels: Sequence[str] | None = None, *, precision: int | None = None,
                         samples: int = 6, seed: int = SEED, method: str = "auto",
                         tol: float | None = None,
                         policy: Policy | None = None) -> ConstraintClasses:
    """Classify the final constraints of a system into first and second class.

    Parameters
    ----------
    source : System, HamiltonianSide or ConstraintAnalysis
    constraints : sequence of sympy.Expr, optional
        The final constraints, given directly: functions of (q, v) (they are
        transported by Leg^{-1}) or of (q, p). Default: from the constraint
        algorithm (or M_1 when the algorithm is unavailable).
    labels : sequence of str, optional
        Names of ``constraints`` (default ``chi[a]``).
    precision : int or None
        None for float64 sampling, an integer for mpmath digits.
    samples, seed : int
        Sample points of sampled decisions.
    method : {"auto", "exact", "sampled"}
        ``"exact"``: symbolic brackets reduced on M_f, exact decisions where
        they exist, sampled otherwise; ``"sampled"``: numeric brackets at seeded
        points of M_f only (no symbolic Legendre inverse); ``"auto"``: exact
        when :attr:`HamiltonianSide.symbolic_affordable`, otherwise at exact
        points of M_f when M_f = M_1 has them (proofs, or Schwartz–Zippel
        bounds), sampled as the last resort.
    tol : float, optional
        Relative tolerance of sampled decisions (default 1e-9 / 10**(3-digits)).
    policy : Policy, optional
        All the settings of the decisions in one object, instead of ``precision``,
        ``samples``, ``seed`` and ``tol``.

    Returns
    -------
    ConstraintClasses

    Examples
    --------
    The Cartesian pendulum: g = x**2 + y**2 - l**2 and its lift are second class, by hand
    {g, g^c} = 2 x (2 x / m) + 2 y (2 y / m).

    >>> from nhham import classify_constraints, models
    >>> classes = classify_constraints(models.pendulum_cartesian())
    >>> classes.second_class, classes.first_class
    (2, 0)
    >>> classes.bracket_matrix
    Matrix([
    [                    0, (4*x**2 + 4*y**2)/m],
    [-(4*x**2 + 4*y**2)/m,                    0]])
    """
    if method not in ("auto", "exact", "sampled"):
        raise InputError(f"classify: method must be 'auto', 'exact' or 'sampled', got {method!r}")
    check_options("classify_constraints", precision=precision, samples=samples, seed=seed,
                  tol=tol)
    policy = policy_of(policy, "classify_constraints", precision=precision, samples=samples,
                       seed=seed, tol=tol)
    precision, samples, seed, tol = policy.precision, policy.samples, policy.seed, policy.tol
    side_in = source if isinstance(source, HamiltonianSide) else None
    system = source.system if isinstance(source, HamiltonianSide) else getattr(
        source, "system", source)
    side = side_in if side_in is not None else hamiltonian_side(
        system, policy=Policy(precision=precision, samples=samples, seed=seed))
    requested = method
    if method == "auto":
        method = "exact" if _exact_affordable(side) else "sampled"
    if constraints is None:
        if method == "sampled" and not isinstance(source, ConstraintAnalysis) \
                and _numerically_regular(side, precision, samples, seed, tol):
            # C has full rank at the samples of M_1: M_f = M_1, no symbolic algorithm run.
            cons, labs, analysis = (tuple(system.holonomic) + tuple(system.phi),
                                    system.m1_labels, None)
        else:
            system, cons, labs, analysis = final_constraints_of(source, policy)
    else:
        cons = tuple(sp.sympify(c) for c in constraints)
        labs = tuple(labels) if labels is not None else tuple(f"chi[{a}]" for a in range(len(cons)))
        analysis = None if source is system or source is side_in else source
    if len(labs) != len(cons):
        raise InputError(f"classify: {len(labs)} labels for {len(cons)} constraints")
    if method == "exact":
        return _classify_exact(side, cons, labs, analysis, tol)
    if requested == "auto" and set(cons) == set(system.holonomic) | set(system.phi):
        # M_f = M_1: the brackets can be decided at exact points of M_1.
        classes = decide(BracketRank(side, cons, labs, analysis, policy),
                         Submanifold(system, cons, precision=precision, samples=samples,
                                     seed=seed), policy)
    else:
        classes = _classify_sampled(side, cons, labs, analysis, tol, precision, samples, seed)
    return _with_combinations(classes, policy)


def _with_combinations(classes: ConstraintClasses, policy: Policy) -> ConstraintClasses:
    """``classes`` (decided at points) with its first-class combinations in closed form.

    The rank and the maximal second-class set R were decided at points of M_f;
    the combinations gamma_k = chi_k - sum_{a in R} (B_RR^{-1} B_Rk)_a chi_a
    follow from the entries of B_RR and B_Rk by polynomial arithmetic
    (:func:`nhham.hamiltonian.combinations.closed_form_combinations`), with their
    coefficients as ``combination_coefficients``. Where that is not possible
    the combinations stay None and a ``"combinations"`` decision says why (with
    a warning); the coefficients at the points remain.
    """
    if classes.first_class == 0 or classes.first_class_combinations is not None:
        return classes
    system = classes.side.system
    size = policy.combination_size
    why = f"n = {system.n} > {size}" if system.n > size else ""
    if not why:
        try:
            gammas, coeffs = _combinations(system, classes.constraints_TQ,
                                           classes.second_class_indices)
        except NotFormed as exc:
            why = str(exc)
    if why:
        note = (f"first-class combinations not formed in closed form ({why}); their "
                f"coefficients at the points are in combination_coefficients")
        decision = Decision(False, classes.method, note, warnings=(note,))
        return replace(classes, decisions={**classes.decisions, "combinations": decision})
    labels = classes.labels
    decision = Decision(True, "exact", "first-class combinations formed in closed form from "
                        "the entries of B_RR and B_Rk (R decided at points)")
    return replace(classes, first_class_combinations=gammas,
                   combination_coefficients=tuple({labels[a]: c for a, c in d.items()}
                                                  for d in coeffs),
                   decisions={**classes.decisions, "combinations": decision})


#: Largest n for which the coefficients are reduced on M_f: the reduction forms
#: delta W^-1 symbolically, which past n = 6 (a 5-link snake, n = 7: minutes) costs more
#: than the closed form it would shorten.
REDUCED_MAX_N = 6


def _combinations(system, constraints, second_class) -> tuple:
    """(gammas, coefficients): in (q, p) from the brackets of the transported constraints
    while their coefficients stay small; else with the coefficients reduced on M_f (the
    segway: 56,000 characters against 400); else the first way without a size bound."""
    try:
        return closed_form_combinations(system, constraints, second_class,
                                        max_coefficient_terms=COEFFICIENT_TERMS)
    except OutOfTime:
        raise   # the last way takes the same steps: it would run out of time too
    except NotFormed:
        pass
    if system.n <= REDUCED_MAX_N:
        try:
            return reduced_combinations(system, constraints, second_class)
        except NotFormed:
            pass
    return closed_form_combinations(system, constraints, second_class)


def _numerically_regular(side, precision, samples, seed, tol) -> bool:
    """C^H has full rank m on M_1: proved at an exact point modulo p when M_1 has exact
    points and L is quadratic in v (rank C^H can only drop under reduction mod p, so
    full rank there is full generic rank); else at every seeded point (numeric layer)."""
    system = side.system
    if not system.m:
        return True
    if precision is None and side.legendre.is_quadratic:
        try:
            sampler = PointSampler.on_M1(system, seed, modular=True)
            mod = ModularBackend()
            for _ in range(3):
                C = side.numeric.point_from_tq(mod, sampler.point().env).C
                if exact_rank([list(row) for row in C])[0] == system.m:
                    return True
        except (NotExact, ZeroDivisionError):
            pass  # no exact points: decide at sampled points
    M1 = Submanifold(system, tuple(system.holonomic) + tuple(system.phi), precision=precision,
                     samples=samples, seed=seed, exact=False)
    be = Backend(precision)
    tol = be.default_tol() if tol is None else tol
    with be.context():
        Cs = [side.numeric.point_from_tq(be, x).C for x in M1.points()[0]]
    for C in _finite_samples(Cs, "C = mu W^-1 mu^T"):
        s = np.linalg.svd(C, compute_uv=False)
        if s[-1] <= tol * max(s[0], 1.0):
            return False
    return True


def _finite_samples(matrices, what: str) -> list:
    """The matrices sampled at points of M_1 that are finite and real, as float arrays
    (where one is not, the point is outside the domain of L or a constraint, log(q) at
    q < 0, and says nothing); the InputError naming ``what`` when none is."""
    kept = []
    for S in matrices:
        try:
            A = np.asarray(S, dtype=float)
        except TypeError:  # a complex value (mpmath's log of a negative number)
            continue
        if np.all(np.isfinite(A)):
            kept.append(A)
    if not kept:
        raise InputError(f"{what} is not finite at any of {len(matrices)} points of M_1 (an "
                         f"overflow, or a function outside its domain: the Lagrangian's W or "
                         f"a constraint is singular there); nhham needs them defined on M_1")
    return kept


def _exact_affordable(side: HamiltonianSide) -> bool:
    return side.symbolic_affordable


def _to_hamiltonian(side, cons):
    system = side.system
    out_tq, out_h = [], []
    for c in cons:
        if _is_on_tq(c, system):
            out_tq.append(c)
            out_h.append(side.legendre.transport(c))
        else:
            out_h.append(cancel(c))
            out_tq.append(side.legendre.pullback(c))
    return tuple(out_tq), tuple(out_h)


def _classify_exact(side, cons, labels, analysis, tol):
    cons_tq, chi = _to_hamiltonian(side, cons)
    return classify_on(side.submanifold(chi), side.algebra, chi, labels, constraints_TQ=cons_tq,
                       tol=tol, side=side, analysis=analysis)


def classify_on(Mf: Submanifold, algebra, chi: Sequence, labels: Sequence[str], *,
                constraints_TQ: Sequence | None = None, tol: float | None = None, side=None,
                analysis=None) -> ConstraintClasses:
    """First and second class of constraints ``chi`` in (q, p) on their zero set ``Mf``.

    The exact classification: B_ab = {chi_a, chi_b} by ``algebra``, each entry's vanishing
    and the rank of B decided on ``Mf`` (the decision engine), a maximal second-class set R
    and the first-class combinations gamma_k. ``first_class`` is k - rank B: the number of
    constraints given minus the second-class ones (a caller with a reducible set counts
    independent ones itself, as the Dirac-Bergmann chain does).

    Parameters
    ----------
    Mf : Submanifold
        The zero set of ``chi`` in T*Q (``fibre`` the momenta).
    algebra : BracketAlgebra
    chi : sequence of sympy.Expr, length k
    labels : sequence of str, length k
    constraints_TQ : sequence of sympy.Expr, optional
        The same constraints on TQ (default ``chi``).
    tol : float, optional
        Relative tolerance of sampled decisions.

    Returns
    -------
    ConstraintClasses

    Examples
    --------
    {q1, p1, p1 + p2}: rank B = 2 although no row of B vanishes; p1 + p2 - p1 = p2 is first
    class.

    >>> import sympy as sp
    >>> from nhham import BracketAlgebra, Submanifold, System
    >>> from nhham.hamiltonian.classification import classify_on
    >>> s = System(["q1", "q2"], "q1_dot**2/2")
    >>> q1, q2, p1, p2 = sp.symbols("q1 q2 p_q1 p_q2")
    >>> M = Submanifold(s, [q1, p1, p1 + p2], fibre=(p1, p2))
    >>> c = classify_on(M, BracketAlgebra((q1, q2), (p1, p2)), [q1, p1, p1 + p2], ["a", "b", "c"])
    >>> c.second_class, c.first_class_combinations
    (2, (p_q2,))
    """
    chi = tuple(chi)
    cons_tq = tuple(chi if constraints_TQ is None else constraints_TQ)
    k = len(chi)
    B = algebra.bracket_matrix(chi).matrix
    decisions: dict = {}
    Br = sp.zeros(k, k)
    nonzero = np.zeros((k, k), dtype=bool)
    for a in range(k):
        for b in range(a + 1, k):
            d = Mf.vanishes(B[a, b], tol=tol)
            decisions[f"B[{labels[a]},{labels[b]}]"] = d
            if not d.value:
                Br[a, b] = Mf.reduce(B[a, b])
                Br[b, a] = -Br[a, b]
                nonzero[a, b] = nonzero[b, a] = True
    rank_d = Mf.rank(Br, tol=tol) if k else Decision(0, "exact", "no constraints")
    decisions["rank"] = rank_d
    r = int(cast(int, rank_d.value))
    samples_B = sample_matrix(Mf, Br) if r else ()
    R = principal_pivots(Br, samples_B, r, tol,
                          nonzero=lambda e: not Mf.vanishes(cancel(e), tol=tol).value)
    gammas, coeff_dicts = [], []
    # B_RR^-1 only where a first-class combination needs it (sympy's inverse of a 4 x 4
    # block on a curved M_f verifies invertibility by simplify: seconds).
    inv = block_inverse(Br.extract(R, R)) if R and len(R) < k else sp.zeros(0, 0)
    for kk in (i for i in range(k) if i not in R):
        c = sp.zeros(k, 1)
        c[kk] = 1
        if R:
            cR = (-(inv * Br.extract(R, [kk]))).applyfunc(cancel)
            for i, a in enumerate(R):
                c[a] = cR[i]
        gamma = cancel(sum((c[a] * chi[a] for a in range(k)), sp.S.Zero))
        gammas.append(gamma)
        coeff_dicts.append({labels[a]: c[a] for a in range(k) if c[a] != 0})
        residual = (Br * c).applyfunc(cancel)
        decisions[f"gamma[{labels[kk]}]"] = _all_vanish(Mf, residual, tol)
    alone = tuple(labels[a] for a in range(k) if not nonzero[a].any())
    blocks = tuple(tuple(labels[a] for a in blk) for blk in connected_blocks(nonzero)) if k else ()
    return ConstraintClasses(
        labels=tuple(labels), constraints_TQ=cons_tq, constraints=chi, bracket_matrix=Br,
        bracket_samples=tuple(samples_B), rank=r, first_class=k - r, second_class=r,
        second_class_set=tuple(labels[a] for a in R),
        first_class_combinations=tuple(gammas), combination_coefficients=tuple(coeff_dicts),
        individually_first_class=alone, blocks=blocks, decisions=decisions, method="exact",
        manifold=Mf, side=side, analysis=analysis)


def _all_vanish(Mf, column, tol):
    """One Decision: every entry of ``column`` vanishes on M_f."""
    worst = None
    for e in column:
        d = Mf.vanishes(e, tol=tol)
        if not d.value:
            return d
        if worst is None or d.method == "sampled":
            worst = d
    return worst or Decision(True, "exact", "no entries")


def sample_matrix(Mf: Submanifold, matrix: sp.Matrix):
    """numpy float matrices of ``matrix`` at M_f's sample points."""
    points, _ = Mf.points()
    args = list(Mf.variables) + list(Mf.system.parameters)
    f = Lambdified(args, list(matrix), matrix.shape)
    be = Backend(None)
    out = []
    with np.errstate(all="ignore"):  # a singular point gives inf or nan, read by callers
        for pt in points:
            out.append(f(be, [float(pt[s]) for s in args]))
    return out


def _classify_sampled(side, cons, labels, analysis, tol, precision, samples, seed):
    """Numeric classification: B at seeded points of M_f from the numeric layer."""
    system = side.system
    cons_tq = tuple(c if _is_on_tq(c, system) or not (sp.sympify(c).free_symbols
                                                      & set(side.momenta))
                    else side.legendre.pullback(c) for c in cons)
    be = Backend(precision)
    Mtq = Submanifold(system, cons_tq, precision=precision, samples=samples, seed=seed,
                      exact=False)
    points, resid = Mtq.points()
    num = side.numeric
    mats = []
    with be.context():
        for x in points:
            pt = num.point_from_tq(be, x)
            mats.append(num.bracket_matrix(be, pt, cons_tq))
    if precision is None:  # float64: the points outside the domain of L left out
        mats = _finite_samples(mats, "the bracket matrix {chi_a, chi_b}")
    return classes_from_samples(side, cons_tq, labels, analysis, mats, be, tol, resid,
                                 "the numeric bracket matrix")
