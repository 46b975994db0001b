"""The records of a run of the constraint algorithm: its evidence, stages and result.

An :class:`AlgorithmRun` is frozen; what it derives (multipliers, dynamics, the
projectors P = id - Q) is formed on first use from its stages.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Callable, Mapping

import sympy as sp

from nhham.errors import ComputationError
from nhham.lagrangian.algebra import cancel, solve_linear, tidy, tidy_light
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.graphs import Provenance
from nhham.lagrangian.submanifold import Submanifold

__all__ = ["Evidence", "Stage", "AlgorithmRun", "tangency_matrix", "solve_on"]


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
    """

    status: str
    stages: tuple
    final_constraints: tuple
    final_labels: tuple
    rank: int | None
    block: tuple
    multiplier_symbols: tuple
    free_multiplier_symbols: tuple
    provenance_data: Provenance
    inconsistency: str | None
    warnings: tuple
    converged: bool
    dimension: int | None
    variables: tuple
    fields: Callable = field(compare=False, repr=False)
    manifold: Submanifold | None = field(default=None, compare=False, repr=False)
    scaled_fields: Callable | None = field(default=None, compare=False, repr=False)
    denominator: object = field(default=None, compare=False, repr=False)

    @cached_property
    def provenance(self):
        """The provenance as a ``networkx.DiGraph`` (see the class docstring)."""
        return self.provenance_data.graph()

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
        return _tangency_rhs(self.final_constraints, self.base_field, self.variables)

    @cached_property
    def _loop_fields(self):
        """(ξ, Z) as the loop used them: scaled by δ when ``scaled_fields`` is set."""
        if self.scaled_fields is None:
            return self.base_field, self.vertical_fields
        return self._scaled[:2]

    @cached_property
    def _loop_tangency(self):
        """(A, b) over the final constraints from the loop's fields (δ A, δ b if scaled)."""
        if self.scaled_fields is None:
            return self.tangency_matrix, self.tangency_rhs
        xi, Z = self._loop_fields
        return (tangency_matrix(self.final_constraints, Z, self.variables, expand=True),
                _tangency_rhs(self.final_constraints, xi, self.variables, expand=True))

    @cached_property
    def multipliers(self) -> Mapping:
        """Determined ``{λ^i: expression}`` (see the class docstring); the same from the
        scaled fields (δ cancels in λ_I = −B^{-1}(b_J + A[J, F] λ_F))."""
        if self.status == "inconsistent":
            return MappingProxyType({})
        A, b = self._loop_tangency
        rows, cols = list(self.block[0]), list(self.block[1])
        if not cols:
            return MappingProxyType({})
        free_cols = [i for i in range(len(self.multiplier_symbols)) if i not in cols]
        rhs = b.extract(rows, [0])
        if free_cols:
            rhs = rhs + A.extract(rows, free_cols) * sp.Matrix(
                [self.multiplier_symbols[i] for i in free_cols])
        solved = -solve_on(self.manifold, A.extract(rows, cols), rhs)
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
        # B from the loop's fields: Z_I^T B^{-1} does not change when Z is scaled by δ.
        Z = self._loop_fields[1]
        A = tangency_matrix([self.final_constraints[j] for j in rows], Z, self.variables,
                            expand=self.scaled_fields is not None)
        B = A.extract(list(range(len(rows))), list(cols)) if rows else sp.zeros(0, 0)
        return solve_on(self.manifold, B, grads) if rows else grads

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
        Z_I = self._loop_fields[1].extract(cols, list(range(N)))
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


def tangency_matrix(chis, Z, variables, expand: bool = False) -> sp.Matrix:
    """A_ji = Z_i(χ_j) for the listed constraints (``expand``: polynomial fields, the
    entries are expanded instead of cancelled)."""
    normal = sp.expand if expand else cancel
    rows = []
    for chi in chis:
        grad = sp.Matrix([[sp.diff(chi, s) for s in variables]])
        rows.append([normal((grad * Z.row(i).T)[0]) for i in range(Z.rows)])
    return sp.Matrix(rows) if rows else sp.zeros(0, Z.rows)


def _tangency_rhs(chis, xi, variables, expand: bool = False) -> sp.Matrix:
    """b_j = ξ(χ_j) for the listed constraints (``expand`` as in :func:`tangency_matrix`)."""
    if not chis:
        return sp.zeros(0, 1)
    normal = sp.expand if expand else cancel
    return sp.Matrix([normal((sp.Matrix([[sp.diff(c, s) for s in variables]]) * xi)[0])
                      for c in chis])


def solve_on(M, B, rhs):
    """B^{-1} rhs for a small B of functions regular on M (see :meth:`Submanifold.solve`)."""
    return solve_linear(B, rhs) if M is None else M.solve(B, rhs)
