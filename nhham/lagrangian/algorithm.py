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
index of the constraint φ_i in ``System.phi``, see :mod:`nhham.system.naming`).

:func:`run_algorithm` is the generic loop (used by both the Lagrangian and the
Hamiltonian side); its records are :mod:`nhham.lagrangian.records`, its trace as text
:mod:`nhham.render.trace`;
:func:`nhham.lagrangian.analysis.analyze_constraints` is the Lagrangian entry point.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import sympy as sp

from nhham.errors import BudgetExceeded, ComputationError
from nhham.lagrangian.adjugate import divide_out, scale_factors
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.graphs import Provenance
from nhham.lagrangian.projection import gradient_rows, tangency_equations, time_rates
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.expressions import short
from nhham.system.naming import multiplier_symbol
from nhham.lagrangian.records import AlgorithmRun, Evidence, Stage, solve_on

__all__ = [
    "run_algorithm",
    "constraint_kind",
    "rank_drop_warnings",
    "square_free",
]


def run_algorithm(base_field, vertical_fields, primary: Sequence, labels: Sequence[str],
                  manifold_factory: Callable[[tuple], Submanifold], *,
                  max_stages: int | None = None, multiplier_symbols: Sequence | None = None,
                  variables: Sequence | None = None, secondary_start: int = 0,
                  secondary_prefix: str = "secondary", scale=None,
                  closed_fields: Callable | None = None, time=None,
                  points_are_motions: bool = False,
                  field_conditions: Sequence = ()) -> AlgorithmRun:
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
    scale : sympy.Expr, optional
        Set when ``base_field`` and ``vertical_fields`` are δ ξ and δ Z for a
        function δ ≠ 0 on the domain, with polynomial entries (on TQ: δ W⁻¹ from
        :func:`nhham.lagrangian.adjugate.scaled_inverse`, δ = ``scale``). The
        tangency rows are then polynomials and are expanded, not cancelled; ranks,
        multipliers and projector are those of the unscaled fields; a λ-free
        condition is δ ψ and is stored as a new constraint with the factors of δ
        divided out (the zeros of ψ where δ ≠ 0). None (default): the fields are
        used as they are and every row is cancelled.
    closed_fields : callable, optional
        With ``scale``: ``closed_fields() -> (ξ, Z)``, the unscaled fields, formed only
        when ``base_field``, ``vertical_fields`` or ``dynamics`` of the run are asked
        for; default (ξ̃/δ, Z̃/δ).
    time : sympy.Symbol, optional
        The time t when the system depends on it (``System.time``): the tangency rows
        gain ∂χ/∂t (δ ∂χ/∂t with ``scale``), the field on ℝ × TQ being ∂/∂t + ξ; t is a
        parameter of M_k without a value (``DESIGN.md`` §2).
    points_are_motions : bool, optional
        False (default): an M_f of dimension 0 is inconsistent (isolated points, no
        motion of a system with external constraints). True: it is a final surface with
        no degree of freedom (the Dirac-Bergmann chain: L = -V(q) rests at the critical
        points of V).
    field_conditions : sequence of (str, sympy.Expr), optional
        Conditions on the field X = ξ + λ^i Z_i itself, each an expression in the
        variables affine in the multipliers (label, c): their rows (∂c/∂λ_i, c at λ = 0)
        join the tangency rows at every stage, and their λ-free combinations become
        constraints like the others. On T*Q for a singular L, a velocity constraint
        φ(q, v) with v = ∂H_T/∂p (affine in the u^a) is one. With them the run's
        ``projection`` (and so ``multipliers``) is None when the block uses such a row:
        the caller solves its block.

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
    seeded samples; see :mod:`nhham.lagrangian.submanifold`), and the block is chosen by
    conditioning at sample points when A is not constant. So a condition is as
    reliable as the rank decision it rests on, and every decision is recorded.

    Secondary constraints are stored as the numerator of ψ_j computed from the
    unreduced functions (so the paper's ψ = ξ_L(φ) reads as printed), or of its
    reduction on M_k when that is much smaller; factors without zeros (numbers,
    parameters, definite-sign factors) are dropped and repeated factors taken once,
    which keeps the zero set and the regularity of the constraint.

    Examples
    --------
    L = (x'^2 - y'^2)/2 - x^2/2 with phi = x' + y': C = -(1 - 1) = 0 and xi_L(phi) =
    -x, so x = 0 is a secondary constraint, its tangency x' = 0 another, and the tangency
    of x' = 0, x'' = -x - lambda = 0, fixes lambda = -x.

    >>> import sympy as sp
    >>> from nhham import Submanifold, System, run_algorithm
    >>> s = System(["x", "y"], "(x_dot**2 - y_dot**2)/2 - x**2/2", constraints=["x_dot + y_dot"])
    >>> x, y, vx, vy = s.coordinates + s.velocities
    >>> xi = sp.Matrix([vx, vy, -x, 0])       # x'' = -x, y'' = 0
    >>> Z = sp.Matrix([[0, 0, -1, 1]])         # -W^-1 mu^T with W = diag(1, -1), mu = (1, 1)
    >>> run = run_algorithm(xi, Z, s.phi, ["constraints[0]"], lambda eqs: Submanifold(s, eqs))
    >>> run.status, run.final_constraints, dict(run.multipliers)
    ('determined', (x_dot + y_dot, -x, -x_dot), {lambda_1: -x})
    >>> run.final_labels
    ('constraints[0]', 'secondary[0]', 'secondary[1]')
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

    graph = Provenance()
    for lab, chi in zip(labels, primary):
        graph = graph.with_node(lab, expr=chi, stage=1, kind=constraint_kind(lab))
    loop = _Loop(xi, Z, variables, lam, manifold_factory, graph, secondary_start,
                 secondary_prefix, scale=scale, closed_fields=closed_fields)
    loop.time = time
    loop.points_are_motions = points_are_motions
    loop.field_conditions = tuple((str(lab), sp.sympify(c)) for lab, c in field_conditions)
    for lab, c in loop.field_conditions:
        loop.graph = loop.graph.with_node(lab, expr=c, stage=1, kind=constraint_kind(lab))
    return loop.run(primary, labels, bound)


class _Loop:
    """State of one run of the algorithm (row caches, provenance, warnings)."""

    def __init__(self, xi, Z, variables, lam, factory, graph, start, prefix, scale=None,
                 closed_fields=None):
        self.xi, self.Z, self.variables, self.lam = xi, Z, variables, lam
        self.factory, self.graph = factory, graph
        self.next_secondary, self.prefix = start, prefix
        self.rows: dict = {}
        self.warnings: list[str] = []
        # Scaled fields (δ ξ, δ Z) have polynomial entries: rows are expanded, and the
        # factors of δ are divided out of conditions (they do not vanish on the domain).
        self.scaled = scale is not None
        self.scale = sp.S.One if scale is None else sp.sympify(scale)
        self.scale_factors = scale_factors(self.scale)
        self.closed_fields = closed_fields
        self.time = None  # the time t of a time-dependent system (run_algorithm's time)
        self.points_are_motions = False  # run_algorithm's points_are_motions
        self.field_conditions: tuple = ()  # run_algorithm's field_conditions

    # ------------------------------------------------------------ tangency rows
    def row(self, chi):
        """(dχ, Z_i(χ) for every i, ξ(χ)) cached by expression."""
        if chi not in self.rows:
            grad = gradient_rows([chi], self.variables)
            # Polynomial rows of scaled fields need no cancellation, only expansion.
            A, b = tangency_equations(grad, self.xi, self.Z, sp.expand if self.scaled else cancel,
                                      time_rates([chi], self.time, self.scale))
            self.rows[chi] = (grad, list(A.row(0)) if A.cols else [], b[0])
        return self.rows[chi]

    def unscaled(self, psi):
        """A condition δ ψ computed from scaled fields with the factors of δ divided
        out: the same zeros as ψ where δ ≠ 0 (``psi`` itself when δ = 1)."""
        return divide_out(psi, self.scale_factors) if self.scale_factors else psi

    def matrices(self, chis):
        A = sp.Matrix(len(chis), self.Z.rows, lambda j, i: self.row(chis[j])[1][i])
        b = sp.Matrix([self.row(c)[2] for c in chis]) if chis else sp.zeros(0, 1)
        if self.field_conditions:  # conditions on the field: rows of their own
            zero = {s: 0 for s in self.lam}
            Ac = sp.Matrix([[cancel(sp.diff(c, s)) for s in self.lam]
                            for _, c in self.field_conditions])
            bc = sp.Matrix([cancel(c.xreplace(zero)) for _, c in self.field_conditions])
            A, b = A.col_join(Ac), b.col_join(bc)
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
        labs = list(labs) + [lab for lab, _ in self.field_conditions]  # the rows' names
        evidence = []
        rank_dec = M.rank(A)
        r = int(rank_dec.value)
        if 0 not in A.shape:
            evidence.append(Evidence(f"rank of (Z_i(chi_j)) on M_{k}", rank_dec, f"rank {r}"))
            self._collect(f"stage {k}: rank of (Z_i(chi_j))", rank_dec)
        rows, cols, choice = M.regular_block(A, r) if r else ([], [], None)
        if r:
            if len(labs) > r or self.Z.rows > r:
                # The block is a choice only when A is not square and regular.
                evidence.append(Evidence(f"regular {r}x{r} block on M_{k}", choice,
                                         "rows " + ", ".join(labs[j] for j in rows)))
            self._rank_drop_check(k, M, A, rows, cols, chis)
        others = [j for j in range(len(labs)) if j not in rows]
        B = A.extract(rows, cols)
        coeffs = (solve_on(M, B.T, A.extract(others, cols).T)
                  if r and others else sp.zeros(r, len(others)))
        conditions, candidates, problem = [], [], None
        for pos, j in enumerate(others):
            c = coeffs[:, pos] if r else sp.zeros(0, 1)
            psi = cancel(b[j] - (c.T * b.extract(rows, [0]))[0]) if r else b[j]
            sources = [labs[j]] + [labs[rows[t]] for t in range(r) if c[t] != 0]
            # Recorded as ψ (its values at points are those of the unscaled route);
            # decided on δ ψ with the factors of δ divided out (same zeros, no division).
            conditions.append((labs[j], psi / self.scale if self.scale != 1 else psi))
            psi = self.unscaled(psi)
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
            index=k, constraints=tuple(chis), labels=tuple(labs[:len(chis)]),
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
            self.graph = self.graph.with_node(label, expr=expr, stage=k + 1, kind="secondary")
            for src in dict.fromkeys(sources):
                self.graph = self.graph.with_edge(src, label, stage=k, label=f"stage {k}")
        return new, labels, None

    def _rank_drop_check(self, k, M, A, rows, cols, chis):
        """Warn where the rank of A drops on M_k (the paper assumes it does not)."""
        det = cancel(A.extract(rows, cols).det(method="berkowitz"))
        det = self.unscaled(det)  # δ^r det B: the factors of δ do not vanish on the domain
        red = M.reduce(det) if M.exact else det
        if red.is_number or _sign_definite(red):
            return
        if M.exact and not M.reduction.residual:
            # Constant on M (e.g. a multiple of sin^2 + cos^2): every derivative in the
            # variables left free by the reduction vanishes.
            left = [s for s in red.free_symbols if s in self.variables]
            exact_zero = [M.vanishes(cancel(sp.diff(red, s))) for s in left]
            if all(d.value and d.method == "exact" for d in exact_zero):
                return
        try:
            points, _ = M.points()
        except ComputationError:
            return
        f = M.evaluator(sp.Matrix([red]))
        values = [complex(f(pt)[0, 0]) for pt in points]
        if max(abs(v - values[0]) for v in values) <= 1e-9 * max(1.0, abs(values[0])):
            return  # numerically constant on M_k (e.g. sin^2 + cos^2)
        try:
            zeros, _ = M.with_equations(tuple(chis) + (sp.numer(sp.together(red)),),
                                        samples=2).points()
        except ComputationError:
            return
        fA = M.evaluator(A)
        for pt in zeros:
            S = np.array(np.asarray(fA(pt)).astype(complex).real, dtype=float)
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
            provenance_data=self.graph, inconsistency=inconsistency,
            warnings=tuple(dict.fromkeys(self.warnings)), converged=converged,
            dimension=dimension, variables=self.variables,
            fields=self._closed_fields(), manifold=M,
            scaled_fields=_constant_fields(self.xi, self.Z, self.scale) if self.scaled else None,
            denominator=self.scale if self.scaled else None, time=self.time,
            field_conditions=self.field_conditions,
        )

    def _closed_fields(self):
        """``fields`` of the run: the unscaled (ξ, Z), formed on first use."""
        if not self.scaled:
            return _constant_fields(self.xi, self.Z)
        if self.closed_fields is not None:
            return self.closed_fields
        xi, Z, scale = self.xi, self.Z, self.scale
        return lambda: ((xi / scale).applyfunc(cancel), (Z / scale).applyfunc(cancel))

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
        if dim <= 0 and self.points_are_motions:
            return 0, None
        if dim <= 0:
            return 0, (f"stage {k}: M_f = M_{k} has dimension 0 ({how}): isolated points, "
                       f"no motion")
        return dim, None


def rank_drop_warnings(k, manifold, base_field, vertical_fields, variables, multipliers, A,
                       rows, cols, chis, scale=None) -> list:
    """Warnings where the rank of A = (Z_i(chi_j)) drops on M_k (the paper assumes it does
    not): the symbolic check of the loop, for callers that decided the rank elsewhere.
    ``scale``: δ when the fields (and A) are scaled by δ (see :func:`run_algorithm`)."""
    loop = _Loop(base_field, vertical_fields, tuple(variables), tuple(multipliers),
                 lambda eqs: manifold.with_equations(eqs), Provenance(), 0, "secondary",
                 scale=scale)
    loop._rank_drop_check(k, manifold, A, list(rows), list(cols), list(chis))
    return loop.warnings


# ================================================================= small helpers
def _constant_fields(*fields):
    return lambda: fields


def constraint_kind(label: str) -> str:
    if label.endswith(".lift"):
        return "lift"
    if label.startswith("holonomic"):
        return "holonomic"
    if label.startswith("secondary"):
        return "secondary"
    return "primary"


def _reduced(M, expr):
    return M.reduce(expr) if M.exact else cancel(expr)


def _exactly_empty(M):
    """A reason why M is empty, proved by the reduction (a nonzero constant residual)."""
    if not M.exact:
        return None
    # the fibre too: on T*Q the residual of a nonlinear (Chetaev) constraint is in p
    state = set(M.system.coordinates) | set(M.system.velocities) | set(M.fibre)
    for r in M.reduction.residual:
        if r.is_number and r != 0:
            return f"the reduction leaves the equation 0 = {r}"
        if r != 0 and not r.free_symbols & state:
            # Nonzero for generic parameters; where the parameter values make it vanish,
            # the verdict at the values substitutes them (nhham.verdict.values).
            return (f"the reduction leaves the equation 0 = {short(r)}, a nonzero function "
                    f"of the parameters alone (exact)")
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
    except BudgetExceeded:  # an expiry is not an undecided sign
        raise
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
    full = square_free(sp.numer(sp.together(psi)), state)
    if M.exact:
        red = square_free(sp.numer(sp.together(M.reduce(psi))), state)
        if sp.count_ops(full) > 2 * sp.count_ops(red) + 5:
            full = red
    return full


def square_free(expr, state):
    """``expr`` without factors free of zeros, each remaining factor once: the same zero
    set, and a regular equation where ``expr`` was a power (x**2 -> x).

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham.lagrangian.algorithm import square_free
    >>> x, y, k = sp.symbols("x y k")
    >>> square_free(-3*k*x**2*(y**2 + 1), {x, y})
    -x
    """
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
