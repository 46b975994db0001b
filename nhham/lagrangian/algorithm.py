"""The constraint algorithm of the paper's Section 3, for any number of constraints.

Given a base field ξ (the Euler–Lagrange field ξ_L on TQ, or X_H on T*Q), vertical
fields Z_i (one per multiplier λ^i) and the constraints χ_j defining M_1, a solution
of the constrained problem is a field X = ξ + λ^i Z_i tangent to the final constraint
submanifold M_f. On M_k the tangency equations are::

    0 = ξ(χ_j) + λ^i Z_i(χ_j)            (j over every constraint defining M_k)

written as A λ + b = 0 with A_ji = Z_i(χ_j) (rows: constraints, columns: multipliers)
and b_j = ξ(χ_j). With r = rank A on M_k and a regular r x r block B = A[J, I], every
row j outside J gives one λ-free combination (a row of the left null space of A)::

    ψ_j = b_j − A[j, I] B^{-1} b_J       (the Schur complement of b)

A ψ_j that vanishes on M_k adds nothing; one that is a nonzero constant or has no
zeros makes the problem inconsistent; any other is a new constraint and M_{k+1} is
cut out by it. When nothing new appears M_f = M_k and the multipliers of I are
determined, λ_I = −B^{-1}(b_J + A[J, F] λ_F), the m − r others (F) stay free. The
almost product structure on M_f is Q = Z_I^T B^{-1} dχ_J (the paper's
Q = (C')^{i'j'} Z_{j'} ⊗ dχ_{i'} built on the block), P = id − Q.

Conventions: vectors are sympy column matrices of length N = 2n in the order of the
manifold's variables (coordinates, then velocities or momenta); vertical fields are
the rows of an m x N matrix; the i-th multiplier is ``lambda_<i>`` (1-based, the
index of the constraint φ_i in ``System.phi``, see :mod:`nhham.symbols`).

:func:`run_algorithm` is the generic loop (used by both the Lagrangian and the
Hamiltonian side); :func:`analyze_constraints` is the Lagrangian entry point, which
also splits the system into independent blocks, reports dropped redundant constraints
and the Frobenius integrability of the constraint distribution.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from types import MappingProxyType
from typing import Callable, Mapping, Sequence

import networkx as nx
import numpy as np
import sympy as sp

from nhham.settings import SEED
from nhham.errors import ComputationError
from nhham.lagrangian.algebra import cancel, solve_linear, tidy, tidy_light
from nhham.lagrangian.submanifold import Decision, Submanifold
from nhham.system.expressions import short
from nhham.system.naming import multiplier_symbol

__all__ = [
    "Evidence",
    "Stage",
    "AlgorithmRun",
    "Block",
    "ConstraintAnalysis",
    "run_algorithm",
    "analyze_constraints",
]


# ====================================================================== records
@dataclass(frozen=True)
class Evidence:
    """One decision of the algorithm and what it was about.

    Attributes
    ----------
    subject : str
        What was decided (``"rank of (Z_i(chi_j)) on M_2"``,
        ``"condition from secondary[0]"``).
    decision : Decision
        The answer with its evidence (exact, or sampled with points,
        singular values and residuals).
    outcome : str
        What the algorithm did with it (``"adds nothing"``,
        ``"new constraint secondary[1]"``, ``"inconsistent"``).
    """

    subject: str
    decision: Decision
    outcome: str = ""

    # The decision's fields, for callers that treat the evidence as a Decision.
    @property
    def value(self):
        return self.decision.value

    @property
    def method(self) -> str:
        return self.decision.method

    @property
    def precision(self) -> str:
        return self.decision.precision

    @property
    def detail(self) -> str:
        return self.decision.detail

    @property
    def warnings(self) -> tuple:
        return self.decision.warnings

    def describe(self) -> str:
        """One line: subject, outcome and how it was decided."""
        text = f"{self.subject}: {self.decision.describe()}"
        return text + (f" -> {self.outcome}" if self.outcome else "")


@dataclass(frozen=True)
class Stage:
    """One stage k of the algorithm, on M_k.

    Attributes
    ----------
    index : int
        k (1-based; stage 1 works on M_1).
    constraints : tuple of sympy.Expr
        The cumulative list χ_1..χ_{m_k} of constraints defining M_k (primary ones
        first, then the secondary ones in the order they appeared).
    labels : tuple of str
        The label of each constraint (``constraints[0]``, ``holonomic[0]``,
        ``holonomic[0].lift``, ``secondary[0]``...).
    new_constraints : tuple of sympy.Expr
        The constraints found on M_k; with ``constraints`` they define M_{k+1}.
        Empty at the last stage of a consistent run.
    new_labels : tuple of str
        Labels of ``new_constraints`` (``secondary[<i>]``, numbered from 0 in order
        of appearance).
    rank : int
        rank of (Z_i(χ_j)) on M_k.
    augmented_rank : int
        rank of (Z_i(χ_j) | ξ(χ_j)) on M_k: ``rank`` when every λ-free condition
        vanishes (the paper's condition (7)), ``rank + 1`` otherwise.
    block : tuple
        ``(constraint labels J, multiplier symbols I)`` of the regular r x r block
        used to solve for λ_I and to write the conditions.
    conditions : tuple of (str, sympy.Expr)
        Each λ-free combination ψ_j with the label of the row j it comes from.
    decisions : tuple of Evidence
        Every decision taken at this stage with its evidence.
    """

    index: int
    constraints: tuple
    labels: tuple
    new_constraints: tuple
    new_labels: tuple
    rank: int
    augmented_rank: int
    block: tuple
    conditions: tuple
    decisions: tuple

    @property
    def consistent(self) -> bool:
        """True when the tangency equations on M_k are solvable as they stand."""
        return self.augmented_rank == self.rank


# ======================================================================= generic
@dataclass(frozen=True)
class AlgorithmRun:
    """Result of :func:`run_algorithm` on one (block of a) system.

    Attributes
    ----------
    status : {"determined", "underdetermined", "inconsistent"}
    stages : tuple of Stage
    final_constraints, final_labels : tuple
        The constraints defining M_f (the last stage's cumulative list).
    rank : int or None
        rank of (Z_i(χ_j)) on M_f (None if inconsistent before any rank).
    block : tuple
        ``(rows J, columns I)`` as indices into the final constraints and the
        multipliers: the regular block B = A[J, I] on M_f.
    multiplier_symbols : tuple of sympy.Symbol
        λ^1..λ^m in the order of the vertical fields.
    free_multiplier_symbols : tuple of sympy.Symbol
        The m − rank multipliers left free (the columns outside I).
    multipliers : Mapping (computed on first use)
        ``{λ^i: expression}`` for the determined multipliers, in the state and the
        free multiplier symbols: λ_I = −B^{-1}(b_J + A[J, F] λ_F) from the unreduced
        functions (valid on M_f); empty when inconsistent.
    dynamics : sympy.Matrix or None, shape (N, 1) (computed on first use)
        ξ + λ^i Z_i with the determined λ substituted and the free λ^α as symbols.
    tangency_matrix, tangency_rhs : sympy.Matrix (computed on first use)
        A_ji = Z_i(χ_j) and b_j = ξ(χ_j) over the final constraints.
    provenance : networkx.DiGraph
        Constraint labels as nodes (attributes ``expr``, ``stage``, ``kind``); an
        edge a -> b (attribute ``stage``) when the condition that produced b at
        that stage involves the tangency equation of a.
    inconsistency : str or None
        At which stage and why the problem has no solution.
    warnings : tuple of str
    converged : bool
        False when ``max_stages`` was hit while new constraints were still
        appearing (the status is then provisional).
    dimension : int or None
        dim M_f (N minus the rank of the Jacobian of the final constraints on M_f).
    variables : tuple
        The N variables.
    fields : callable
        ``fields() -> (ξ, Z)``: the base field and the rows Z_i, formed only when
        ``base_field``/``vertical_fields`` (or what needs them: multipliers,
        dynamics, projectors) are asked for.
    manifold : Submanifold or None
        M_f (the last M_k), for further decisions on it.
    """

    status: str
    stages: tuple
    final_constraints: tuple
    final_labels: tuple
    rank: int | None
    block: tuple
    multiplier_symbols: tuple
    free_multiplier_symbols: tuple
    provenance: nx.DiGraph
    inconsistency: str | None
    warnings: tuple
    converged: bool
    dimension: int | None
    variables: tuple
    fields: Callable = field(compare=False, repr=False)
    manifold: Submanifold | None = field(default=None, compare=False, repr=False)

    @cached_property
    def base_field(self) -> sp.Matrix:
        """ξ (N x 1); formed on first use (W⁻¹ in closed form on the Lagrangian side)."""
        return self.fields()[0]

    @cached_property
    def vertical_fields(self) -> sp.Matrix:
        """The rows Z_i (m x N); formed on first use."""
        return self.fields()[1]

    @cached_property
    def tangency_matrix(self) -> sp.Matrix:
        """A_ji = Z_i(χ_j) over the final constraints."""
        return _tangency_matrix(self.final_constraints, self.vertical_fields, self.variables)

    @cached_property
    def tangency_rhs(self) -> sp.Matrix:
        """b_j = ξ(χ_j) over the final constraints."""
        if not self.final_constraints:
            return sp.zeros(0, 1)
        return sp.Matrix([cancel((sp.Matrix([[sp.diff(c, s) for s in self.variables]])
                                  * self.base_field)[0]) for c in self.final_constraints])

    @cached_property
    def multipliers(self) -> Mapping:
        """Determined ``{λ^i: expression}`` (see the class docstring)."""
        if self.status == "inconsistent":
            return MappingProxyType({})
        A, b = self.tangency_matrix, self.tangency_rhs
        rows, cols = list(self.block[0]), list(self.block[1])
        if not cols:
            return MappingProxyType({})
        free_cols = [i for i in range(len(self.multiplier_symbols)) if i not in cols]
        rhs = b.extract(rows, [0])
        if free_cols:
            rhs = rhs + A.extract(rows, free_cols) * sp.Matrix(
                [self.multiplier_symbols[i] for i in free_cols])
        solved = -_solve_on(self.manifold, A.extract(rows, cols), rhs)
        return MappingProxyType({self.multiplier_symbols[i]: tidy(solved[pos])
                                 for pos, i in enumerate(cols)})

    @cached_property
    def dynamics(self) -> sp.Matrix | None:
        """ξ + λ^i Z_i with the determined λ and the free λ^α as symbols (N x 1)."""
        if self.status == "inconsistent":
            return None
        if not self.multiplier_symbols:
            return self.base_field.applyfunc(tidy)
        lam = sp.Matrix(self.multiplier_symbols).xreplace(dict(self.multipliers))
        return (self.base_field + self.vertical_fields.T * lam).applyfunc(tidy_light)

    @property
    def free_multipliers(self) -> int:
        """Number of free multipliers."""
        return len(self.free_multiplier_symbols)

    @cached_property
    def _block_solve(self):
        """B^{-1} dχ_J (r x N) on M_f, or None when inconsistent."""
        if self.status == "inconsistent":
            return None
        rows, cols = self.block
        grads = sp.Matrix([[sp.diff(self.final_constraints[j], s) for s in self.variables]
                           for j in rows]) if rows else sp.zeros(0, len(self.variables))
        A = _tangency_matrix([self.final_constraints[j] for j in rows], self.vertical_fields,
                             self.variables)
        B = A.extract(list(range(len(rows))), list(cols)) if rows else sp.zeros(0, 0)
        return _solve_on(self.manifold, B, grads) if rows else grads

    @cached_property
    def projector_Q(self) -> sp.Matrix | None:
        """Q = Z_I^T B^{-1} dχ_J as an N x N matrix (Q^2 = Q); None if inconsistent.

        The paper's Q = (C')^{i'j'} Z_{j'} ⊗ dχ_{i'} over the regular block: it maps
        Z_i (i in I) to itself and vanishes on vectors tangent to every χ_j (j in J).
        """
        if self._block_solve is None:
            return None
        N = len(self.variables)
        cols = list(self.block[1])
        if not cols:
            return sp.zeros(N, N)
        Z_I = self.vertical_fields.extract(cols, list(range(N)))
        return (Z_I.T * self._block_solve).applyfunc(cancel)

    @cached_property
    def projector_P(self) -> sp.Matrix | None:
        """P = id − Q (N x N); P(X) solves the constrained problem for every solution X."""
        Q = self.projector_Q
        return None if Q is None else sp.eye(len(self.variables)) - Q

    def project(self, X) -> sp.Matrix:
        """P(X) for a vector field X (N-vector); for X = ξ + λ^i Z_i this is ``dynamics``."""
        P = self.projector_P
        if P is None:
            raise ComputationError("the problem is inconsistent: there is no projector")
        return (P * sp.Matrix(X)).applyfunc(cancel)

    def __repr__(self) -> str:
        return (f"<AlgorithmRun: {self.status}, rank {self.rank}, {len(self.stages)} stage(s), "
                f"{len(self.final_constraints)} final constraint(s)>")

    def _repr_latex_(self) -> str:
        return _latex_summary(self.status, self.rank, self.final_labels,
                              self.final_constraints, self.free_multiplier_symbols,
                              len(self.stages))

    def report(self) -> str:
        """Stages, ranks, decisions with their evidence, and the outcome."""
        return "\n".join(_report_lines(self, header="Constraint algorithm"))

    def __str__(self):
        return self.report()


def run_algorithm(base_field, vertical_fields, primary: Sequence, labels: Sequence[str],
                  manifold_factory: Callable[[tuple], Submanifold], *,
                  max_stages: int | None = None, multiplier_symbols: Sequence | None = None,
                  variables: Sequence | None = None, secondary_start: int = 0,
                  secondary_prefix: str = "secondary") -> AlgorithmRun:
    """Run the constraint algorithm (paper §3) for any number of constraints.

    Parameters
    ----------
    base_field : sympy.Matrix, shape (N, 1)
        The unconstrained field ξ in the manifold's variables: ξ_L = (v, W^{-1}F) on
        TQ, or X_H on T*Q.
    vertical_fields : sympy.Matrix, shape (m, N)
        Row i is the field Z_i multiplying λ^i: Z_i = −W^{AB} μ_iB ∂/∂v^A on TQ,
        Z_i^H = −μ_iA ∂/∂p_A on T*Q. Their action on any function ψ is
        Z_i(ψ) = dψ · Z_i, so secondary constraints of any form are handled.
    primary : sequence of sympy.Expr
        The constraints defining M_1 (= 0 each). Tangency to every one of them is
        imposed: list holonomic constraints g(q) too (their tangency condition is
        their complete lift, which must then also be in the list).
    labels : sequence of str
        One label per primary constraint (provenance node names).
    manifold_factory : callable
        ``manifold_factory(equations) -> Submanifold`` builds M_k from its
        equations with the caller's precision, samples, seed, fibre and exactness
        settings (e.g. ``lambda eqs: Submanifold(system, eqs, fibre=momenta)``).
        Every rank and vanishing question is put to it.
    max_stages : int, optional
        Bound on the number of stages; default N (each stage that adds an
        independent constraint lowers dim M_k by one, so N always suffices). When
        hit, ``converged`` is False and a warning says so.
    multiplier_symbols : sequence of sympy.Symbol, optional
        Names of λ^i; default ``lambda_1..lambda_m``.
    variables : sequence of sympy.Symbol, optional
        The N variables of the vectors; default the manifold's ``variables``.
    secondary_start : int, optional
        Number of the first secondary constraint label (``secondary[<k>]``), so
        that blocks analysed separately get distinct labels.
    secondary_prefix : str, optional
        Stem of the labels of secondary constraints.

    Returns
    -------
    AlgorithmRun
        Stages, final constraints, determined and free multipliers, the family of
        dynamics, provenance, the projector on M_f, evidence and warnings.

    Notes
    -----
    What is exact: the conditions ψ_j and the multipliers are symbolic (Schur
    complements with the chosen block, from unreduced functions); whether a rank
    or a vanishing holds on M_k is decided by the manifold (exact reduction, else
    seeded samples; see :mod:`nhham.onmanifold`), and the block is chosen by
    conditioning at sample points when A is not constant. So a condition is as
    reliable as the rank decision it rests on, and every decision is recorded.

    Secondary constraints are stored as the numerator of ψ_j computed from the
    unreduced functions (so the paper's ψ = ξ_L(φ) reads as printed), or of its
    reduction on M_k when that is much smaller; factors without zeros (numbers,
    parameters, definite-sign factors) are dropped and repeated factors taken once,
    which keeps the zero set and the regularity of the constraint.
    """
    xi = sp.Matrix(base_field)
    Z = sp.Matrix(vertical_fields)
    if variables is None:
        variables = manifold_factory(()).variables
    variables = tuple(variables)
    N = len(variables)
    if xi.shape != (N, 1):
        raise ComputationError(f"base field has shape {xi.shape}; expected ({N}, 1)")
    m = Z.rows
    if m and Z.cols != N:
        raise ComputationError(f"vertical fields have {Z.cols} columns; expected {N}")
    if m == 0:
        Z = sp.zeros(0, N)
    lam = tuple(multiplier_symbols) if multiplier_symbols is not None else tuple(
        multiplier_symbol(i + 1) for i in range(m))
    if len(lam) != m:
        raise ComputationError(f"{len(lam)} multiplier symbols for {m} vertical fields")
    primary = [sp.sympify(c) for c in primary]
    labels = [str(s) for s in labels]
    if len(labels) != len(primary):
        raise ComputationError(f"{len(labels)} labels for {len(primary)} primary constraints")
    bound = N if max_stages is None else int(max_stages)

    graph = nx.DiGraph()
    for lab, chi in zip(labels, primary):
        graph.add_node(lab, expr=chi, stage=1, kind=_kind(lab))
    loop = _Loop(xi, Z, variables, lam, manifold_factory, graph, secondary_start,
                 secondary_prefix)
    return loop.run(primary, labels, bound)


class _Loop:
    """State of one run of the algorithm (row caches, provenance, warnings)."""

    def __init__(self, xi, Z, variables, lam, factory, graph, start, prefix):
        self.xi, self.Z, self.variables, self.lam = xi, Z, variables, lam
        self.factory, self.graph = factory, graph
        self.next_secondary, self.prefix = start, prefix
        self.rows: dict = {}
        self.warnings: list[str] = []

    # ------------------------------------------------------------ tangency rows
    def row(self, chi):
        """(dχ, Z_i(χ) for every i, ξ(χ)) cached by expression."""
        if chi not in self.rows:
            grad = sp.Matrix([[sp.diff(chi, s) for s in self.variables]])
            a = [cancel((grad * self.Z.row(i).T)[0]) for i in range(self.Z.rows)]
            b = cancel((grad * self.xi)[0])
            self.rows[chi] = (grad, a, b)
        return self.rows[chi]

    def matrices(self, chis):
        A = sp.Matrix(len(chis), self.Z.rows, lambda j, i: self.row(chis[j])[1][i])
        b = sp.Matrix([self.row(c)[2] for c in chis]) if chis else sp.zeros(0, 1)
        return A, b

    # ------------------------------------------------------------------ the loop
    def run(self, primary, labels, bound) -> AlgorithmRun:
        chis, labs = list(primary), list(labels)
        stages: list[Stage] = []
        inconsistency, converged = None, True
        M = None
        for k in range(1, bound + 1):
            M = self.factory(tuple(chis))
            empty = _exactly_empty(M)
            if empty:
                inconsistency = f"stage {k}: M_{k} is empty: {empty}"
                break
            try:
                stage, problem = self.stage(k, M, chis, labs)
            except ComputationError as exc:
                inconsistency = f"stage {k}: M_{k} appears to be empty: {exc}"
                break
            stages.append(stage)
            if problem:
                inconsistency = problem
                break
            if not stage.new_constraints:
                break  # M_f = M_k
            if k == bound:
                converged = False
                self.warnings.append(
                    f"stage bound {bound} hit while new constraints were still appearing "
                    f"({', '.join(stage.new_labels)}); the result is provisional")
                break
            chis += list(stage.new_constraints)
            labs += list(stage.new_labels)
        return self.finish(stages, chis, labs, M, inconsistency, converged)

    def stage(self, k, M, chis, labs):
        """Process M_k: rank, block, conditions; returns (Stage, inconsistency or None)."""
        A, b = self.matrices(chis)
        evidence = []
        rank_dec = M.rank(A)
        r = int(rank_dec.value)
        if 0 not in A.shape:
            evidence.append(Evidence(f"rank of (Z_i(chi_j)) on M_{k}", rank_dec, f"rank {r}"))
            self._collect(f"stage {k}: rank of (Z_i(chi_j))", rank_dec)
        rows, cols, choice = M.regular_block(A, r) if r else ([], [], None)
        if r:
            if len(chis) > r or self.Z.rows > r:
                # The block is a choice only when A is not square and regular.
                evidence.append(Evidence(f"regular {r}x{r} block on M_{k}", choice,
                                         "rows " + ", ".join(labs[j] for j in rows)))
            self._rank_drop_check(k, M, A, rows, cols, chis)
        others = [j for j in range(len(chis)) if j not in rows]
        B = A.extract(rows, cols)
        coeffs = (_solve_on(M, B.T, A.extract(others, cols).T)
                  if r and others else sp.zeros(r, len(others)))
        conditions, candidates, problem = [], [], None
        for pos, j in enumerate(others):
            c = coeffs[:, pos] if r else sp.zeros(0, 1)
            psi = cancel(b[j] - (c.T * b.extract(rows, [0]))[0]) if r else b[j]
            sources = [labs[j]] + [labs[rows[t]] for t in range(r) if c[t] != 0]
            conditions.append((labs[j], psi))
            subject = f"condition from {labs[j]} on M_{k}: 0 = {short(psi)}"
            dec = M.vanishes(psi)
            self._collect(f"stage {k}: {subject}", dec)
            if dec.value:
                evidence.append(Evidence(subject, dec, "adds nothing"))
                continue
            why = _no_zeros(M, psi)
            if why:
                evidence.append(Evidence(subject, dec, "inconsistent"))
                problem = (f"stage {k}: the consistency condition from {labs[j]}, "
                           f"0 = {short(_reduced(M, psi), 120)}, {why}")
                break
            candidates.append((psi, sources, subject, dec))
        new, new_labels = [], []
        if not problem:
            new, new_labels, problem = self._accept(k, M, chis, candidates, evidence)
        aug = r + (1 if (new or problem) else 0)
        stage = Stage(
            index=k, constraints=tuple(chis), labels=tuple(labs),
            new_constraints=tuple(new), new_labels=tuple(new_labels), rank=r,
            augmented_rank=aug,
            block=(tuple(labs[j] for j in rows), tuple(self.lam[i] for i in cols)),
            conditions=tuple(conditions), decisions=tuple(evidence),
        )
        self._block = (rows, cols)
        return stage, problem

    def _accept(self, k, M, chis, candidates, evidence):
        """Keep the candidates not implied by the ones kept before them.

        Returns (new constraints, their labels, inconsistency or None). When the kept
        candidates have no common zero on M_k they are the inconsistency, not new
        constraints (as for a condition that reduces to a nonzero constant).
        """
        kept = []
        for psi, sources, subject, dec in sorted(candidates, key=lambda t: sp.count_ops(t[0])):
            expr = _representative(M, psi)
            if kept:
                sub = M.with_equations(tuple(chis) + tuple(e for e, *_ in kept))
                implied = sub.vanishes(expr)
                self._collect(f"stage {k}: {subject} given the other new constraints", implied)
                if implied.value:
                    evidence.append(Evidence(subject + " (given the other new constraints)",
                                             implied, "implied by the other new constraints"))
                    continue
            kept.append((expr, sources, subject, dec))
        if not kept:
            return [], [], None
        exprs = tuple(e for e, *_ in kept)
        nxt = M.with_equations(tuple(chis) + exprs)
        problem = None
        empty = _exactly_empty(nxt)
        if empty:
            problem = f"stage {k}: the consistency conditions cut M_{k} down to the empty " \
                      f"set: {empty}"
        elif not M.exact or nxt.reduction.residual:
            try:
                nxt.points()
            except ComputationError as exc:
                problem = (f"stage {k}: the consistency conditions 0 = "
                           + ", 0 = ".join(short(e) for e in exprs)
                           + f" appear to have no common zero on M_{k} (sampled evidence: "
                           f"{exc})")
        if problem:
            for expr, sources, subject, dec in kept:
                evidence.append(Evidence(subject, dec, "inconsistent (no common zero)"))
            return [], [], problem
        new, labels = [], []
        for expr, sources, subject, dec in kept:
            label = f"{self.prefix}[{self.next_secondary}]"
            self.next_secondary += 1
            evidence.append(Evidence(subject, dec, f"new constraint {label} = {short(expr)}"))
            new.append(expr)
            labels.append(label)
            self.graph.add_node(label, expr=expr, stage=k + 1, kind="secondary")
            for src in dict.fromkeys(sources):
                self.graph.add_edge(src, label, stage=k, label=f"stage {k}")
        return new, labels, None

    def _rank_drop_check(self, k, M, A, rows, cols, chis):
        """Warn where the rank of A drops on M_k (the paper assumes it does not)."""
        det = cancel(A.extract(rows, cols).det(method="berkowitz"))
        red = M.reduce(det) if M.exact else det
        if red.is_number or _sign_definite(red):
            return
        if M.exact and not M.reduction.residual:
            # Constant on M (e.g. a multiple of sin^2 + cos^2): every derivative in the
            # variables left free by the reduction vanishes.
            left = [s for s in red.free_symbols if s in self.variables]
            if all(M._zero_test(cancel(sp.diff(red, s)))[0] is True for s in left):
                return
        try:
            points, _ = M.points()
        except ComputationError:
            return
        f = M._lambdify([red])
        values = [complex(M._evaluate(f, pt)[0]) for pt in points]
        if max(abs(v - values[0]) for v in values) <= 1e-9 * max(1.0, abs(values[0])):
            return  # numerically constant on M_k (e.g. sin^2 + cos^2)
        try:
            zeros, _ = M.with_equations(tuple(chis) + (sp.numer(sp.together(red)),),
                                        samples=2).points()
        except ComputationError:
            return
        fA = M._lambdify([A])
        for pt in zeros:
            S = np.array(M._matrix_at(fA, pt, A.shape).astype(complex).real, dtype=float)
            s = np.linalg.svd(S, compute_uv=False) if S.size else np.zeros(0)
            rank = int(np.sum(s > 1e-8 * max(1.0, s[0] if s.size else 0.0)))
            if rank < len(rows):
                where = ", ".join(f"{k_}={float(v):.4g}" for k_, v in pt.items()
                                  if k_ in self.variables)
                self.warnings.append(
                    f"stage {k}: the rank of (Z_i(chi_j)) is not constant on M_{k}: it drops "
                    f"from {len(rows)} to {rank} where {short(red)} = 0, e.g. at {where}")
                return

    def _collect(self, subject, decision):
        for w in decision.warnings:
            self.warnings.append(f"{subject}: {w}")

    # ------------------------------------------------------------------- finish
    def finish(self, stages, chis, labs, M, inconsistency, converged):
        m = self.Z.rows
        rank = stages[-1].rank if stages else None
        rows, cols = getattr(self, "_block", ([], []))
        dimension = None
        if inconsistency is None and M is not None:
            try:
                dimension, problem = self._dimension(M, chis, len(stages))
            except ComputationError as exc:
                dimension, problem = None, (f"stage {len(stages)}: M_f appears to be empty "
                                            f"({exc})")
            if problem:
                inconsistency = problem
        free = ()
        if inconsistency is None:
            free = tuple(self.lam[i] for i in range(m) if i not in cols)
        status = "inconsistent" if inconsistency else (
            "underdetermined" if free else "determined")
        if not converged and status != "inconsistent":
            self.warnings.append(f"status {status!r} is provisional: the stage bound was hit")
        return AlgorithmRun(
            status=status, stages=tuple(stages), final_constraints=tuple(chis),
            final_labels=tuple(labs), rank=rank, block=(tuple(rows), tuple(cols)),
            multiplier_symbols=self.lam, free_multiplier_symbols=free,
            provenance=self.graph, inconsistency=inconsistency,
            warnings=tuple(dict.fromkeys(self.warnings)), converged=converged,
            dimension=dimension, variables=self.variables,
            fields=_constant_fields(self.xi, self.Z), manifold=M,
        )

    def _dimension(self, M, chis, k):
        """dim M_f and, if it is 0 or M_f looks empty, the inconsistency message.

        When the exact reduction parametrises M_f (no residual equations), dim M_f is
        the number of variables left free by it; otherwise N minus the rank of the
        Jacobian of the residual equations in the remaining variables on M_f.
        """
        N = len(self.variables)
        if not chis:
            return N, None
        if M.exact:
            red = M.reduction
            left = [s for s in self.variables if s not in red.substitution]
            how = f"exact reduction eliminates {len(red.substitution)} variable(s)"
            if red.residual:
                M.points()  # raises ComputationError when no point is found
                J = sp.Matrix([[sp.diff(c, s) for s in left] for c in red.residual])
                dec = M.rank(J)
                self._collect(f"stage {k}: rank of the Jacobian of the final constraints", dec)
                rank = len(red.substitution) + int(dec.value)
                how += f", residual Jacobian of rank {dec.value} ({dec.method})"
            else:
                rank = len(red.substitution)
        else:
            M.points()
            J = sp.Matrix([[sp.diff(c, s) for s in self.variables] for c in chis])
            dec = M.rank(J)
            self._collect(f"stage {k}: rank of the Jacobian of the final constraints", dec)
            rank, how = int(dec.value), f"Jacobian of rank {dec.value} ({dec.method})"
        dim = N - rank
        if dim <= 0:
            return 0, (f"stage {k}: M_f = M_{k} has dimension 0 ({how}): isolated points, "
                       f"no motion")
        return dim, None


# ================================================================= small helpers
def _constant_fields(xi, Z):
    return lambda: (xi, Z)


def _kind(label: str) -> str:
    if label.endswith(".lift"):
        return "lift"
    if label.startswith("holonomic"):
        return "holonomic"
    if label.startswith("secondary"):
        return "secondary"
    return "primary"


def _tangency_matrix(chis, Z, variables):
    """A_ji = Z_i(χ_j) for the listed constraints."""
    rows = []
    for chi in chis:
        grad = sp.Matrix([[sp.diff(chi, s) for s in variables]])
        rows.append([cancel((grad * Z.row(i).T)[0]) for i in range(Z.rows)])
    return sp.Matrix(rows) if rows else sp.zeros(0, Z.rows)


def _solve_on(M, B, rhs):
    """B^{-1} rhs for a small B of functions regular on M (see :meth:`Submanifold.solve`)."""
    return solve_linear(B, rhs) if M is None else M.solve(B, rhs)


def _reduced(M, expr):
    return M.reduce(expr) if M.exact else cancel(expr)


def _exactly_empty(M):
    """A reason why M is empty, proved by the reduction (a nonzero constant residual)."""
    if not M.exact:
        return None
    for r in M.reduction.residual:
        if r.is_number and r != 0:
            return f"the reduction leaves the equation 0 = {r}"
    return None


def _no_zeros(M, psi):
    """Why the condition ψ has no zeros on M (exact reasons only), else None."""
    red = _reduced(M, psi)
    if red.is_number:
        return f"is the nonzero constant {red} on M ({'exact' if M.exact else 'sampled mode'})"
    if _sign_definite(red):
        return f"never vanishes ({short(red)} has a definite sign; exact)"
    return None


def _sign_definite(expr) -> bool:
    """True when sympy proves ``expr`` > 0 or < 0 for all real values of its symbols."""
    if sp.count_ops(expr) > 60:  # the assumption system gets slow; undecided
        return False
    syms = sorted(expr.free_symbols, key=sp.default_sort_key)
    real = {s: sp.Dummy(s.name, real=True) for s in syms}
    e = expr.xreplace(real)
    try:
        return bool(e.is_positive) or bool(e.is_negative)
    except Exception:  # pragma: no cover - assumption system failure
        return False


def _representative(M, psi):
    """The function stored as a new constraint: a simple function with ψ's zeros on M_k.

    The numerator of ψ as computed from the unreduced functions (so the paper's
    ψ = ξ_L(φ) reads as printed), or the numerator of its reduction on M_k when that
    is much smaller; in either, factors without zeros (numbers, functions of the
    parameters only, factors of definite sign) are dropped and repeated factors taken
    once, which leaves the zero set unchanged and keeps the constraint regular.
    """
    state = set(M.variables)
    full = _essential(sp.numer(sp.together(psi)), state)
    if M.exact:
        red = _essential(sp.numer(sp.together(M.reduce(psi))), state)
        if sp.count_ops(full) > 2 * sp.count_ops(red) + 5:
            full = red
    return full


def _essential(expr, state):
    """``expr`` without factors free of zeros, each remaining factor once."""
    if sp.count_ops(expr) > 200:
        return expr
    try:
        coeff, factors = sp.factor_list(expr)
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError,
            ValueError):  # pragma: no cover - not a polynomial in its generators
        return expr
    keep = [f for f, _ in factors if f.free_symbols & state and not _sign_definite(f)]
    if not keep:
        return expr  # a function without zeros: kept whole, the caller reports it
    out = sp.Mul(*keep)
    if coeff.is_number and coeff.is_negative:
        out = -out  # keep the sign the condition was computed with
    return sp.expand(out) if sp.count_ops(out) < 60 else out


# ================================================================ Lagrangian side
@dataclass(frozen=True)
class Block:
    """An independent block: constraints and coordinates that do not interact with
    the rest (a connected component of the constraint–coordinate graph).

    Attributes
    ----------
    coordinates : tuple of sympy.Symbol
    constraint_labels : tuple of str
        Labels of its primary constraints.
    run : AlgorithmRun
        The algorithm run on this block alone.
    """

    coordinates: tuple
    constraint_labels: tuple
    run: AlgorithmRun


@dataclass(frozen=True)
class ConstraintAnalysis:
    """What the constraint algorithm says about a Lagrangian system.

    Attributes
    ----------
    system : nhham.System
    status : {"determined", "underdetermined", "inconsistent"}
    stages : tuple of Stage
        Stage k of the whole system: ``constraints`` is the cumulative list
        defining M_k (the product of the blocks' M_k; a block that stopped earlier
        contributes its M_f), ``new_constraints`` the ones found on M_k, ``rank`` the
        rank of (Z_i(χ_j)) on M_k (summed over blocks), ``decisions`` every decision
        of every block at that stage (prefixed by the block's coordinates when there
        are several blocks).
    final_constraints, final_labels : tuple
        The constraints defining M_f.
    rank_C : int
        rank of C = (Z_i(φ_j)) on M_1.
    regular : bool
        True when C is regular on M_1 (rank_C == m).
    free_multiplier_symbols : tuple of sympy.Symbol
        The free λ^α (``lambda_<i>``, i the 1-based index in ``System.phi``).
    multipliers : Mapping (computed on first use)
        Determined ``{lambda_i: expression}`` in the state and the free λ^α.
    dynamics : sympy.Matrix or None, shape (2n, 1) (computed on first use)
        The family ξ_L + λ^i Z_i (determined λ substituted, free ones as symbols),
        in the order (q, v); None when inconsistent.
    dropped : tuple of nhham.DroppedConstraint
        Redundant constraints dropped before the algorithm ran
        (``System(..., drop_redundant=True)``).
    provenance : networkx.DiGraph
        Nodes: constraint labels (``holonomic[0]``, ``holonomic[0].lift``,
        ``constraints[1]``, ``secondary[0]``) with attributes ``expr``, ``stage``,
        ``kind`` and ``block``; edges labelled by ``stage``: primary -> secondary -> ...
    blocks : tuple of Block
        The independent blocks, each analysed on its own.
    inconsistency : str or None
        Stage and reason when there is no solution.
    warnings : tuple of str
    converged : bool
        False when the stage bound was hit.
    dimension : int or None
        dim M_f (0 for the inconsistent "isolated points" case, None when M_f is
        empty or was not reached).
    options : Mapping
        precision, samples, seed, exact, max_stages as used.
    geometry : LagrangianGeometry
        The Lagrangian geometry of the whole system (W, F, ... formed on first use),
        shared with later questions about the same system.

    Derived on first use: ``multipliers``, ``dynamics``, ``free_multipliers``,
    ``integrability`` / ``integrable``
    (Frobenius test of the constraint distribution), ``projector_Q``,
    ``projector_P`` and :meth:`project` (the almost product structure on M_f).
    """

    system: object
    status: str
    stages: tuple
    final_constraints: tuple
    final_labels: tuple
    rank_C: int
    regular: bool
    free_multiplier_symbols: tuple
    dropped: tuple
    provenance: nx.DiGraph
    blocks: tuple
    inconsistency: str | None
    warnings: tuple
    converged: bool
    dimension: int | None
    options: Mapping
    geometry: object = field(default=None, compare=False, repr=False)

    @property
    def free_multipliers(self) -> int:
        """Number of free multipliers."""
        return len(self.free_multiplier_symbols)

    @cached_property
    def multipliers(self) -> Mapping:
        """Determined ``{lambda_i: expression}`` over all blocks (computed on first use)."""
        out = {}
        for blk in self.blocks:
            out.update(blk.run.multipliers)
        return MappingProxyType(out)

    @cached_property
    def dynamics(self) -> sp.Matrix | None:
        """ξ_L + λ^i Z_i (2n x 1, free λ^α as symbols); None when inconsistent."""
        if self.status == "inconsistent":
            return None
        out = sp.zeros(2 * self.system.n, 1)
        for blk in self.blocks:
            for a, i in enumerate(_state_positions(self.system, blk.coordinates)):
                out[i] = blk.run.dynamics[a]
        return out

    @cached_property
    def integrability(self):
        """:class:`nhham.integrability.Integrability` of the constraint distribution."""
        from nhham.lagrangian.integrability import integrability

        opts = self.options
        return integrability(self.system, precision=opts["precision"],
                             samples=opts["samples"], seed=opts["seed"],
                             exact=opts["exact"])

    @cached_property
    def integrable(self) -> bool | None:
        """Whether ker μ is involutive (the constraints are secretly holonomic); None if
        undecidable."""
        return self.integrability.integrable

    @cached_property
    def projector_Q(self) -> sp.Matrix | None:
        """The paper's Q on M_f as a 2n x 2n matrix (block-diagonal over the blocks)."""
        return self._assemble("projector_Q")

    @cached_property
    def projector_P(self) -> sp.Matrix | None:
        """P = id − Q on M_f (2n x 2n); P(X) solves the problem for every solution X."""
        Q = self.projector_Q
        return None if Q is None else sp.eye(2 * self.system.n) - Q

    def project(self, X) -> sp.Matrix:
        """P(X) for a field X = ξ_L + λ^i Z_i (any λ), shape (2n, 1)."""
        P = self.projector_P
        if P is None:
            raise ComputationError("the problem is inconsistent: there is no projector")
        return (P * sp.Matrix(X)).applyfunc(cancel)

    def _assemble(self, name):
        n = self.system.n
        out = sp.zeros(2 * n, 2 * n)
        for blk in self.blocks:
            part = getattr(blk.run, name)
            if part is None:
                return None
            idx = _state_positions(self.system, blk.coordinates)
            for a, ia in enumerate(idx):
                for c, ic in enumerate(idx):
                    out[ia, ic] = part[a, c]
        return out

    def __repr__(self) -> str:
        name = getattr(self.system, "name", "") or "system"
        return (f"<ConstraintAnalysis of {name}: {self.status}, rank C = {self.rank_C}, "
                f"{len(self.stages)} stage(s), {len(self.final_constraints)} final "
                f"constraint(s), {self.free_multipliers} free multiplier(s)>")

    def _repr_latex_(self) -> str:
        """M_f and the verdict in the paper's notation (for notebooks)."""
        return _latex_summary(self.status, self.rank_C, self.final_labels,
                              self.final_constraints, self.free_multiplier_symbols,
                              len(self.stages), _dot_names(self.system))

    def report(self) -> str:
        """Stages, ranks, decisions with their evidence, outcome, warnings."""
        lines = _report_lines(self, header=f"Constraint analysis of {self.system!r}")
        if self.dropped:
            lines.insert(1, "dropped redundant constraints: " + "; ".join(
                f"{d.label} = " + " + ".join(f"({c})*{k}" for k, c in d.combination.items())
                for d in self.dropped))
        if len(self.blocks) > 1:
            lines.insert(1, f"{len(self.blocks)} independent blocks: " + "; ".join(
                f"[{', '.join(q.name for q in b.coordinates)}] with "
                f"{', '.join(b.constraint_labels) or 'no constraints'}: {b.run.status}"
                for b in self.blocks))
        try:
            integ = self.integrability.describe()
        except Exception as exc:  # pragma: no cover - report must not fail
            integ = f"not decided ({exc})"
        lines.append(f"integrability of the constraint distribution: {integ}")
        return "\n".join(lines)

    def __str__(self):
        return self.report()


def analyze_constraints(system, *, precision: int | None = None, samples: int = 6,
                        seed: int = SEED, max_stages: int | None = None, exact: bool = True,
                        decompose: bool = True) -> ConstraintAnalysis:
    """Run the paper's constraint algorithm on a Lagrangian system.

    M_1 = {g = 0, g^c = 0, φ = 0} (holonomic constraints, their complete lifts, the
    affine constraints); the base field is ξ_L and the vertical fields are
    Z_i = −W^{AB} μ_iB ∂/∂v^A, one per φ_i (see :func:`run_algorithm`).

    Parameters
    ----------
    system : nhham.System
        Redundant constraints must already be dropped
        (``System(..., drop_redundant=True)``); they are reported in ``dropped``.
    precision : int or None, optional
        Precision of sampled decisions: None for float64, an integer for mpmath with
        that many digits (slower, decides near-singular cases).
    samples, seed : int, optional
        Number and seed of the sample points of sampled decisions.
    max_stages : int, optional
        Bound on the number of stages (default 2n of each block).
    exact : bool, optional
        True: decide by exact reduction where possible and sample otherwise;
        False: decide every rank and vanishing at sample points only.
    decompose : bool, optional
        Split into independent blocks (constraints and coordinates that do not
        interact, the Lagrangian being a sum over the blocks) and analyse each on
        its own; False analyses the system as one block.

    Returns
    -------
    ConstraintAnalysis
    """
    opts = MappingProxyType(dict(precision=precision, samples=samples, seed=seed,
                                 max_stages=max_stages, exact=exact))
    specs = _decompose(system) if decompose else [_whole(system)]
    blocks, start = [], 0
    from nhham.lagrangian.geometry import LagrangianGeometry

    geometry = LagrangianGeometry(system, precision=precision, samples=samples, seed=seed)
    for spec in specs:
        run = _run_block(system, spec, opts, start, geometry)
        start += sum(1 for _, d in run.provenance.nodes(data=True) if d["kind"] == "secondary")
        blocks.append(Block(tuple(system.coordinates[i] for i in spec["coords"]),
                            tuple(spec["labels"]), run))
    return _merge(system, blocks, opts, geometry)


# ------------------------------------------------------------- blocks and merging
def _m1_parts(system, hol_idx, phi_idx):
    """Primary constraints of M_1 with labels: g's, then the φ rows (lifts first)."""
    labels_phi = system.constraint_labels
    nh = len(system.holonomic)
    exprs, labels = [], []
    for i in hol_idx:
        exprs.append(system.holonomic[i])
        labels.append(f"holonomic[{i}]")
    for p in phi_idx:
        exprs.append(system.phi[p])
        labels.append(f"{labels_phi[p]}.lift" if p < nh else labels_phi[p])
    return exprs, labels


def _whole(system):
    nh = len(system.holonomic)
    return {"coords": list(range(system.n)), "hol": list(range(nh)),
            "phi": list(range(system.m)), "lagrangian": system.lagrangian,
            "labels": _m1_parts(system, range(nh), range(system.m))[1]}


def _decompose(system):
    """Connected components of the constraint–coordinate graph.

    A coordinate is joined to the coordinates it shares a term of the expanded
    Lagrangian with (W, mixed Hessian or potential couplings), and every
    constraint to the coordinates whose q or v it involves. Components without
    constraints are merged into one free block. Each block's Lagrangian is the sum
    of the terms of L in its coordinates, so L is a sum over the blocks by
    construction.
    """
    n, nh = system.n, len(system.holonomic)
    index = {}
    for i, (q, v) in enumerate(zip(system.coordinates, system.velocities)):
        index[q] = index[v] = i
    G = nx.Graph()
    G.add_nodes_from(("q", i) for i in range(n))
    terms = sp.Add.make_args(sp.expand(system.lagrangian))
    term_sets = []
    for t in terms:
        idx = sorted({index[s] for s in t.free_symbols if s in index})
        term_sets.append((t, idx))
        for a, b in zip(idx, idx[1:]):
            G.add_edge(("q", a), ("q", b))
    for k, g in enumerate(system.holonomic):
        for s in g.free_symbols:
            if s in index:
                G.add_edge(("g", k), ("q", index[s]))
    for p in range(nh, system.m):
        for s in system.phi[p].free_symbols:
            if s in index:
                G.add_edge(("c", p), ("q", index[s]))
    comps = [sorted(c, key=lambda x: (x[0] != "q", x[1])) for c in nx.connected_components(G)]
    constrained, free = [], []
    for c in comps:
        coords = sorted(i for kind, i in c if kind == "q")
        hol = sorted(i for kind, i in c if kind == "g")
        phi = sorted(hol + [i for kind, i in c if kind == "c"])
        (constrained if phi else free).append((coords, hol, phi))
    if free:
        constrained.append((sorted(i for c in free for i in c[0]), [], []))
    if len(constrained) == 1:
        return [_whole(system)]
    specs = []
    for coords, hol, phi in sorted(constrained, key=lambda c: c[0][0]):
        cset = set(coords)
        L = sp.Add(*[t for t, idx in term_sets if idx and set(idx) <= cset])
        specs.append({"coords": coords, "hol": hol, "phi": phi, "lagrangian": L,
                      "labels": _m1_parts(system, hol, phi)[1]})
    return specs


class _BlockSystem:
    """A system-like view of one block (the attributes LagrangianGeometry and
    Submanifold read), without System's validation (a block may have m = n)."""

    def __init__(self, system, spec):
        self.name = f"{system.name} block" if system.name else "block"
        self.coordinates = tuple(system.coordinates[i] for i in spec["coords"])
        self.velocities = tuple(system.velocities[i] for i in spec["coords"])
        self.parameters = system.parameters
        self.parameter_values = system.parameter_values
        self.lagrangian = spec["lagrangian"]
        self.holonomic = tuple(system.holonomic[i] for i in spec["hol"])
        self.phi = tuple(system.phi[p] for p in spec["phi"])
        self.n, self.m = len(self.coordinates), len(self.phi)
        self.state = self.coordinates + self.velocities
        self.mu = (sp.Matrix([[sp.diff(f, v) for v in self.velocities] for f in self.phi])
                   if self.phi else sp.zeros(0, self.n))
        self.hessian = sp.hessian(self.lagrangian, self.velocities)

    def __repr__(self):
        return f"_BlockSystem({[q.name for q in self.coordinates]})"


def _run_block(system, spec, opts, start, geometry):
    from nhham.lagrangian.geometry import LagrangianGeometry

    whole = len(spec["coords"]) == system.n
    view = system if whole else _BlockSystem(system, spec)
    geo = geometry if whole else LagrangianGeometry(
        view, precision=opts["precision"], samples=opts["samples"], seed=opts["seed"])
    exprs, labels = _m1_parts(system, spec["hol"], spec["phi"])

    def factory(eqs):
        return Submanifold(view, eqs, precision=opts["precision"], samples=opts["samples"],
                           seed=opts["seed"], exact=opts["exact"])

    lam = [multiplier_symbol(p + 1) for p in spec["phi"]]
    run = _stage_one_at_points(view, geo, exprs, labels, lam, factory, opts) \
        if opts["exact"] else None
    bound = opts["max_stages"] if opts["max_stages"] is not None else 2 * len(spec["coords"])
    run = run or run_algorithm(
        geo.euler_lagrange_field, geo.vertical_fields, exprs, labels, factory,
        max_stages=bound, multiplier_symbols=lam, variables=view.state,
        secondary_start=start,
    )
    for i in spec["hol"]:
        lift = f"holonomic[{i}].lift"
        if run.provenance.has_node(lift):
            run.provenance.add_edge(f"holonomic[{i}]", lift, stage=1,
                                    label="stage 1 (complete lift)")
    block_name = ",".join(q.name for q in view.coordinates)
    for node in run.provenance.nodes:
        run.provenance.nodes[node]["block"] = block_name
    return run


# Systems up to this many coordinates get their closed forms (lambda, P(xi_L)) printed
# by report(); beyond, W^-1 written out is too large to be worth forming unasked.
CLOSED_FORM_SIZE = 4



def _stage_one_at_points(view, geo, exprs, labels, lam, factory, opts):
    """The run when stage 1 decides everything at exact points, else None.

    When C is regular on M_1 and every λ-free condition vanishes there (decided by
    :func:`nhham.lagrangian.tangency.tangency_at_points`, no W⁻¹ formed), M_f = M_1
    and every multiplier is determined. Otherwise (no exact points, C singular,
    secondary constraints) the caller runs the symbolic algorithm, which produces
    the secondary constraints as expressions.
    """
    from nhham.lagrangian.points import NotExact
    from nhham.lagrangian.tangency import tangency_at_points, tangency_sampled

    m = len(view.phi)
    try:
        verdict = tangency_at_points(view, geo.hessian, geo.forcing, exprs, seed=opts["seed"])
    except NotExact:
        if view.n <= CLOSED_FORM_SIZE:
            return None  # small: the symbolic route decides exactly
        sampled = Submanifold(view, tuple(exprs), precision=opts["precision"],
                              samples=opts["samples"], seed=opts["seed"], exact=False)
        verdict = tangency_sampled(view, geo.hessian, geo.forcing, exprs, sampled)
        if any(d.warnings for d in (verdict.rank, verdict.consistent)):
            return None  # doubtful at this precision: leave it to the full algorithm
    r = int(verdict.rank.value)
    if r != m or not verdict.consistent.value:
        return None
    rows, cols = verdict.rows, verdict.cols
    others = [j for j in range(len(exprs)) if j not in rows]
    v = sp.Matrix(view.velocities)
    # Rows outside the block have dchi/dv = 0 (holonomic g): their condition is dg/dq . v.
    conditions = tuple((labels[j], sp.expand((sp.Matrix([[sp.diff(exprs[j], q) for q in
                                                           view.coordinates]]) * v)[0]))
                       for j in others)
    evidence = (
        Evidence("rank of (Z_i(chi_j)) on M_1", verdict.rank, f"rank {r}"),
        Evidence("lambda-free conditions on M_1", verdict.consistent, "add nothing"),
    )
    stage = Stage(index=1, constraints=tuple(exprs), labels=tuple(labels), new_constraints=(),
                  new_labels=(), rank=r, augmented_rank=r,
                  block=(tuple(labels[j] for j in rows), tuple(lam[i] for i in cols)),
                  conditions=conditions, decisions=evidence)
    graph = nx.DiGraph()
    for lab, chi in zip(labels, exprs):
        graph.add_node(lab, expr=chi, stage=1, kind=_kind(lab))
    warnings = [w for d in (verdict.rank, verdict.consistent, verdict.jacobian_rank)
                for w in d.warnings]
    M = factory(tuple(exprs))
    if r and geo.closed_form_affordable:
        # Where the rank of C drops on M_1 (the paper assumes it does not): the
        # symbolic check needs A = (Z_i(chi_j)), affordable only for small blocks.
        loop = _Loop(geo.euler_lagrange_field, geo.vertical_fields, tuple(view.state), lam,
                     factory, nx.DiGraph(), 0, "secondary")
        A = _tangency_matrix(list(exprs), geo.vertical_fields, tuple(view.state))
        loop._rank_drop_check(1, M, A, list(rows), list(cols), list(exprs))
        warnings += loop.warnings
    dimension = 2 * view.n - int(verdict.jacobian_rank.value)
    return AlgorithmRun(
        status="determined", stages=(stage,), final_constraints=tuple(exprs),
        final_labels=tuple(labels), rank=r, block=(tuple(rows), tuple(cols)),
        multiplier_symbols=tuple(lam), free_multiplier_symbols=(), provenance=graph,
        inconsistency=None, warnings=tuple(warnings), converged=True, dimension=dimension,
        variables=tuple(view.state),
        fields=lambda: (geo.euler_lagrange_field, geo.vertical_fields), manifold=M,
    )


def _state_positions(system, coords):
    pos = {q: i for i, q in enumerate(system.coordinates)}
    idx = [pos[q] for q in coords]
    return idx + [system.n + i for i in idx]


def _merge(system, blocks, opts, geometry) -> ConstraintAnalysis:
    runs = [b.run for b in blocks]
    K = max((len(r.stages) for r in runs), default=0)
    stages = []
    tags = [f"[{', '.join(q.name for q in b.coordinates)}] " if len(blocks) > 1 else ""
            for b in blocks]
    for k in range(1, K + 1):
        parts = [_tagged(r.stages[k - 1], tag) if k <= len(r.stages) else _frozen_stage(r, k)
                 for r, tag in zip(runs, tags)]
        parts = [p for p in parts if p is not None]
        stages.append(Stage(
            index=k,
            constraints=sum((p.constraints for p in parts), ()),
            labels=sum((p.labels for p in parts), ()),
            new_constraints=sum((p.new_constraints for p in parts), ()),
            new_labels=sum((p.new_labels for p in parts), ()),
            rank=sum(p.rank for p in parts),
            augmented_rank=sum(p.augmented_rank for p in parts),
            block=(sum((p.block[0] for p in parts), ()), sum((p.block[1] for p in parts), ())),
            conditions=sum((p.conditions for p in parts), ()),
            decisions=sum((p.decisions for p in parts), ()),
        ))
    bad = [(b, r) for b, r in zip(blocks, runs) if r.status == "inconsistent"]
    prefix = len(blocks) > 1
    inconsistency = None
    if bad:
        inconsistency = "; ".join(
            (f"block [{', '.join(q.name for q in b.coordinates)}]: " if prefix else "")
            + r.inconsistency for b, r in bad)
    free = sum((r.free_multiplier_symbols for r in runs), ())
    free = tuple(sorted(free, key=lambda s: int(s.name.split("_")[-1])
                        if s.name.split("_")[-1].isdigit() else 0))
    status = "inconsistent" if bad else ("underdetermined" if free else "determined")
    warnings = []
    for tag, r in zip(tags, runs):
        warnings += [(f"block {tag.strip()}: " if tag else "") + w for w in r.warnings]
    first = stages[0] if stages else None
    rank_C = first.rank if first else 0
    provenance = nx.compose_all([r.provenance for r in runs]) if runs else nx.DiGraph()
    dims = [r.dimension for r in runs]
    return ConstraintAnalysis(
        system=system, status=status, stages=tuple(stages),
        final_constraints=sum((r.final_constraints for r in runs), ()),
        final_labels=sum((r.final_labels for r in runs), ()),
        rank_C=rank_C, regular=(rank_C == system.m),
        free_multiplier_symbols=free,
        dropped=tuple(getattr(system, "dropped", ())), provenance=provenance,
        blocks=tuple(blocks), inconsistency=inconsistency, warnings=tuple(warnings),
        converged=all(r.converged for r in runs),
        dimension=None if None in dims else sum(dims), options=opts, geometry=geometry,
    )


def _tagged(stage, tag):
    """The stage with its decisions' subjects prefixed by the block they belong to."""
    if not tag:
        return stage
    return replace(stage, decisions=tuple(replace(e, subject=tag + e.subject)
                                          for e in stage.decisions))


def _frozen_stage(run, k):
    """A finished block seen at a later stage k: its M_f, nothing new."""
    if not run.stages or run.status == "inconsistent":
        return None
    last = run.stages[-1]
    return Stage(index=k, constraints=last.constraints, labels=last.labels,
                 new_constraints=(), new_labels=(), rank=last.rank,
                 augmented_rank=last.rank, block=last.block, conditions=(), decisions=())


# ------------------------------------------------------------------------ report
def _dot_names(system) -> dict:
    """LaTeX names \\dot{q} for the velocity symbols q_dot."""
    return {v: rf"\dot{{{sp.latex(q)}}}" for q, v in zip(system.coordinates,
                                                          system.velocities)}


def _latex_summary(status, rank, labels, constraints, free, stages, names=None) -> str:
    """$$-wrapped LaTeX: the verdict line and the constraints defining M_f."""
    names = names or {}
    rows = [rf"\text{{{status}}},\ \operatorname{{rank}} = {rank},\ {stages}"
            rf"\ \text{{stage(s)}},\ \text{{free}}: "
            + (", ".join(sp.latex(s) for s in free) or r"\text{none}")]
    rows += [rf"\text{{{lab}}}: &\ {sp.latex(c, symbol_names=names)} = 0"
             for lab, c in zip(labels, constraints)]
    return "$$\\begin{aligned}" + r" \\ ".join(rows) + "\\end{aligned}$$"


def _small(res) -> bool:
    """Closed forms are printed by the report only for small systems."""
    N = len(res.variables) if isinstance(res, AlgorithmRun) else 2 * res.system.n
    return N <= 2 * CLOSED_FORM_SIZE


def _report_lines(res, header):
    lines = [f"{header}: {res.status}"]
    if isinstance(res, ConstraintAnalysis):
        sysm = res.system
        lines.append(f"n = {sysm.n}, m = {sysm.m}; rank C on M_1 = {res.rank_C} "
                     f"({'regular' if res.regular else 'singular'}); options: "
                     + ", ".join(f"{k}={v}" for k, v in res.options.items()))
    for st in res.stages:
        lines.append(f"Stage {st.index}: M_{st.index} defined by {len(st.constraints)} "
                     f"constraint(s); rank (Z_i(chi_j)) = {st.rank}, augmented rank "
                     f"{st.augmented_rank}")
        for lab, chi in zip(st.labels, st.constraints):
            lines.append(f"    {lab}: {chi}")
        if st.block[0]:
            lines.append(f"  regular block: rows {', '.join(st.block[0])}; multipliers "
                         f"{', '.join(str(s) for s in st.block[1])}")
        for ev in st.decisions:
            lines.append("  - " + ev.describe())
        for lab, chi in zip(st.new_labels, st.new_constraints):
            lines.append(f"  new: {lab} = {chi}")
    if res.inconsistency:
        lines.append(f"INCONSISTENT: {res.inconsistency}")
    else:
        lines.append(f"M_f: {len(res.final_constraints)} constraint(s), dimension "
                     f"{res.dimension}")
        closed = "multipliers" in res.__dict__ or _small(res)
        if closed:
            for s, e in res.multipliers.items():
                lines.append(f"  {s} = {e}")
        else:
            lines.append("  multipliers and dynamics: not formed in closed form (W^-1 of a "
                         "large system); ask for .multipliers / .dynamics")
        lines.append("free multipliers: " + (", ".join(str(s) for s in
                                                    res.free_multiplier_symbols) or "none"))
        if closed and res.dynamics is not None:
            lines.append(f"dynamics: {list(res.dynamics)}")
    if not res.converged:
        lines.append("NOT CONVERGED: the stage bound was hit")
    for w in res.warnings:
        lines.append(f"WARNING: {w}")
    return lines
