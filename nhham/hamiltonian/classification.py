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

import math
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
import sympy as sp

from nhham.settings import SEED
from nhham.hamiltonian.brackets import DiracBracket, connected_blocks
from nhham.errors import ComputationError, InputError, NhhamError
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.hamiltonian.legendre import Backend, Lambdified, ModularBackend
from nhham.hamiltonian.combinations import NotFormed, closed_form_combinations
from nhham.lagrangian.algebra import block_inverse, cancel
from nhham.lagrangian.analysis import ConstraintAnalysis, analyze_constraints
from nhham.lagrangian.domains import NotExact, evaluate, minor_degree, schwartz_zippel_bound
from nhham.lagrangian.formulas import lagrangian_bracket
from nhham.lagrangian.linalg import FloatMatrix, ListMatrix, exact_rank, exact_solve
from nhham.lagrangian.points import PointSampler, jacobian_row
from nhham.lagrangian.submanifold import Decision, Submanifold
from nhham.lagrangian.tangency import MAX_POINTS, TARGET_ERROR
from nhham.system.expressions import short

__all__ = [
    "ConstraintClasses",
    "classify_constraints",
    "dirac_bracket",
    "DiracProjectedReport",
    "dirac_vs_projected",
    "final_constraints_of",
]


# ---------------------------------------------------------------- inputs
def final_constraints_of(source, precision: int | None = None, samples: int = 6,
                         seed: int = SEED):
    """(system, final constraints on TQ, labels, analysis) for a source.

    Parameters
    ----------
    source : System, HamiltonianSide or ConstraintAnalysis
        A system (or a side, for its system) runs the constraint algorithm
        (:func:`nhham.lagrangian.analysis.analyze_constraints` with these
        precision, samples and seed); an analysis is used as it is.

    Raises
    ------
    ComputationError
        When the analysis is inconsistent: there is no M_f to classify on.
    """
    if isinstance(source, HamiltonianSide):
        source = source.system
    analysis = source if isinstance(source, ConstraintAnalysis) else analyze_constraints(
        source, precision=precision, samples=samples, seed=seed)
    if analysis.status == "inconsistent":
        raise ComputationError(
            f"classify: the constraint algorithm found no dynamics (inconsistent: "
            f"{analysis.inconsistency}); there is no M_f to classify on")
    cons = tuple(sp.sympify(c) for c in analysis.final_constraints)
    return analysis.system, cons, tuple(analysis.final_labels), analysis


def _default_labels(system):
    k = len(system.holonomic)
    return tuple(f"holonomic[{i}]" for i in range(k)) + tuple(
        f"{lab}.lift" if lab.startswith("holonomic") else lab
        for lab in system.constraint_labels)


def _is_on_tq(expr, system):
    return bool(sp.sympify(expr).free_symbols & set(system.velocities))


# --------------------------------------------------------------- results
@dataclass(frozen=True)
class ConstraintClasses:
    """Classification of the final constraints chi_a on M_f (in T*Q).

    Attributes
    ----------
    labels : tuple of str
        Names of the chi_a.
    constraints_TQ : tuple of sympy.Expr
        chi_a on TQ, functions of (q, v).
    constraints : tuple of sympy.Expr or None
        chi_a o Leg^{-1} in (q, p) (None in sampled mode without a symbolic inverse).
    bracket_matrix : sympy.Matrix or None
        B_ab = {chi_a, chi_b} reduced on M_f (exact mode), shape (k, k).
    bracket_samples : tuple of numpy.ndarray
        B at the sample points of M_f (sampled mode, or the pivot evidence).
    rank : int
        rank B on M_f = number of second-class constraints.
    first_class, second_class : int
    second_class_set : tuple of str
        Labels of a maximal second-class set R (B_RR invertible on M_f).
    first_class_combinations : tuple of sympy.Expr or None
        A basis gamma_k = chi_k - sum_{a in R} (B_RR^{-1} B_Rk)_a chi_a (in
        (q, p)), one per constraint outside R.
    combination_coefficients : tuple of dict
        ``{label: coefficient}`` of each gamma_k (expressions on M_f in
        exact mode; in sampled mode a tuple of values, one per sample point).
    individually_first_class : tuple of str
        Labels whose whole row of B vanishes on M_f.
    blocks : tuple of tuple of str
        Connected components of the nonzero pattern of B on M_f.
    decisions : dict
        Named :class:`Decision` objects: ``"rank"``, ``"B[a,b]"`` per entry,
        ``"gamma[k]"`` for the check that each combination is first class.
    method : str
        ``"exact"`` (symbolic B reduced on M_f), ``"exact at points"`` (B at
        exact points of M_f: each decision says whether it is a proof or carries
        a Schwartz–Zippel error bound; no symbolic B) or ``"sampled"``.
    manifold : Submanifold or None
        M_f in T*Q (exact mode).
    side : HamiltonianSide
    analysis : object or None
        The ConstraintAnalysis the constraints came from.
    """

    labels: tuple
    constraints_TQ: tuple
    constraints: tuple | None
    bracket_matrix: sp.Matrix | None
    bracket_samples: tuple
    rank: int
    first_class: int
    second_class: int
    second_class_set: tuple
    first_class_combinations: tuple | None
    combination_coefficients: tuple
    individually_first_class: tuple
    blocks: tuple
    decisions: dict
    method: str
    manifold: Submanifold | None
    side: HamiltonianSide
    analysis: object = None

    @property
    def second_class_indices(self) -> tuple:
        return tuple(self.labels.index(lab) for lab in self.second_class_set)

    @property
    def second_class_constraints(self) -> tuple | None:
        """The chi_a of the maximal second-class set, in (q, p)."""
        if self.constraints is None:
            return None
        return tuple(self.constraints[a] for a in self.second_class_indices)

    @property
    def rank_decision(self) -> Decision:
        return self.decisions["rank"]

    @property
    def warnings(self) -> tuple:
        """Warnings of every decision, prefixed by what was decided."""
        return tuple(f"{name}: {w}" for name, d in self.decisions.items() for w in d.warnings)

    def __repr__(self) -> str:
        return (f"<ConstraintClasses: {len(self.labels)} final constraint(s), "
                f"{self.second_class} second class, {self.first_class} first class "
                f"({self.method})>")

    def _repr_latex_(self) -> str:
        """The classification table (for notebooks)."""
        kinds = {lab: "in the maximal second-class set" for lab in self.second_class_set}
        rows = [rf"\text{{{lab}}} & \text{{{kinds.get(lab, 'gives a first-class combination')}}}"
                for lab in self.labels]
        head = (rf"\operatorname{{rank}} \{{\chi_a, \chi_b\}} = {self.rank}:\ "
                rf"{self.second_class}\ \text{{second class}},\ {self.first_class}\ "
                rf"\text{{first class}}")
        return "$$" + head + r"\\ \begin{array}{ll}" + r" \\ ".join(rows) + r"\end{array}$$"

    def describe(self) -> str:
        lines = [f"{len(self.labels)} final constraints: {self.second_class} second class, "
                 f"{self.first_class} first class (rank of the bracket matrix on M_f: "
                 f"{self.rank_decision.describe()})"]
        if self.second_class_set:
            lines.append("maximal second-class set: " + ", ".join(self.second_class_set))
        if self.first_class_combinations is not None:
            for g in self.first_class_combinations:
                lines.append(f"first class: {g}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready summary (expressions as sympy-parsable strings)."""
        def coeffs(c):
            return {k: (str(v) if isinstance(v, sp.Basic) else [float(x) for x in v])
                    for k, v in c.items()}
        return {
            "constraints": [str(c) for c in self.constraints] if self.constraints else None,
            "labels": list(self.labels),
            "rank": self.rank,
            "first_class": self.first_class,
            "second_class": self.second_class,
            "second_class_set": list(self.second_class_set),
            "first_class_combinations": (None if self.first_class_combinations is None
                                         else [str(g) for g in self.first_class_combinations]),
            "combination_coefficients": [coeffs(c) for c in self.combination_coefficients],
            "individually_first_class": list(self.individually_first_class),
            "blocks": [list(b) for b in self.blocks],
            "method": self.method,
            "decisions": {k: {"value": d.value if isinstance(d.value, (bool, int)) else str(d.value),
                              "method": d.method, "detail": d.detail, "precision": d.precision,
                              "warnings": list(d.warnings)}
                          for k, d in self.decisions.items()},
        }


# ------------------------------------------------------------ classify
def classify_constraints(source, constraints: Sequence | None = None,
                         labels: Sequence[str] | None = None, *, precision: int | None = None,
                         samples: int = 6, seed: int = SEED, method: str = "auto",
                         tol: float | None = None) -> ConstraintClasses:
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

    Returns
    -------
    ConstraintClasses
    """
    if method not in ("auto", "exact", "sampled"):
        raise InputError(f"classify: method must be 'auto', 'exact' or 'sampled', got {method!r}")
    side_in = source if isinstance(source, HamiltonianSide) else None
    system = source.system if isinstance(source, HamiltonianSide) else getattr(
        source, "system", source)
    side = side_in if side_in is not None else hamiltonian_side(
        system, precision=precision, samples=samples, seed=seed)
    requested = method
    if method == "auto":
        method = "exact" if _exact_affordable(side) else "sampled"
    if constraints is None:
        if method == "sampled" and not isinstance(source, ConstraintAnalysis) \
                and _numerically_regular(side, precision, samples, seed, tol):
            # C has full rank at the samples of M_1: M_f = M_1, no symbolic algorithm run.
            cons, labs, analysis = (tuple(system.holonomic) + tuple(system.phi),
                                    _default_labels(system), None)
        else:
            system, cons, labs, analysis = final_constraints_of(source, precision, samples, seed)
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
        try:
            classes = _classify_at_points(side, cons, labs, analysis, seed)
        except NotExact:
            classes = _classify_lagrangian_sampled(side, cons, labs, analysis, tol, precision,
                                                   samples, seed)
    else:
        classes = _classify_sampled(side, cons, labs, analysis, tol, precision, samples, seed)
    return _with_combinations(classes)


def _classify_at_points(side, cons, labels, analysis, seed, target=TARGET_ERROR):
    """B_ab = {chi_a, chi_b} at random exact points of M_f = M_1, through the
    Lagrangian bracket (the pull-back of the canonical one by Leg):

        {f, g}_L = f_q . W^{-1} g_v - W^{-1} f_v . g_q - (W^{-1} f_v)^T (M - M^T) W^{-1} g_v

    with M the mixed Hessian d2L/dq dv. rank B at an exact point is proved; a
    deficiency seen at k points carries the Schwartz–Zippel bound.
    """
    from nhham.lagrangian.geometry import lagrangian_geometry

    system = side.system
    geo = analysis.geometry if isinstance(analysis, ConstraintAnalysis) else \
        lagrangian_geometry(system)
    q, v = system.coordinates, system.velocities
    cons = [sp.sympify(c) for c in cons]
    k = len(cons)
    sampler = PointSampler.on_M1(system, seed)
    Jq = [jacobian_row(c, q) for c in cons]
    Jv = [jacobian_row(c, v) for c in cons]
    W = [list(geo.hessian.row(i)) for i in range(system.n)]
    Mx = [list(geo.mixed_hessian.row(i)) for i in range(system.n)]
    proof = _rank_modulo_p(side, cons, labels, analysis, seed, W, Mx, Jq, Jv)
    if proof is not None:
        return proof
    best, count, pivots, mats, degrees, error = -1, 0, [], [], None, 0.0
    while count < MAX_POINTS:
        pt = sampler.point()
        try:
            Bp = _bracket_at(pt.env, W, Mx, Jq, Jv)
        except ZeroDivisionError:
            continue
        count += 1
        mats.append(Bp)
        r, rows, _ = exact_rank(Bp) if k else (0, [], [])
        if r > best:
            best, pivots = r, rows
        if degrees is None:
            degrees = _bracket_at(pt.degrees, W, Mx, Jq, Jv)
        if best >= k:
            break
        error = schwartz_zippel_bound(minor_degree(degrees, best + 1), count,
                                      denominator_degree=sampler.denominator_degree)
        if error < target:
            break
    r = best
    if r >= k:
        rank_d = Decision(r, "exact", f"bracket matrix of full rank {r} at an exact point of "
                          f"M_f (proof)", samples=count, error_bound=0.0)
    else:
        rank_d = Decision(r, "exact at points", f"rank {r} of the bracket matrix at {count} "
                          f"random exact points of M_f", samples=count, error_bound=error)
    decisions = {"rank": rank_d}
    R = list(pivots) if r else []
    nonzero = np.zeros((k, k), dtype=bool)
    for Bp in mats:
        nonzero |= np.array([[x != 0 for x in row] for row in Bp], dtype=bool).reshape(k, k)
    coeff_dicts = []
    for kk in (i for i in range(k) if i not in R):
        per_point = []
        for Bp in mats:
            per_point.append(_exact_combination(Bp, R, kk))
        coeff_dicts.append({labels[a]: tuple(float(c[a]) for c in per_point)
                            for a in range(k) if any(c[a] != 0 for c in per_point)})
        decisions[f"gamma[{labels[kk]}]"] = Decision(
            True, "exact", "B c = 0 exactly at each point (c solved from the regular block "
            "of B at that point); the coefficients depend on the point", samples=count)
    alone = tuple(labels[a] for a in range(k) if not nonzero[a].any())
    blocks = tuple(tuple(labels[a] for a in blk) for blk in connected_blocks(nonzero)) if k else ()
    cons_tq = tuple(cons)
    return ConstraintClasses(
        labels=tuple(labels), constraints_TQ=cons_tq, constraints=None, bracket_matrix=None,
        bracket_samples=tuple(np.array([[float(x) for x in row] for row in Bp], dtype=float)
                              .reshape(k, k) for Bp in mats),
        rank=r, first_class=k - r, second_class=r,
        second_class_set=tuple(labels[a] for a in R), first_class_combinations=None,
        combination_coefficients=tuple(coeff_dicts), individually_first_class=alone,
        blocks=blocks, decisions=decisions, method="exact at points", manifold=None,
        side=side, analysis=analysis)


#: The first-class combinations of a classification decided at points are formed in
#: closed form up to this many coordinates (:mod:`nhham.hamiltonian.combinations`).
COMBINATION_MAX_N = 8


def _with_combinations(classes: ConstraintClasses) -> ConstraintClasses:
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
    why = f"n = {system.n} > {COMBINATION_MAX_N}" if system.n > COMBINATION_MAX_N else ""
    if not why:
        try:
            gammas, coeffs = closed_form_combinations(system, classes.constraints_TQ,
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


def _rank_modulo_p(side, cons, labels, analysis, seed, W, Mx, Jq, Jv, tries=3):
    """The rank of B proved at a point over F_p where it is the largest B can have; else None.

    B is antisymmetric, so its rank is at most k for k even and k - 1 for k odd. A rank
    r modulo p at a point of M_1 is a lower bound of its rank over Q at a rational point
    (no inverse taken was of a multiple of p), hence of its generic rank on M_1: where r
    is that largest rank, the rank is proved. The r pivot rows R are independent, so
    B_RR is invertible (a principal submatrix of an antisymmetric matrix on a maximal
    independent set of rows); for k odd the one first-class combination is
    chi_k - sum_R (B_RR^-1 B_Rk)_a chi_a, its coefficients given at seeded float points
    of M_1 (rational arithmetic at n = 19 took 5 s a point).
    """
    system = side.system
    k = len(cons)
    if k == 0:
        return None
    largest = k - k % 2
    sampler = PointSampler.on_M1(system, seed, modular=True)
    for _ in range(tries):
        try:
            Bp = _bracket_at(sampler.point().env, W, Mx, Jq, Jv)
        except (ZeroDivisionError, NotExact):
            continue
        r, rows, _ = exact_rank(Bp)
        if r < largest:
            continue
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
            coeff_dicts = (_coefficients_at_a_point(side, cons, labels, analysis, seed, R, kk,
                                                     (W, Mx, Jq, Jv)),)
            decisions[f"gamma[{labels[kk]}]"] = Decision(
                True, "exact", "B_RR of rank r modulo p at the point: the combination with "
                "coefficient 1 on this constraint and -B_RR^-1 B_Rk on R is first class (its "
                "coefficients depend on the point)", samples=1)
        return ConstraintClasses(
            labels=tuple(labels), constraints_TQ=tuple(cons), constraints=None,
            bracket_matrix=None, bracket_samples=(), rank=r, first_class=k - r,
            second_class=r, second_class_set=tuple(labels[a] for a in R),
            first_class_combinations=() if r == k else None,
            combination_coefficients=coeff_dicts,
            individually_first_class=tuple(labels[a] for a in range(k)
                                           if not nonzero[a].any()),
            blocks=blocks, decisions=decisions, method="exact at points", manifold=None,
            side=side, analysis=analysis)
    return None


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


def _coefficients_at_a_point(side, cons, labels, analysis, seed, R, kk, data) -> dict:
    """The coefficients of chi_kk - sum_R (B_RR^-1 B_Rk)_a chi_a: label -> values.

    At one random rational point of M_1 (exact, then rounded) up to
    COMBINATION_MAX_N coordinates or when float points cannot be found (parameters
    of very different sizes); beyond, at seeded float points (rational arithmetic at
    n = 19 takes seconds a point).
    """
    if not R:
        return {labels[kk]: (1.0,)}
    mats: list = []
    if side.system.n > COMBINATION_MAX_N:
        try:
            mats, _ = _float_brackets(side, cons, analysis, None, 3, seed)
        except NhhamError:
            pass  # no float points (parameters of very different sizes): a rational one
    if not mats:
        sampler = PointSampler.on_M1(side.system, seed)
        for _ in range(MAX_POINTS):
            try:
                c = _exact_combination(_bracket_at(sampler.point().env, *data), R, kk)
            except ZeroDivisionError:
                continue
            return {labels[a]: (float(c[a]),) for a in range(len(cons)) if c[a] != 0}
        raise ComputationError(f"B_RR singular at {MAX_POINTS} random points of M_1 though "
                               f"it is regular modulo p at one")
    per_point = []
    for S in mats:
        c = np.zeros(len(cons))
        c[kk] = 1.0
        c[R] = -np.linalg.solve(S[np.ix_(R, R)], S[R, kk])
        per_point.append(c)
    return {labels[a]: tuple(float(c[a]) for c in per_point)
            for a in range(len(cons)) if any(c[a] != 0 for c in per_point)}


def _classify_lagrangian_sampled(side, cons, labels, analysis, tol, precision, samples,
                                 seed):
    """B = {chi_a, chi_b}_L at seeded float points of M_f = M_1 (no exact points).

    The Lagrangian bracket needs only W, the mixed Hessian and the gradients of
    the constraints at each point (numbers), never H or Leg^-1 symbolically.
    """
    mats, resid = _float_brackets(side, cons, analysis, precision, samples, seed)
    return _classes_from_samples(side, tuple(sp.sympify(c) for c in cons), labels, analysis,
                                 mats, Backend(None), tol, resid,
                                 "the bracket matrix {chi_a, chi_b}_L")


def _float_brackets(side, cons, analysis, precision, samples, seed) -> tuple:
    """B = {chi_a, chi_b}_L (float64 arrays, k x k) at seeded float points of M_f = M_1,
    with the points' residual."""
    from nhham.lagrangian.geometry import lagrangian_geometry

    system = side.system
    geo = analysis.geometry if isinstance(analysis, ConstraintAnalysis) else \
        lagrangian_geometry(system)
    q, v = system.coordinates, system.velocities
    cons = [sp.sympify(c) for c in cons]
    k, n = len(cons), system.n
    Mtq = Submanifold(system, tuple(cons), precision=precision, samples=samples, seed=seed,
                      exact=False)
    points, resid = Mtq.points()
    J = sp.Matrix([jacobian_row(c, list(q) + list(v)) for c in cons])
    fW, fM, fJ = (Mtq.evaluator(geo.hessian), Mtq.evaluator(geo.mixed_hessian),
                  Mtq.evaluator(J))
    mats = []
    for pt in points:
        Jp = np.array(fJ(pt), dtype=float).reshape(k, 2 * n)
        B = lagrangian_bracket(FloatMatrix(Jp[:, :n]), FloatMatrix(Jp[:, n:]),
                               FloatMatrix(fW(pt)), FloatMatrix(fM(pt)))
        mats.append(B.a)
    return mats, resid


def _bracket_at(env, W, Mx, Jq, Jv):
    """The bracket matrix {chi_a, chi_b}_L at one point (exact values, residues or
    Degree bounds: the arithmetic of ``env``)."""
    if not Jq:
        return []
    cache: dict = {}
    Wp, Mp, Jqp, Jvp = (ListMatrix([evaluate(r, env, cache) for r in rows])
                        for rows in (W, Mx, Jq, Jv))
    return lagrangian_bracket(Jqp, Jvp, Wp, Mp).to_list()


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
            be = ModularBackend()
            for _ in range(3):
                C = side.numeric.point_from_tq(be, sampler.point().env).C
                if exact_rank([list(row) for row in C])[0] == system.m:
                    return True
        except (NotExact, ZeroDivisionError):
            pass  # no exact points: decide at sampled points
    M1 = Submanifold(system, tuple(system.holonomic) + tuple(system.phi), precision=precision,
                     samples=samples, seed=seed, exact=False)
    be = Backend(precision)
    tol = be.default_tol() if tol is None else tol
    with be.context():
        for x in M1.points()[0]:
            C = side.numeric.point_from_tq(be, x).C
            s = np.linalg.svd(np.asarray(C, dtype=float), compute_uv=False)
            if s[-1] <= tol * max(s[0], 1.0):
                return False
    return True


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
    k = len(chi)
    Mf = side.submanifold(chi)
    B = side.algebra.bracket_matrix(chi).matrix
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
    r = int(rank_d.value)
    samples_B = _sample_matrix(Mf, Br) if r else ()
    R = _principal_pivots(Br, samples_B, r, tol,
                          nonzero=lambda e: not Mf.vanishes(cancel(e), tol=tol).value)
    gammas, coeff_dicts = [], []
    inv = block_inverse(Br.extract(R, R)) if R else sp.zeros(0, 0)
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


def _sample_matrix(Mf: Submanifold, matrix: sp.Matrix):
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


def _principal_pivots(Br: sp.Matrix, samples, r: int, tol, nonzero=None) -> list:
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
            trial = next((sorted(R + [a, b]) for a in range(k) for b in range(a + 1, k)
                          if a not in R and b not in R
                          and nonzero(Br.extract(sorted(R + [a, b]), sorted(R + [a, b])).det())),
                         None)
            if trial is not None:
                R, grown = trial, True
        if not grown:
            raise ComputationError(
                f"classification: no principal {len(R) + 2}x{len(R) + 2} block of the bracket "
                f"matrix is invertible at the samples although its rank on M_f is {r}")
    return R


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
    return _classes_from_samples(side, cons_tq, labels, analysis, mats, be, tol, resid,
                                 "the numeric bracket matrix")


def _classes_from_samples(side, cons_tq, labels, analysis, mats, be, tol, resid, what):
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
    R = _principal_pivots(sp.Matrix(k, k, lambda a, b: sp.Symbol("b")), fmats, r, tol_) \
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


# ---------------------------------------------------------------- Dirac
def dirac_bracket(source, classes: ConstraintClasses | None = None, *,
                  on_manifold: bool = False, **classify_options) -> DiracBracket:
    """The Dirac bracket over the maximal second-class set of the final constraints.

    Parameters
    ----------
    source : System, HamiltonianSide, ConstraintAnalysis or ConstraintClasses
    classes : ConstraintClasses, optional
        A classification to use (default: computed, exact mode).
    on_manifold : bool
        False (default): B = {chi_a, chi_b} as functions on T*Q, blocks from
        its identically nonzero entries, so the Dirac bracket is a Poisson
        bracket wherever B is invertible. True: B reduced on M_f and blocks
        from the decisions on M_f (cheaper; valid on M_f only).
    **classify_options
        Passed to :func:`classify_constraints`.

    Returns
    -------
    DiracBracket
    """
    if isinstance(source, ConstraintClasses):
        classes = source
    if classes is None:
        classify_options.setdefault("method", "exact")
        classes = classify_constraints(source, **classify_options)
    if classes.constraints is None:
        raise ComputationError("the Dirac bracket needs the constraints in (q, p): classify "
                               "with method='exact'")
    side = classes.side
    R = list(classes.second_class_indices)
    chi = [classes.constraints[a] for a in R]
    if on_manifold:
        B = classes.bracket_matrix.extract(R, R)
        label_index = {lab: i for i, lab in enumerate(classes.second_class_set)}
        blocks = [[label_index[lab] for lab in blk if lab in label_index]
                  for blk in classes.blocks]
        blocks = [b for b in blocks if b]
        return DiracBracket(side.algebra, chi, blocks=blocks, matrix=B)
    return DiracBracket(side.algebra, chi)


@dataclass(frozen=True)
class DiracProjectedReport:
    """The Dirac-bracket flow of H against the projected field X on M_f.

    Attributes
    ----------
    equal : bool
        True when X_D - X vanishes on M_f (every component).
    difference : sympy.Matrix, shape (2n, 1), or None
        X_D - X reduced on M_f, in (q, p) (None in sampled mode).
    dirac_field, projected_field : sympy.Matrix, shape (2n, 1), or None
        X_D = (z -> {z, H}_D) and X = X_H + lambda^j Z_j^H on M_f (None in
        sampled mode).
    decisions : tuple of Decision
        Per component of the difference: does it vanish on M_f.
    max_abs_difference : float
        Largest |X_D - X| at the seeded sample points of M_f (nan when compared
        exactly modulo p at exact points: F_p has no absolute value).
    samples : int
    notes : tuple of str
        Caveats (first-class constraints make the Dirac flow a gauge family).
    classes : ConstraintClasses
    """

    equal: bool
    difference: sp.Matrix | None
    dirac_field: sp.Matrix | None
    projected_field: sp.Matrix | None
    decisions: tuple
    max_abs_difference: float
    samples: int
    notes: tuple
    classes: ConstraintClasses

    def describe(self) -> str:
        if self.equal:
            return ("the Dirac-bracket flow of H equals the projected (nonholonomic) field on "
                    "M_f")
        if self.difference is None:
            return ("the Dirac-bracket flow of H is NOT the true dynamics on M_f: "
                    + self.decisions[0].detail)
        comps = [f"d/d{z}: {short(d, 160)}" for z, d in zip(self.classes.side.variables,
                                                              self.difference) if d != 0]
        cut = any(len(str(d)) > 160 for d in self.difference)
        return ("the Dirac-bracket flow of H is NOT the true dynamics on M_f; X_D - X = "
                + "; ".join(comps) + f" (max |X_D - X| = {self.max_abs_difference:.3g} at "
                f"{self.samples} sample points" + ("; whole expressions with --json or "
                                                    "--latex)" if cut else ")"))

    def to_dict(self) -> dict:
        return {"equal": self.equal,
                "difference": (None if self.difference is None
                               else [str(d) for d in self.difference]),
                "max_abs_difference": self.max_abs_difference,
                "samples": self.samples, "notes": list(self.notes)}


def dirac_vs_projected(system, *, precision=None, samples=6, seed=SEED,
                       classes: ConstraintClasses | None = None, method: str = "auto",
                       tol: float | None = None,
                       side: HamiltonianSide | None = None) -> DiracProjectedReport:
    """Compare the Dirac-bracket flow of H with the true (projected) dynamics on M_f.

    For holonomic constraints the two agree on M_f; for truly nonholonomic
    constraints they do not (nonholonomic dynamics is not variational). The
    Dirac flow is taken over the maximal second-class set of the final
    constraints. Exact mode: the difference X_D - X is reduced on M_f and
    decided per component, and evaluated at seeded points. Sampled mode (large
    systems): both fields are evaluated numerically at seeded points of M_f
    and the difference is decided there (``difference`` is then None).

    Parameters
    ----------
    system : nhham.System
        A regular system (C^H invertible on M_1).
    precision, samples, seed
        Settings of the sampled decisions.
    classes : ConstraintClasses, optional
        A classification to use; its method decides the mode.
    method : {"auto", "exact", "sampled"}
        As for :func:`classify_constraints`.
    tol : float, optional
        Relative tolerance of sampled decisions.
    side : HamiltonianSide, optional
        The T*Q side of ``system`` when the caller has it.

    Returns
    -------
    DiracProjectedReport
    """
    if side is None:
        side = classes.side if classes is not None else hamiltonian_side(
            system, precision=precision, samples=samples, seed=seed, closed_form=True)
    if classes is None:
        classes = classify_constraints(side, precision=precision, samples=samples, seed=seed,
                                       method=method, tol=tol)
    if classes.method == "exact at points" and precision is None \
            and side.legendre.is_quadratic:
        try:
            return _dirac_vs_projected_at_points(side, classes, samples, seed)
        except NotExact:
            pass  # no exact points after all: sampled
    if classes.method != "exact":
        return _dirac_vs_projected_sampled(side, classes, precision, samples, seed, tol)
    if not side.regular:
        raise ComputationError(
            "dirac_vs_projected: C^H is singular on M_1; the projected field is a family "
            "(see nhham.lagrangian.algorithm) and the comparison is defined for regular systems only")
    XD, X, diff = _fields_on_Mf(side, classes)
    Mf = classes.manifold
    decisions = tuple(Mf.vanishes(d, tol=tol) for d in diff)
    reduced = sp.Matrix([0 if d.value else e for d, e in zip(decisions, diff)])
    notes = _gauge_note(classes)
    at, generic = _at_parameter_values(Mf, reduced, tol, side.variables)
    if at is not None:
        # The verdict is for the scene's values; the generic difference is a note.
        decisions, reduced = at
        notes += (f"X_D - X vanishes at the parameter values but not for generic values "
                  f"({generic})",)
    sampled = _sample_matrix(Mf, reduced) if reduced.rows else []
    # A sample point on a singular set of the chart (the snakeboard at phi = +-pi/2)
    # gives no value: it is left out, not reported as an infinite difference.
    sampled = [S for S in sampled if np.all(np.isfinite(S))]
    worst = max((float(np.max(np.abs(S))) for S in sampled), default=0.0)
    return DiracProjectedReport(
        equal=all(d.value for d in decisions), difference=reduced, dirac_field=XD,
        projected_field=X, decisions=decisions, max_abs_difference=worst,
        samples=len(sampled), notes=notes, classes=classes)


def _at_parameter_values(Mf, reduced, tol, variables):
    """((decisions, reduced difference) at the system's parameter values, the generic
    difference as text) when the values make a generically nonzero X_D - X vanish;
    else (None, None)."""
    values = Mf.system.exact_parameter_values
    if not values or all(e == 0 for e in reduced):
        return None, None
    at_values = [cancel(e.xreplace(values)) for e in reduced]
    decisions = tuple(Mf.vanishes(e, tol=tol) for e in at_values)
    if not all(d.value for d in decisions):
        return None, None
    generic = "; ".join(f"d/d{z}: {e}" for z, e in zip(variables, reduced) if e != 0)
    return (decisions, sp.zeros(*reduced.shape)), generic


def _gauge_note(classes) -> tuple:
    if not classes.first_class:
        return ()
    return (f"{classes.first_class} first-class constraint(s): the Dirac flow is then only "
            f"defined up to adding multiples of their Hamiltonian fields (gauge); the field "
            f"compared is {{z, H}}_D without such terms",)


def _dirac_minus_projected(be, num, hp, chis):
    """X_D - X at one point of the numeric layer (``be`` arithmetic), or None where C^H
    is singular (outside the domain of X).

    X_D = X_H - X_{chi_a} (B_RR^{-1})^{ab} {chi_b, H} with X_chi = (chi_p, -chi_q),
    X = X_H + lambda^j Z_j^H.
    """
    try:
        X, _ = num.projected_field(be, hp)
    except (np.linalg.LinAlgError, ZeroDivisionError):
        return None
    XD = hp.X_H.copy()
    if chis:
        _, Gq, Gp = num.gradients(be, hp, chis)
        B = Gq @ Gp.T - Gp @ Gq.T
        y = be.solve(B, Gq @ hp.Hp - Gp @ hp.Hq)
        XD = XD - np.concatenate([Gp.T @ y, -(Gq.T @ y)])
    return XD, X


def _dirac_vs_projected_at_points(side, classes, samples, seed):
    """X_D - X exactly modulo p at seeded points of M_f = M_1 (no symbolic inverse, no
    compilation). A difference nonzero at a point proves X_D != X; zero at every
    point is the probabilistic verdict "equal" (a nonzero rational function of the
    drawn values vanishes at a random point of F_p with probability at most its
    degree over p = 2^61 - 1)."""
    system = side.system
    be = ModularBackend()
    R = list(classes.second_class_indices)
    chis = [classes.constraints_TQ[a] for a in R]
    sampler = PointSampler.on_M1(system, seed, modular=True)
    num = side.numeric
    used = differ = 0
    for _ in range(2 * samples):
        if used == samples:
            break
        got = _dirac_minus_projected(be, num, num.point_from_tq(be, sampler.point().env), chis)
        if got is None:
            continue
        used += 1
        differ += any(a != b for a, b in zip(*got))
    if not used:
        raise ComputationError("dirac_vs_projected: C^H is singular at every exact point")
    equal = not differ
    detail = (f"X_D - X is 0 at each of {used} exact points of M_f (arithmetic modulo "
              f"p = 2^61 - 1)" if equal else
              f"X_D - X is nonzero at {differ} of {used} exact points of M_f (arithmetic "
              f"modulo p = 2^61 - 1; a proof)")
    decision = Decision(equal, "exact at points", detail, precision=be.label, samples=used)
    return DiracProjectedReport(
        equal=equal, difference=None, dirac_field=None, projected_field=None,
        decisions=(decision,), max_abs_difference=math.nan, samples=used,
        notes=_gauge_note(classes), classes=classes)


def _dirac_vs_projected_sampled(side, classes, precision, samples, seed, tol):
    """X_D - X at seeded points of M_f from the numeric layer (no symbolic inverse).

    X_D = X_H - X_{chi_a} (B_RR^{-1})^{ab} {chi_b, H} with X_chi = (chi_p, -chi_q),
    X = X_H + lambda^j Z_j^H; R the maximal second-class set of ``classes``.
    """
    system = side.system
    be = Backend(precision)
    tol_ = be.default_tol() if tol is None else tol
    R = list(classes.second_class_indices)
    chis = [classes.constraints_TQ[a] for a in R]
    Mtq = Submanifold(system, classes.constraints_TQ, precision=precision, samples=samples,
                      seed=seed, exact=False)
    points, resid = Mtq.points()
    num = side.numeric
    worst, worst_rel, used = 0.0, 0.0, 0
    with be.context():
        for x in points:
            got = _dirac_minus_projected(be, num, num.point_from_tq(be, x), chis)
            if got is None:
                continue  # C singular at this point: outside the domain of X
            XD, X = got
            d = float(be.norm(XD - X))
            scale = max(1.0, float(be.norm(X)), float(be.norm(XD)))
            worst, worst_rel, used = max(worst, d), max(worst_rel, d / scale), used + 1
    if not used:
        raise ComputationError("dirac_vs_projected: C^H is singular at every sample point")
    equal = worst_rel <= tol_
    decision = Decision(
        equal, "sampled",
        f"largest |X_D - X| {worst:.3g} (relative {worst_rel:.3g}) at {used} seeded points "
        f"of M_f, tolerance {tol_:g}", precision=be.label, samples=used, max_abs=worst,
        point_residual=resid)
    return DiracProjectedReport(
        equal=equal, difference=None, dirac_field=None, projected_field=None,
        decisions=(decision,), max_abs_difference=worst, samples=used,
        notes=_gauge_note(classes), classes=classes)


def _fields_on_Mf(side: HamiltonianSide, classes: ConstraintClasses):
    """X_D, X and X_D - X on M_f, assembled from factors reduced on M_f first.

    {z, H}_D = {z, H} - {z, chi_a} (B^{-1})^{ab} {chi_b, H} and
    X = X_H + Z_j^H lambda^j; reducing the small factors before multiplying
    keeps the expressions small (reducing the assembled fields is far slower).
    """
    Mf = classes.manifold
    alg = side.algebra
    R = list(classes.second_class_indices)
    chi = [classes.constraints[a] for a in R]
    B = classes.bracket_matrix.extract(R, R)
    label_index = {lab: i for i, lab in enumerate(classes.second_class_set)}
    blocks = [[label_index[lab] for lab in blk if lab in label_index] for blk in classes.blocks]
    blocks = [b for b in blocks if b]
    inverses = [(blk, block_inverse(B.extract(blk, blk))) for blk in blocks]
    s = [Mf.reduce(alg.bracket(c, side.H)) for c in chi]
    XH = [Mf.reduce(e) for e in side.X_H]
    lam = [Mf.reduce(e) for e in side.multipliers]
    Z = side.vertical_fields
    XD, X, diff = [], [], []
    for i, z in enumerate(side.variables):
        t = [Mf.reduce(alg.bracket(z, c)) for c in chi]
        corr = sp.S.Zero
        for blk, inv in inverses:
            for ia, a in enumerate(blk):
                if t[a] == 0:
                    continue
                for ib, b in enumerate(blk):
                    if inv[ia, ib] != 0 and s[b] != 0:
                        corr += t[a] * inv[ia, ib] * s[b]
        force = sum((Z[j, i] * lam[j] for j in range(side.m)), sp.S.Zero)
        XD.append(cancel(XH[i] - corr))
        X.append(cancel(XH[i] + force))
        diff.append(cancel(-corr - force))
    return sp.Matrix(XD), sp.Matrix(X), sp.Matrix(diff)
