"""The records of a run of the constraint algorithm: its evidence, stages and result.

An :class:`AlgorithmRun` is frozen; what it derives (multipliers, dynamics, the
projectors P = id - Q) is formed on first use from its stages.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Callable, Mapping, cast

import sympy as sp

from nhham.lagrangian.algebra import cancel, solve_linear, tidy, tidy_light
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.graphs import Provenance
from nhham.lagrangian.projection import (Projected, Projection, gradient_rows,
                                         tangency_equations, time_rates)
from nhham.lagrangian.submanifold import Submanifold

__all__ = ["Evidence", "Stage", "ConstraintOutcome", "AlgorithmRun", "tangency_matrix", "solve_on"]


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

    def describe(self) -> str:
        """One line: subject, outcome and how it was decided."""
        text = f"{self.subject}: {self.decision.describe()}"
        return text + (f" -> {self.outcome}" if self.outcome else "")

    def to_dict(self) -> dict:
        """Subject, outcome and how it was decided, JSON-ready."""
        return {"subject": self.subject, "outcome": self.outcome,
                **self.decision.to_dict(value=False)}


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
    assumptions : tuple of Assumption
        The functions the stage's generic decisions assumed not identically zero on
        M_k: the determinant of the regular block (its rank) and every λ-free
        condition (Lagrangian analyses; empty on T*Q).
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
    assumptions: tuple = ()

    @property
    def consistent(self) -> bool:
        """True when the tangency equations on M_k are solvable as they stand."""
        return self.augmented_rank == self.rank

    def to_dict(self, expressions: bool = True) -> dict:
        """Index, labels, constraints, rank and the decisions, JSON-ready (with
        ``expressions=False`` the constraints stay sympy expressions)."""
        return {"index": int(self.index), "labels": list(self.labels),
                "constraints": [str(c) if expressions else c for c in self.constraints],
                "rank": int(self.rank), "decisions": [e.to_dict() for e in self.decisions]}


# ======================================================================= generic
@dataclass(frozen=True, kw_only=True)
class ConstraintOutcome(Projected):
    """What the constraint algorithm concludes: the names a run on one block
    (:class:`AlgorithmRun`) and the whole system's analysis
    (:class:`~nhham.lagrangian.analysis.ConstraintAnalysis`) both answer, in one place
    (given by keyword).

    Attributes
    ----------
    status : {"determined", "underdetermined", "inconsistent"}
    stages : tuple of Stage
    final_constraints, final_labels : tuple
        The constraints defining M_f and their labels.
    free_multiplier_symbols : tuple of sympy.Symbol
        The multipliers left free.
    provenance_data : Provenance
        Which constraint generated which, stage by stage (plain nodes and edges);
        ``provenance`` is the same as a ``networkx.DiGraph``, formed on first use.
    inconsistency : str or None
        At which stage and why the problem has no solution.
    warnings : tuple of str
    converged : bool
        False when the stage bound was hit while new constraints were still appearing.
    dimension : int or None
        dim M_f.

    Each result derives ``multipliers``, ``dynamics`` and ``projector_Q``; ``projector_P``
    and ``project`` follow from Q (:class:`~nhham.lagrangian.projection.Projected`).
    """

    status: str
    stages: tuple
    final_constraints: tuple
    final_labels: tuple
    free_multiplier_symbols: tuple
    provenance_data: Provenance
    inconsistency: str | None
    warnings: tuple
    converged: bool
    dimension: int | None

    @cached_property
    def provenance(self):
        """The provenance as a ``networkx.DiGraph`` (networkx is imported only then)."""
        return self.provenance_data.graph()

    @property
    def free_multipliers(self) -> int:
        """Number of free multipliers."""
        return len(self.free_multiplier_symbols)


@dataclass(frozen=True)
class AlgorithmRun(ConstraintOutcome):
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
    provenance_data : Provenance
        Constraint labels as nodes (attributes ``expr``, ``stage``, ``kind``); an
        edge a -> b (attribute ``stage``) when the condition that produced b at
        that stage involves the tangency equation of a.
    provenance : networkx.DiGraph (computed on first use)
        The same as a graph (networkx is imported only then).
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
        ``base_field``/``vertical_fields`` (or what needs them: ``dynamics``,
        ``tangency_matrix``) are asked for. On TQ these are the closed forms with W⁻¹.
    manifold : Submanifold or None
        M_f (the last M_k), for further decisions on it.
    scaled_fields : callable or None
        ``scaled_fields() -> (δ ξ, δ Z, δ)``: the fields scaled by a function δ ≠ 0
        with polynomial entries (on TQ δ W⁻¹ is made of adjugates, see
        :mod:`nhham.lagrangian.adjugate`), formed on first use; None when the loop
        ran with ``fields`` as they are. The multipliers and the projector do not
        change under the scaling and are formed from these, so they need no W⁻¹.
    denominator : sympy.Expr or None
        δ when the loop ran with scaled fields (the denominator of W⁻¹ on TQ: the
        tangency equations, hence every result, hold where it does not vanish), else
        None.
    scale : sympy.Expr (computed on first use)
        δ of ``scaled_fields`` (1 when unscaled).
    time : sympy.Symbol or None
        The time t of a time-dependent system: b_j gains ∂χ_j/∂t (δ ∂χ_j/∂t for the
        scaled fields); None for an autonomous one.
    """

    rank: int | None
    block: tuple
    multiplier_symbols: tuple
    variables: tuple
    fields: Callable = field(compare=False, repr=False)
    manifold: Submanifold | None = field(default=None, compare=False, repr=False)
    scaled_fields: Callable | None = field(default=None, compare=False, repr=False)
    denominator: object = field(default=None, compare=False, repr=False)
    time: object = field(default=None, compare=False, repr=False)
    field_conditions: tuple = field(default=(), compare=False, repr=False)

    @cached_property
    def scale(self) -> sp.Expr:
        """δ, the factor of the scaled fields (1 when unscaled)."""
        if self.denominator is not None:
            return self.denominator
        return sp.S.One if self.scaled_fields is None else self._scaled[2]

    @cached_property
    def _scaled(self):
        return self.scaled_fields() if self.scaled_fields is not None else None

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
        return tangency_matrix(self.final_constraints, self.vertical_fields, self.variables)

    @cached_property
    def tangency_rhs(self) -> sp.Matrix:
        """b_j = ξ(χ_j) over the final constraints."""
        return _tangency_rhs(self.final_constraints, self.base_field, self.variables,
                             time=self.time)

    @cached_property
    def _loop_fields(self):
        """(ξ, Z) as the loop used them: scaled by δ when ``scaled_fields`` is set."""
        if self.scaled_fields is None:
            return self.base_field, self.vertical_fields
        return self._scaled[:2]

    @cached_property
    def projection(self) -> Projection | None:
        """The §4 projection on M_f over the regular block (rows J, multipliers I), from
        the loop's fields: C = (Z_i(χ_j))_{J, I}ᵀ, the free λ^α (columns F) in
        ξ(χ_J) + Z_F(χ_J) λ_F, solves on M_f; None when inconsistent. Its entries are
        as solved (``multipliers`` and ``projector_Q`` tidy them)."""
        if self.status == "inconsistent":
            return None
        rows, cols = list(self.block[0]), list(self.block[1])
        if any(j >= len(self.final_constraints) for j in rows):
            return None  # the block uses a condition on the field (run_algorithm's)
        N = len(self.variables)
        grads = gradient_rows([self.final_constraints[j] for j in rows], self.variables)
        xi, Z = self._loop_fields
        normal = sp.expand if self.scaled_fields is not None else cancel
        A = cast(sp.Matrix, tangency_equations(grads, None, Z, normal)[0])
        free = [i for i in range(len(self.multiplier_symbols)) if i not in cols]

        def derivatives():
            chis = [self.final_constraints[j] for j in rows]
            scale = self.scale if self.scaled_fields is not None else 1
            _, b = tangency_equations(grads, xi, None, normal,
                                      time_rates(chis, self.time, scale))
            if free:
                b = b + A.extract(list(range(len(rows))), free) * sp.Matrix(
                    [self.multiplier_symbols[i] for i in free])
            return b

        return Projection(None, Z.extract(cols, list(range(N))), grads,
                          matrix=A.extract(list(range(len(rows))), cols).T,
                          derivatives=derivatives,
                          solve=lambda B, rhs: solve_on(self.manifold, B, rhs))

    @cached_property
    def multipliers(self) -> Mapping:
        """Determined ``{λ^i: expression}`` (see the class docstring); the same from the
        scaled fields (δ cancels in λ_I = −B^{-1}(b_J + A[J, F] λ_F))."""
        cols = list(self.block[1])
        if self.status == "inconsistent" or not cols:
            return MappingProxyType({})
        if self.projection is None:  # the block uses a condition on the field
            return MappingProxyType(self._conditioned_multipliers())
        solved = self.projection.multipliers
        return MappingProxyType({self.multiplier_symbols[i]: tidy(solved[pos])
                                 for pos, i in enumerate(cols)})

    def rows(self, labels) -> tuple:
        """(A, b) of the rows named, A λ + b = 0: for a final constraint χ its tangency
        row (A_ji = Z_i(χ), b_j = ξ(χ) (+ ∂χ/∂t with ``time``), unscaled fields), for a ``field_conditions``
        entry c its coefficients of the multipliers and c at λ = 0."""
        lam = list(self.multiplier_symbols)
        zero = {s: 0 for s in lam}
        named = dict(zip(self.final_labels, self.final_constraints))
        conditions = dict(self.field_conditions)
        xi, Z = self.base_field, self.vertical_fields
        A, b = [], []
        for lab in labels:
            if lab in conditions:
                c = conditions[lab]
                A.append([cancel(sp.diff(c, s)) for s in lam])
                b.append(cancel(c.xreplace(zero)))
            else:
                grad = gradient_rows([named[lab]], self.variables)
                A.append([cancel((grad * Z.row(i).T)[0]) for i in range(len(lam))])
                rate = sp.diff(named[lab], self.time) if self.time is not None else 0
                b.append(cancel((grad * xi)[0] + rate))
        return sp.Matrix(len(A), len(lam), lambda r, i: A[r][i]), sp.Matrix(b)

    def _conditioned_multipliers(self) -> dict:
        """λ_I from the last stage's block when it has rows of ``field_conditions``
        (run_algorithm's), solved on M_f with the free λ as symbols."""
        labels, cols = self.stages[-1].block
        lam = list(self.multiplier_symbols)
        A, b = self.rows(labels)
        index = [lam.index(s) for s in cols]
        free = [i for i in range(len(lam)) if i not in index]
        rhs = -b
        if free:
            rhs -= A.extract(list(range(A.rows)), free) * sp.Matrix([lam[i] for i in free])
        sol = solve_on(self.manifold, A.extract(list(range(A.rows)), index), rhs)
        return {s: tidy(sol[k]) for k, s in enumerate(cols)}

    @cached_property
    def dynamics(self) -> sp.Matrix | None:
        """ξ + λ^i Z_i with the determined λ and the free λ^α as symbols (N x 1)."""
        if self.status == "inconsistent":
            return None
        if not self.multiplier_symbols:
            return self.base_field.applyfunc(tidy)
        lam = sp.Matrix(self.multiplier_symbols).xreplace(dict(self.multipliers))
        return (self.base_field + self.vertical_fields.T * lam).applyfunc(tidy_light)

    @cached_property
    def projector_Q(self) -> sp.Matrix | None:
        """Q = Z_I^T B^{-1} dχ_J as an N x N matrix (Q^2 = Q); None if inconsistent.

        The paper's Q = (C')^{i'j'} Z_{j'} ⊗ dχ_{i'} over the regular block: it maps
        Z_i (i in I) to itself and vanishes on vectors tangent to every χ_j (j in J);
        Z_I^T B^{-1} does not change when Z is scaled by δ.
        """
        if self.projection is None:
            return None
        return self.projection.projector_Q.applyfunc(cancel)

    def __repr__(self) -> str:
        return (f"<AlgorithmRun: {self.status}, rank {self.rank}, {len(self.stages)} stage(s), "
                f"{len(self.final_constraints)} final constraint(s)>")


def tangency_matrix(chis, Z, variables, expand: bool = False) -> sp.Matrix:
    """A_ji = Z_i(χ_j) for the listed constraints (``expand``: polynomial fields, the
    entries are expanded instead of cancelled; :func:`~nhham.lagrangian.projection.
    tangency_equations`)."""
    A, _ = tangency_equations(gradient_rows(list(chis), variables), None, Z,
                         sp.expand if expand else cancel)
    return A


def _tangency_rhs(chis, xi, variables, expand: bool = False, time=None) -> sp.Matrix:
    """b_j = ξ(χ_j) (+ ∂χ_j/∂t with ``time``) for the listed constraints (``expand`` as in
    :func:`tangency_matrix`)."""
    _, b = tangency_equations(gradient_rows(list(chis), variables), xi, None,
                         sp.expand if expand else cancel, time_rates(list(chis), time))
    return b


def solve_on(M, B, rhs):
    """B^{-1} rhs for a small B of functions regular on M (see :meth:`Submanifold.solve`)."""
    return solve_linear(B, rhs) if M is None else M.solve(B, rhs)
