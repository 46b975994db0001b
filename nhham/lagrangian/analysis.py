"""The constraint algorithm on a Lagrangian system: :func:`analyze_constraints`.

M_1 = {g = 0, g^c = 0, φ = 0}. The system is split into independent blocks
(constraints and coordinates that do not interact); on each block stage 1 is decided
first without W⁻¹ (:mod:`nhham.lagrangian.tangency`: the bordered matrix at exact
points, or at sampled points where there are none), which settles every system whose C
is regular on M_1; otherwise the symbolic loop of :mod:`nhham.lagrangian.algorithm` runs
with δ ξ_L and δ Z_i (:mod:`nhham.lagrangian.adjugate`: δ W⁻¹ has polynomial entries,
so the tangency rows are polynomials and W⁻¹ is not formed). The blocks' runs are
merged into one :class:`ConstraintAnalysis`, with the Frobenius integrability of the
constraint distribution derived on first use.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping, cast

import sympy as sp

from nhham.autonomy import require_autonomous
from nhham.lagrangian.decision import Assumption
from nhham.lagrangian.graphs import Provenance, connected_components
from nhham.lagrangian.engine import Policy, decide, policy_of
from nhham.lagrangian.points import jacobian_row
from nhham.lagrangian.algorithm import (
    constraint_kind,
    rank_drop_warnings,
    run_algorithm,
)
from nhham.lagrangian.records import (AlgorithmRun, ConstraintOutcome, Evidence, Stage,
                                      tangency_matrix)
from nhham.lagrangian.submanifold import Submanifold, has_real_point
from nhham.settings import SEED, check_options
from nhham.system.chetaev import NOT_APPLICABLE, constraint_records
from nhham.system.description import System
from nhham.system.expressions import short
from nhham.system.naming import multiplier_symbol

if TYPE_CHECKING:
    from nhham.lagrangian.geometry import LagrangianGeometry

__all__ = ["Block", "ConstraintAnalysis", "analyze_constraints"]


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
class ConstraintAnalysis(ConstraintOutcome):
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
    provenance_data : Provenance
        Nodes: constraint labels (``holonomic[0]``, ``holonomic[0].lift``,
        ``constraints[1]``, ``secondary[0]``) with attributes ``expr``, ``stage``,
        ``kind`` and ``block``; edges labelled by ``stage``: primary -> secondary -> ...
    provenance : networkx.DiGraph (computed on first use)
        The same as a graph (networkx is imported only then).
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
    policy : Policy
        The settings of every decision of the run.
    geometry : LagrangianGeometry
        The Lagrangian geometry of the whole system (W, F, ... formed on first use),
        shared with later questions about the same system.

    Derived on first use: ``multipliers``, ``dynamics``, ``free_multipliers``,
    ``integrability`` / ``integrable``
    (Frobenius test of the constraint distribution), ``projector_Q``,
    ``projector_P`` and :meth:`project` (the almost product structure on M_f).

    Examples
    --------
    The rolling disk: phi'' = 0, so the centre's acceleration R phi' theta' (-sin, cos)
    is -lambda/m, and M_f = M_1 has dimension 8 - 2.

    >>> from nhham import analyze_constraints, models
    >>> analysis = analyze_constraints(models.rolling_disk())
    >>> analysis.status, analysis.regular, analysis.dimension, analysis.integrable
    ('determined', True, 6, False)
    >>> dict(analysis.multipliers)
    {lambda_1: R*m*phi_dot*theta_dot*sin(theta), lambda_2: -R*m*phi_dot*theta_dot*cos(theta)}
    """

    system: System
    rank_C: int
    regular: bool
    dropped: tuple
    blocks: tuple
    options: Mapping
    policy: Policy = field(default_factory=Policy, compare=False, repr=False)
    geometry: object = field(default=None, compare=False, repr=False)

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
    def assumptions(self) -> tuple:
        """Every function the generic decisions of the run assumed not identically zero
        (:class:`~nhham.lagrangian.decision.Assumption`), in order: det W and the
        maximal minors of μ on M_1 (the premises), each stage's records, and the
        Frobenius terms when the distribution is not integrable."""
        system, stages = self.system, self.stages
        if not stages:
            return ()
        m1 = stages[0].constraints
        hessian = cast("LagrangianGeometry", self.geometry).hessian
        W = tuple(tuple(hessian.row(i)) for i in range(system.n))
        out = [Assumption("the Lagrangian is singular (det W = 0)", "det", W, m1, 1)]
        if system.m:
            mu = tuple(tuple(system.mu.row(i)) for i in range(system.m))
            out.append(Assumption("the constraint one-forms become dependent (a constraint "
                                  "is redundant)", "maximal minors", mu, m1, 1))
        for stage in stages:
            out += stage.assumptions
        if self.integrability.generic is False and system.m and system.n - system.m > 1:
            out.append(Assumption("the constraint distribution becomes integrable",
                                  "Frobenius terms", (), m1, 1))
        return tuple(out)

    @cached_property
    def integrability(self):
        """:class:`nhham.lagrangian.integrability.Integrability` of the constraint distribution."""
        from nhham.lagrangian.integrability import integrability

        return integrability(self.system, policy=self.policy)

    @cached_property
    def integrable(self) -> bool | None:
        """Whether ker μ is involutive (the constraints are secretly holonomic); None if
        undecidable."""
        return self.integrability.integrable

    @cached_property
    def projector_Q(self) -> sp.Matrix | None:
        """The paper's Q on M_f as a 2n x 2n matrix (block-diagonal over the blocks)."""
        return self._assemble("projector_Q")

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

    def to_dict(self, expressions: bool = True) -> dict:
        """The verdict of the run: sizes, rank of C and how it was decided, status,
        stages with their decisions, M_f, free multipliers, redundancy, integrability,
        inconsistency. JSON-ready; with ``expressions=False`` the constraints stay
        sympy expressions, for a renderer that writes them its own way."""
        expression = str if expressions else (lambda e: e)
        system = self.system
        first = self.stages[0].decisions if self.stages else ()
        return {
            "n": int(system.n),
            "m": int(system.m),
            "regular": bool(self.regular),
            "rank_c": int(self.rank_C),
            "rank_c_method": first[0].decision.method if first else "exact",
            "status": str(self.status),
            "stages": [s.to_dict(expressions) for s in self.stages],
            "final_labels": list(self.final_labels),
            "final_constraints": [expression(c) for c in self.final_constraints],
            "free_multipliers": int(self.free_multipliers),
            "free_multiplier_symbols": [s.name for s in self.free_multiplier_symbols],
            "redundant": [d.label for d in self.dropped],
            "integrable": self.integrable,
            "affine_parts": not system.is_linear,
            "inconsistency": self.inconsistency,
            "constraint_kinds": constraint_records(system),
            **({} if system.is_affine else {"integrability": NOT_APPLICABLE}),
        }

    def __repr__(self) -> str:
        name = getattr(self.system, "name", "") or "system"
        return (f"<ConstraintAnalysis of {name}: {self.status}, rank C = {self.rank_C}, "
                f"{len(self.stages)} stage(s), {len(self.final_constraints)} final "
                f"constraint(s), {self.free_multipliers} free multiplier(s)>")


def analyze_constraints(system, *, precision: int | None = None, samples: int = 6,
                        seed: int = SEED, max_stages: int | None = None, exact: bool = True,
                        decompose: bool = True, policy: Policy | None = None
                        ) -> ConstraintAnalysis:
    """Run the paper's constraint algorithm on a Lagrangian system.

    M_1 = {g = 0, g^c = 0, φ = 0} (holonomic constraints, their complete lifts, the
    affine constraints); the base field is ξ_L and the vertical fields are
    Z_i = −W^{AB} μ_iB ∂/∂v^A, one per φ_i (see :func:`run_algorithm`). Both enter
    multiplied by δ (δ = det W, or a factor of it, with δ W⁻¹ free of denominators:
    :mod:`nhham.lagrangian.adjugate`): the tangency equations, ranks, multipliers and
    secondary constraints are the same where W is regular, and no W⁻¹ is formed unless
    the closed forms (``dynamics``, ``tangency_matrix``) are asked for.

    Parameters
    ----------
    system : nhham.System
        Redundant constraints must already be dropped
        (``System(..., drop_redundant=True)``); they are reported in ``dropped``.
    precision, samples, seed, exact : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``, e.g. ``policy=Policy(exact=False)``.
    max_stages : int, optional
        Bound on the number of stages (default 2n of each block).
    decompose : bool, optional
        Split into independent blocks (constraints and coordinates that do not
        interact, the Lagrangian being a sum over the blocks) and analyse each on
        its own; False analyses the system as one block.
    policy : Policy, optional
        Every setting of the decisions (:class:`~nhham.lagrangian.engine.Policy`:
        precision and sampling of sampled decisions, ``exact=False`` to decide at
        sample points only, thresholds); default ``Policy()``.

    Returns
    -------
    ConstraintAnalysis

    Examples
    --------
    Example 3.1 of the paper: L = (q1'^2 + q2'^2 - q3'^2)/2 and phi = q2' + q3', so
    C = -(1 - 1) = 0 and xi_L(phi) = 0: no new constraint, one free multiplier.

    >>> from nhham import System, analyze_constraints
    >>> s = System(["q1", "q2", "q3"], "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...            constraints=["q2_dot + q3_dot"])
    >>> analysis = analyze_constraints(s)
    >>> analysis.status, analysis.rank_C, analysis.free_multiplier_symbols
    ('underdetermined', 0, (lambda_1,))
    >>> analysis.dynamics.T          # q2'' = -lambda_1, q3'' = lambda_1
    Matrix([[q1_dot, q2_dot, q3_dot, 0, -lambda_1, lambda_1]])
    """
    check_options("analyze_constraints", max_stages=max_stages)
    policy = policy_of(policy, "analyze_constraints", precision=precision, samples=samples,
                       seed=seed, exact=exact)
    opts = MappingProxyType(dict(precision=policy.precision, samples=policy.samples,
                                 seed=policy.seed, max_stages=max_stages, exact=policy.exact))
    specs = _decompose(system) if decompose else [_whole(system)]
    blocks, start = [], 0
    from nhham.lagrangian.geometry import lagrangian_geometry

    geometry = lagrangian_geometry(system, closed_form=None, policy=Policy(
        precision=policy.precision, samples=policy.samples, seed=policy.seed))
    for spec in specs:
        run = _run_block(system, spec, policy, max_stages, start, geometry)
        start += len(run.provenance_data.labels(kind="secondary"))
        blocks.append(Block(tuple(system.coordinates[i] for i in spec["coords"]),
                            tuple(spec["labels"]), run))
    _check_autonomous(system, blocks)
    return _merge(system, blocks, opts, policy, geometry)


def _check_autonomous(system, blocks) -> None:
    """Refuse secondary constraints that depend on an input: their tangency would need
    d/dt of the input, which a control law sets at run time. The time t is a parameter
    of M_k whose ∂χ/∂t the tangency rows carry (``run_algorithm``'s ``time``)."""
    moving = set(system.inputs)
    if not moving:
        return
    for block in blocks:
        for stage in block.run.stages:
            for label, chi in zip(stage.new_labels, stage.new_constraints):
                used = sorted(s.name for s in sp.sympify(chi).free_symbols & moving)
                require_autonomous("secondary", bool(used), label=label,
                                   expression=short(chi), names=", ".join(used))


# ------------------------------------------------------------- blocks and merging
def _m1_parts(system, hol_idx, phi_idx):
    """Primary constraints of M_1 with labels: g's, then the φ rows (lifts first)."""
    nh, names = len(system.holonomic), system.m1_labels
    exprs = [system.holonomic[i] for i in hol_idx] + [system.phi[p] for p in phi_idx]
    labels = [names[i] for i in hol_idx] + [names[nh + p] for p in phi_idx]
    return exprs, labels


def _whole(system):
    nh = len(system.holonomic)
    return {"coords": list(range(system.n)), "hol": list(range(nh)),
            "phi": list(range(system.m)), "lagrangian": system.lagrangian,
            "labels": _m1_parts(system, range(nh), range(system.m))[1]}


def _decompose(system):
    """Connected components of the constraint–coordinate graph.

    A coordinate is joined to the coordinates it shares a term of the Lagrangian with
    (a piece W_AC v^A v^C, b_A v^A or a term of V when L is quadratic in the
    velocities, a term of the expanded L otherwise) and to those its force depends on, and every
    constraint to the coordinates whose q or v it involves. Components without
    constraints are merged into one free block. Each block's Lagrangian is the sum
    of the terms of L in its coordinates, so L is a sum over the blocks by
    construction.
    """
    n, nh = system.n, len(system.holonomic)
    index = {}
    for i, (q, v) in enumerate(zip(system.coordinates, system.velocities)):
        index[q] = index[v] = i
    edges: list = []      # the coupling graph: ("q", A), ("g", k), ("c", p) nodes
    parts = getattr(system, "quadratic_parts", None)
    if parts is None:
        terms = sp.Add.make_args(sp.expand(system.lagrangian))
    else:
        # L's pieces W_AC v^A v^C, b_A v^A and the terms of V, not expanded (0.2 s on
        # the bicycle): a piece couples the coordinates it names, which only a
        # cancellation inside it could make fewer.
        W, v, n_ = parts.W, system.velocities, len(system.velocities)
        terms = tuple(
            [W[A, A] / 2 * v[A] ** 2 for A in range(n_) if W[A, A] != 0]
            + [W[A, C] * v[A] * v[C] for A in range(n_) for C in range(A + 1, n_)
               if W[A, C] != 0]
            + [b * v[A] for A, b in enumerate(parts.b) if b != 0]
            + [-t for t in sp.Add.make_args(parts.V) if t != 0])
    term_sets = []
    for t in terms:
        idx = sorted({index[s] for s in t.free_symbols if s in index})
        term_sets.append((t, idx))
        for a, b in zip(idx, idx[1:]):
            edges.append((("q", a), ("q", b)))
    if system.has_forces:  # a force on q^A couples A to the coordinates it depends on
        for A, f in enumerate(system.generalized_forces):
            for s in f.free_symbols:
                if s in index:
                    edges.append((("q", A), ("q", index[s])))
    for k, g in enumerate(system.holonomic):
        for s in g.free_symbols:
            if s in index:
                edges.append((("g", k), ("q", index[s])))
    for p in range(nh, system.m):
        for s in system.phi[p].free_symbols:
            if s in index:
                edges.append((("c", p), ("q", index[s])))
    nodes = [("q", i) for i in range(n)] + [x for edge in edges for x in edge]
    comps = [sorted(c, key=lambda x: (x[0] != "q", x[1]))
             for c in connected_components(nodes, edges)]
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
        self.constraint_kinds = tuple(system.constraint_kinds[p] for p in spec["phi"])
        self.is_affine = all(k == "affine" for k in self.constraint_kinds)
        self.n, self.m = len(self.coordinates), len(self.phi)
        self.state = self.coordinates + self.velocities
        self.mu = (sp.Matrix([[sp.diff(f, v) for v in self.velocities] for f in self.phi])
                   if self.phi else sp.zeros(0, self.n))
        self.hessian = sp.hessian(self.lagrangian, self.velocities)
        self.has_forces, self.inputs = system.has_forces, system.inputs
        self.time = system.time
        self.generalized_forces = sp.Matrix([system.generalized_forces[i]
                                             for i in spec["coords"]])

    def __repr__(self):
        return f"_BlockSystem({[q.name for q in self.coordinates]})"


def _run_block(system, spec, policy, max_stages, start, geometry):
    from nhham.lagrangian.geometry import LagrangianGeometry

    whole = len(spec["coords"]) == system.n
    view = system if whole else _BlockSystem(system, spec)
    geo = geometry if whole else LagrangianGeometry(
        view, precision=policy.precision, samples=policy.samples, seed=policy.seed)
    exprs, labels = _m1_parts(system, spec["hol"], spec["phi"])

    def factory(eqs):
        return Submanifold(view, eqs, precision=policy.precision, samples=policy.samples,
                           seed=policy.seed, exact=policy.exact)

    lam = [multiplier_symbol(p + 1) for p in spec["phi"]]
    run = _stage_one_at_points(view, geo, exprs, labels, lam, factory, policy) \
        if policy.exact else None
    bound = max_stages if max_stages is not None else 2 * len(spec["coords"])
    # C singular or λ-free conditions: the symbolic loop, with the fields scaled by
    # δ (δ W⁻¹ has polynomial entries, see nhham.lagrangian.adjugate), so that no
    # tangency row is a rational function and W⁻¹ is never formed; ξ_L and Z_i in
    # closed form only if the run's dynamics is asked for.
    run = run or run_algorithm(
        geo.scaled_euler_lagrange_field, geo.scaled_vertical_fields, exprs, labels, factory,
        max_stages=bound, multiplier_symbols=lam, variables=view.state,
        secondary_start=start, scale=geo.field_scale,
        closed_fields=lambda: (geo.euler_lagrange_field, geo.vertical_fields),
        time=view.time,
    )
    graph = run.provenance_data
    for i in spec["hol"]:
        lift = f"holonomic[{i}].lift"
        if graph.has_node(lift):
            graph = graph.with_edge(f"holonomic[{i}]", lift, stage=1,
                                    label="stage 1 (complete lift)")
    return replace(run, provenance_data=graph.with_attribute(
        "block", ",".join(q.name for q in view.coordinates)))




def _stage_one_at_points(view, geo, exprs, labels, lam, factory, policy):
    """The run when stage 1 decides everything at exact points, else None.

    When C is regular on M_1 and every λ-free condition vanishes there (decided by
    :func:`nhham.lagrangian.tangency.tangency_at_points`, no W⁻¹ formed), M_f = M_1
    and every multiplier is determined. Otherwise (no exact points, C singular,
    secondary constraints) the caller runs the symbolic algorithm, which produces
    the secondary constraints as expressions.
    """
    from nhham.lagrangian.tangency import Tangency

    m = len(view.phi)
    # F formed only where a point's right-hand side is read (a proof modulo p is not)
    tangency = Tangency(view, geo.hessian, lambda: geo.forcing, exprs)
    verdict = decide(tangency, factory(tuple(exprs)), policy)
    if verdict is None:
        return None  # no exact points and small: the symbolic route decides exactly
    if any(d.warnings for d in (verdict.rank, verdict.consistent)):
        return None  # doubtful at this precision: leave it to the full algorithm
    r = int(verdict.rank.value)
    if r != m or not verdict.consistent.value:
        return None
    if verdict.rank.scope and not has_real_point(view, view.holonomic, policy):
        return None  # points over F_p only (x^2 + y^2 + 1 = 0): the loop says M_1 is empty
    rows, cols = verdict.rows, verdict.cols
    others = [j for j in range(len(exprs)) if j not in rows]
    v = sp.Matrix(view.velocities)
    # Rows outside the block have dchi/dv = 0 (holonomic g): their condition is dg/dq . v.
    conditions = tuple((labels[j], sp.expand((sp.Matrix([[sp.diff(exprs[j], q) for q in
                                                           view.coordinates]]) * v)[0]))
                       for j in others)
    evidence = (
        Evidence("rank of (Z_i(chi_j)) on M_1", verdict.rank, f"rank {r}" + (
            "" if not r or geo.closed_form_affordable else
            f" ({_how_generic(verdict.rank)}; it drops exactly where det W det C = "
            "det [[W, mu^T], [mu, 0]] vanishes on M_1, not expanded at this size)")),
        Evidence("lambda-free conditions on M_1", verdict.consistent, "add nothing"),
    )
    stage = Stage(index=1, constraints=tuple(exprs), labels=tuple(labels), new_constraints=(),
                  new_labels=(), rank=r, augmented_rank=r,
                  block=(tuple(labels[j] for j in rows), tuple(lam[i] for i in cols)),
                  conditions=conditions, decisions=evidence)
    graph = Provenance()
    for lab, chi in zip(labels, exprs):
        graph = graph.with_node(lab, expr=chi, stage=1, kind=constraint_kind(lab))
    warnings = [w for d in (verdict.rank, verdict.consistent, verdict.jacobian_rank)
                for w in d.warnings]
    M = factory(tuple(exprs))
    if r and geo.closed_form_affordable:
        # Where the rank of C drops on M_1 (the paper assumes it does not): the
        # symbolic check needs A = (Z_i(chi_j)), affordable only for small blocks;
        # from the scaled fields (δ A: same rank, the factors of δ divided out).
        Z = geo.scaled_vertical_fields
        A = tangency_matrix(list(exprs), Z, tuple(view.state), expand=True)
        warnings += rank_drop_warnings(1, M, geo.scaled_euler_lagrange_field, Z, view.state,
                                       lam, A, rows, cols, exprs, scale=geo.field_scale)
    dimension = 2 * view.n - int(verdict.jacobian_rank.value)
    return AlgorithmRun(
        status="determined", stages=(stage,), final_constraints=tuple(exprs),
        final_labels=tuple(labels), rank=r, block=(tuple(rows), tuple(cols)),
        multiplier_symbols=tuple(lam), free_multiplier_symbols=(), provenance_data=graph,
        inconsistency=None, warnings=tuple(warnings), converged=True, dimension=dimension,
        variables=tuple(view.state),
        fields=lambda: (geo.euler_lagrange_field, geo.vertical_fields), manifold=M,
        scaled_fields=lambda: (geo.scaled_euler_lagrange_field, geo.scaled_vertical_fields,
                               geo.field_scale), time=view.time,
    )


def _state_positions(system, coords):
    pos = {q: i for i, q in enumerate(system.coordinates)}
    idx = [pos[q] for q in coords]
    return idx + [system.n + i for i in idx]


def _merge(system, blocks, opts, policy, geometry) -> ConstraintAnalysis:
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
        stages[-1] = replace(stages[-1], assumptions=_assumptions(system, geometry,
                                                                   stages[-1]))
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
    dims = [r.dimension for r in runs]
    return ConstraintAnalysis(
        system=system, status=status, stages=tuple(stages),
        final_constraints=sum((r.final_constraints for r in runs), ()),
        final_labels=sum((r.final_labels for r in runs), ()),
        rank_C=rank_C, regular=(rank_C == system.m),
        free_multiplier_symbols=free,
        dropped=tuple(getattr(system, "dropped", ())),
        provenance_data=Provenance.union(r.provenance_data for r in runs),
        blocks=tuple(blocks), inconsistency=inconsistency, warnings=tuple(warnings),
        converged=all(r.converged for r in runs),
        dimension=None if None in dims else sum(dims), options=opts, policy=policy, geometry=geometry,
    )


def _assumptions(system, geometry, stage) -> tuple:
    """What the generic decisions of stage k assumed not identically zero on M_k.

    The rank r of (Z_i(χ_j)) rests on the regular block (rows J, multipliers I):
    det [[W, μ_Iᵀ], [∂χ_J/∂v, 0]] = det W det (Z_i(χ_j))_{J, I}; every λ-free
    condition ψ_j found nonzero is a new constraint or the reason of an inconsistency.
    """
    k = stage.index
    index = dict(zip(stage.labels, stage.constraints))
    rows, cols = stage.block
    out = []
    if rows:
        W = tuple(tuple(geometry.hessian.row(i)) for i in range(system.n))
        mu_I = tuple(tuple(system.mu.row(int(s.name.rsplit("_", 1)[1]) - 1)) for s in cols)
        Jv = tuple(tuple(jacobian_row(index[lab], system.velocities)) for lab in rows)
        out.append(Assumption(f"the rank of (Z_i(chi_j)) on M_{k} drops below {len(rows)}"
                              + (" (C singular)" if k == 1 else ""), "bordered det",
                              (W, mu_I, Jv), stage.constraints, k))
    out += [Assumption(f"the condition from {label} on M_{k} vanishes", "value", (psi,),
                       stage.constraints, k) for label, psi in stage.conditions]
    return tuple(out)


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


def _how_generic(decision) -> str:
    """How a generic rank was found, in the words of its decision (never mixed)."""
    if decision.method == "exact":
        return "generic, proved at an exact point"
    if decision.method == "exact at points":
        return "generic, at random exact points with the stated error bound"
    return f"at {decision.samples} seeded points ({decision.precision}), not proved"
