"""Verdicts for every parameter value: where the classification changes.

An exact verdict of :func:`nhham.lagrangian.analysis.analyze_constraints` holds for
*generic* parameters: every decision assumed that some function of the state and the
parameters is not identically zero on M_k. This module records those functions, finds
the parameter values where they vanish identically in the state, and runs the ordinary
classification there, recursively, in the manner of comprehensive Gröbner systems.

The polynomial data each generic decision rests on (all with parameters kept symbolic):

* ``det W`` — the Lagrangian is regular (where it vanishes nhham does not apply);
* the maximal minors of μ — the constraint one-forms are independent (where they all
  vanish a constraint is redundant);
* for every stage k with rank r > 0, the determinant of the bordered block
  [[W, μ_Iᵀ], [∂χ_J/∂v, 0]] = det W · det (Z_i(χ_j))_{J, I} on M_k — the rank of
  (Z_i(χ_j)) on M_k (rank C at stage 1);
* every λ-free condition ψ_j found nonzero on M_k — a new constraint, or the reason of
  an inconsistency;
* when the constraint distribution is not integrable, every Frobenius term
  dμ_i(X_a, X_b) on Q_1 (where they all vanish it becomes integrable);
* the principal minor det B_RR of the bracket matrix B_ab = {χ_a, χ_b} on M_f over a
  maximal second-class set R (where it vanishes the first/second-class split changes).

A function f(q, v, p) is *exceptional* at parameter values p* where f(·, p*) vanishes
identically on M_k. It is evaluated exactly at random points of M_k (rational
coordinates and velocities, sines and cosines through rational points of the circle,
dependent velocities solved exactly) with the parameters as generators of the field
Q(p): each value is a rational function of the parameters, and the exceptional set is
the common zero set of the numerators of the values, which is that of the coefficients
of f (as a polynomial in the state) with probability ≥ 1 − D/2^62 per point. It is
split into the irreducible factors of their gcd (components of codimension 1) and the
solutions of what remains (lower-dimensional components). Every component is then
*verified*: its condition is substituted into the system (solved for a parameter when
linear, else by ``sympy.solve``, real branches only) and the ordinary classification is
run there, so a spurious component can only produce a case that repeats its parent's
verdict, and such cases are dropped.

Conditions with no real solution under the parameters' declared signs (``positive=``
names, or sympy assumptions on the parameter symbols) are dropped and reported.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import random
from dataclasses import dataclass, field
from functools import reduce
from types import MappingProxyType
from typing import Callable, Mapping, Sequence

import numpy as np
import sympy as sp
from mpmath.libmp import from_rational
from sympy import QQ
from sympy.external.gmpy import MPQ
from sympy.polys.domains import GF, RealField
from sympy.polys.matrices import DomainMatrix

from nhham.errors import InputError, NhhamError, SingularLagrangianError
from nhham.lagrangian.analysis import ConstraintAnalysis, analyze_constraints
from nhham.lagrangian.points import (
    FLOAT64,
    FloatMatrix,
    PRIME,
    Angle,
    NotExact,
    eliminate_coordinates,
    evaluate,
    jacobian_row,
    field_det,
    field_solve,
    maximal_minors,
    adjacent_column_sets,
)
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED
from nhham.system.description import System
from nhham.system.expressions import short

__all__ = [
    "Verdict",
    "Condition",
    "Case",
    "ParametricVerdict",
    "ValuesVerdict",
    "parametric_classification",
    "classification_at_values",
    "exceptional_conditions",
    "NEAR",
    "MAX_DEPTH",
]

# Default relative distance below which parameter values count as "near" an exceptional set.
NEAR = 1e-8
# Default bound on the depth of the recursion over cases.
MAX_DEPTH = 3
# Exact points per decision (each a proof of non-vanishing; the gcd of the values at
# several points gives the content of the function in the parameters).
POINTS = 3
# Size of the random state values: small numbers keep the arithmetic in Q(p) cheap. A
# value can only add a spurious factor to the gcd of the values (never hide a true
# component), and every component is verified by running the classification on it.
DRAW_BITS = 16
# Plain classification names the condition its values satisfy (symbolically) up to this
# n + m; beyond, the parameters involved are substituted by their values.
SYMBOLIC_VALUES_SIZE = 10
# Whether a datum vanishes at the values is decided modulo p first (nonzero there is a
# proof); near vanishing, its nearness is estimated at moved values in 200-bit floating
# point, where a determinant's rounding error is far below its change over 1e-4.
MODULAR = GF(PRIME)
SHIFT_FIELD = RealField(200)
# The estimate is made in float64 first and kept when it puts the values farther than
# NEAR * FLOAT_MARGIN from vanishing: float64 with pivoting would need a rounding error
# of 1e-4 relative to a datum's terms to move a distance below NEAR that far.
FLOAT_MARGIN = 1e4
# Beyond this many maximal minors of mu, the m (n - m) + 1 next to the pivot block.
MAX_MINORS = 120


# ====================================================================== results
@dataclass(frozen=True)
class Verdict:
    """The classification at one parameter case (the keys of ``nhham classify``).

    Attributes
    ----------
    status : {"determined", "underdetermined", "inconsistent", "invalid"}
        ``"invalid"`` where nhham does not apply (the Lagrangian is singular, or the
        system description fails validation); ``note`` says why.
    regular : bool or None
        C regular on M_1.
    rank_C : int or None
        rank C on M_1.
    stages : int
        Number of stages of the constraint algorithm.
    free_multipliers : int
    integrable : bool or None
        Frobenius integrability of the constraint distribution.
    first_class, second_class : int or None
        Counts of the final constraints on T*Q (None when inconsistent or not decided).
    redundant : tuple of str
        Labels of the constraints dropped as redundant.
    final_constraints : int
        Number of constraints defining M_f.
    dimension : int or None
        dim M_f.
    note : str or None
        Why the case is ``"invalid"``.
    system, analysis, classes
        The system the verdict was computed on (the case's condition substituted), its
        :class:`~nhham.lagrangian.analysis.ConstraintAnalysis` and, when a ``classes``
        function was given, its first/second-class result (not compared).
    """

    status: str
    regular: bool | None
    rank_C: int | None
    stages: int
    free_multipliers: int
    integrable: bool | None
    first_class: int | None
    second_class: int | None
    redundant: tuple = ()
    final_constraints: int = 0
    dimension: int | None = None
    note: str | None = None
    system: object = field(default=None, compare=False, repr=False)
    analysis: object = field(default=None, compare=False, repr=False)
    classes: object = field(default=None, compare=False, repr=False)

    FIELDS = ("status", "regular", "rank_C", "stages", "free_multipliers", "integrable",
              "first_class", "second_class", "redundant", "final_constraints", "dimension")

    def differences(self, other: "Verdict") -> tuple:
        """Names of the fields in which this verdict differs from ``other``."""
        return tuple(f for f in self.FIELDS if getattr(self, f) != getattr(other, f))

    def describe(self) -> str:
        """One line: the verdict's fields."""
        if self.status == "invalid":
            return f"invalid: {self.note}"
        yn = {True: "yes", False: "no", None: "undecided"}
        text = (f"C regular {yn[self.regular]} (rank {self.rank_C}), {self.status}, "
                f"{self.stages} stage(s), {self.free_multipliers} free multiplier(s), "
                f"integrable {yn[self.integrable]}")
        if self.first_class is not None:
            text += f", {self.first_class} first class, {self.second_class} second class"
        if self.redundant:
            text += f", redundant {', '.join(self.redundant)}"
        return text

    def to_dict(self) -> dict:
        """The verdict's fields as JSON-ready data."""
        # Counts get their own names: "stages" and "final_constraints" are lists in
        # classify's JSON (one type per key across the output).
        rename = {"rank_C": "rank_c", "stages": "stage_count",
                  "final_constraints": "final_constraint_count"}
        out = {rename.get(f, f): getattr(self, f) for f in self.FIELDS}
        out["redundant"] = list(self.redundant)
        out["note"] = self.note
        return out


@dataclass(frozen=True)
class Condition:
    """One component of an exceptional set: polynomial equations in the parameters.

    Attributes
    ----------
    equations : tuple of sympy.Expr
        Each = 0, factored, in the scene's parameter names.
    reasons : tuple of str
        Which generic decisions fail there.
    """

    equations: tuple
    reasons: tuple

    def describe(self) -> str:
        return ", ".join(f"{short(e)} = 0" for e in self.equations)


@dataclass(frozen=True)
class Case:
    """A set of parameter values with its own verdict.

    Attributes
    ----------
    conditions : tuple of sympy.Expr
        Equations (each = 0) in the parameters, factored.
    excluding : tuple of sympy.Expr
        Inequations (each != 0) that exclude the cases listed before this one. A
        sum of squares stands for "not all of these vanish".
    verdict : Verdict
    substitution : Mapping
        Parameter -> expression: how the case's system was obtained.
    reasons : tuple of str
        The generic decisions that fail on this set.
    """

    conditions: tuple
    excluding: tuple
    verdict: Verdict
    substitution: Mapping = field(default_factory=dict, compare=False)
    reasons: tuple = ()

    def holds_at(self, values: Mapping) -> bool | None:
        """Whether parameter values satisfy the conditions and inequations.

        ``values`` maps parameters (symbols or names) to numbers, read exactly (floats as
        their decimal text). None when a condition involves a parameter without a value.
        """
        values = {(k if isinstance(k, sp.Symbol) else sp.Symbol(str(k))): v
                  for k, v in values.items()}
        exprs = tuple(self.conditions) + tuple(self.excluding)
        if any(s not in values for e in exprs for s in sp.sympify(e).free_symbols):
            return None
        at = {p: _exact(v) for p, v in values.items()}
        return (all(sp.sympify(e).xreplace(at) == 0 for e in self.conditions)
                and all(sp.sympify(e).xreplace(at) != 0 for e in self.excluding))

    def describe(self) -> str:
        text = " and ".join(f"{short(e)} = 0" for e in self.conditions)
        if self.excluding:
            text += " (excluding " + ", ".join(f"{short(e)} = 0" for e in self.excluding) + ")"
        return text


@dataclass(frozen=True)
class ParametricVerdict:
    """Verdicts for every parameter value (see :func:`parametric_classification`).

    Attributes
    ----------
    generic : Verdict
        The verdict where no case's conditions hold.
    cases : tuple of Case
        The exceptional cases; a parameter point belongs to the first case whose
        conditions it satisfies (the ``excluding`` inequations say so explicitly).
    scene_case : int or None
        Index of the case the system's parameter values fall in (None: generic, or
        no values).
    dropped : tuple of (tuple of sympy.Expr, str)
        Conditions with no real solution under the declared signs, with the reason.
    notes : tuple of str
        Limits hit (depth bound, data not computed and why).
    warnings : tuple of str
        Parameter values near an exceptional set.
    parameters : tuple of sympy.Symbol
    positive : tuple of sympy.Symbol
        Parameters declared positive.
    values : Mapping
        The system's parameter values.
    """

    generic: Verdict
    cases: tuple
    scene_case: int | None
    dropped: tuple
    notes: tuple
    warnings: tuple
    parameters: tuple
    positive: tuple
    values: Mapping = field(default_factory=dict)

    @property
    def scene_verdict(self) -> Verdict:
        """The verdict at the system's parameter values."""
        return self.generic if self.scene_case is None else self.cases[self.scene_case].verdict

    def report(self) -> str:
        """The generic verdict, the cases, dropped conditions and where the values fall."""
        names = ", ".join(p.name for p in self.parameters) or "none"
        lines = [f"parameters: {names}"
                 + (f" (positive: {', '.join(p.name for p in self.positive)})"
                    if self.positive else "")]
        lines.append(f"generic: {self.generic.describe()}")
        for i, case in enumerate(self.cases):
            lines.append(f"case {i}: {case.describe()}")
            lines.append(f"  verdict: {case.verdict.describe()}")
            if case.reasons:
                lines.append(f"  why: {'; '.join(case.reasons)}")
        for eqs, why in self.dropped:
            lines.append(f"dropped: {', '.join(f'{short(e)} = 0' for e in eqs)} ({why})")
        if self.values:
            where = "generic" if self.scene_case is None else f"case {self.scene_case}"
            lines.append("values " + ", ".join(f"{p.name} = {v}" for p, v in self.values.items())
                         + f": {where}")
        lines += [f"note: {n}" for n in self.notes]
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def __str__(self):
        return self.report()


@dataclass(frozen=True)
class ValuesVerdict:
    """The verdict at a system's parameter values (see :func:`classification_at_values`).

    Attributes
    ----------
    verdict : Verdict
        The verdict that holds at the values.
    generic : Verdict
        The verdict for generic parameters (what the exact decisions give when they
        treat the parameters as indeterminates).
    conditions : tuple of sympy.Expr
        The exceptional conditions the values satisfy (empty: the values are generic).
    system : System
        The system the verdict was computed on (the conditions substituted).
    warnings : tuple of str
        Values near an exceptional set; the depth bound hit; every check that was not
        made and why (no exact points, a datum not evaluable): an unchecked answer is
        not silently a checked one.
    """

    verdict: Verdict
    generic: Verdict
    conditions: tuple
    system: object = field(compare=False, repr=False)
    warnings: tuple = ()

    @property
    def differs(self) -> bool:
        """True when the verdict at the values is not the generic one."""
        return self.verdict != self.generic


# ================================================================ entry points
def parametric_classification(system, *, positive: Sequence = (),
                              classes: Callable | None = None, max_depth: int = MAX_DEPTH,
                              precision: int | None = None, seed: int = SEED,
                              near: float = NEAR, points: int = POINTS) -> ParametricVerdict:
    """The verdict for generic parameters and every case where it changes.

    Parameters
    ----------
    system : nhham.System
        Parameter values, if any, are ignored for the cases (every parameter is
        treated as an indeterminate) and used only to place the system in a case.
    positive : sequence of str or sympy.Symbol, optional
        Parameters declared positive (masses, lengths); parameter symbols carrying
        sympy sign assumptions count as declared too.
    classes : callable, optional
        ``classes(analysis) -> result with first_class, second_class`` (e.g.
        :func:`nhham.hamiltonian.classification.classify_constraints`), called on
        every case's analysis; by default the counts come from the rank of the
        bracket matrix at exact points of M_f with the parameters symbolic.
    max_depth : int, optional
        Bound on the nesting of cases (a note says when it was hit).
    precision, seed
        As in :func:`~nhham.lagrangian.analysis.analyze_constraints`.
    near : float, optional
        Relative distance to an exceptional set below which the values are warned
        about.
    points : int, optional
        Exact points per decision datum.

    Returns
    -------
    ParametricVerdict

    Raises
    ------
    InputError
        On a ``positive`` name that is not a parameter of the system, or a bad
        ``max_depth``/``near``.
    """
    params = tuple(system.parameters)
    declared = _declared_positive(system, positive)
    if int(max_depth) != max_depth or max_depth < 0:
        raise InputError(f"max_depth: expected a non-negative integer, got {max_depth!r}")
    if not (near >= 0):
        raise InputError(f"near: expected a non-negative number, got {near!r}")
    opts = dict(classes=classes, precision=precision, seed=seed, points=points)
    base = _rebuild(system, {}, None)
    signs = _sign_dummies(params, declared)
    generic, comps, notes, _, _ = _examine(base, params, **opts)
    notes = list(notes)
    nodes, dropped, seen = [], [], set()

    def visit(sysm, sub, conditions, reasons_here, verdict_here, comps, depth):
        for comp in comps:
            full = tuple(conditions) + tuple(comp.equations)
            why = _no_real_solution(comp.equations, signs)
            if why:
                dropped.append((full, why))
                continue
            for branch in _branches(comp.equations, tuple(sysm.parameters), signs):
                total = _compose(sub, branch)
                why = _bad_substitution(total, signs)
                if why:
                    dropped.append((full, why))
                    continue
                key = _canonical(total)
                if key in seen:
                    continue
                seen.add(key)
                spec = _rebuild(system, total, None)
                if isinstance(spec, Verdict):
                    nodes.append((full, total, spec, verdict_here, comp.reasons))
                    continue
                remaining = tuple(p for p in params if p not in total)
                verdict, sub_comps, sub_notes, _, _ = _examine(spec, remaining, **opts)
                notes.extend(sub_notes)
                nodes.append((full, total, verdict, verdict_here, comp.reasons))
                if depth + 1 < max_depth:
                    visit(spec, total, full, comp.reasons, verdict, sub_comps, depth + 1)
                elif sub_comps:
                    notes.append(
                        f"depth bound {max_depth} hit: below "
                        + ", ".join(f"{short(e)} = 0" for e in full)
                        + " further exceptional sets were not explored ("
                        + "; ".join(c.describe() for c in sub_comps) + ")")

    visit(base, {}, (), (), generic, comps, 0)
    cases = _order_cases(nodes)
    values = dict(system.parameter_values)
    scene_case, warnings = None, []
    if values:
        for i, case in enumerate(cases):
            if case.holds_at(values):
                scene_case = i
                break
        warnings = _near_warnings([(c.conditions, c.verdict) for c in cases], values, near)
    return ParametricVerdict(
        generic=generic, cases=tuple(cases), scene_case=scene_case,
        dropped=tuple(_dedupe(dropped)), notes=tuple(dict.fromkeys(notes)),
        warnings=tuple(warnings), parameters=params, positive=tuple(declared),
        values=MappingProxyType(values))


def classification_at_values(system, *, classes: Callable | None = None,
                             max_depth: int = MAX_DEPTH, precision: int | None = None,
                             seed: int = SEED, near: float = NEAR,
                             points: int = POINTS) -> ValuesVerdict:
    """The verdict that holds at the system's parameter values.

    The ordinary classification treats parameters as indeterminates wherever it
    decides symbolically. Here the data those decisions rest on are checked at the
    given values (exactly, the values read as decimals): when the values satisfy an
    exceptional condition, the condition is substituted (solved for a parameter with
    a value) and the classification is run again, up to ``max_depth`` times.
    Parameters without values stay generic.

    Parameters
    ----------
    system : nhham.System
    classes, max_depth, precision, seed, near, points
        As in :func:`parametric_classification`.

    Returns
    -------
    ValuesVerdict
    """
    valued = tuple(p for p in system.parameters if p in system.parameter_values)
    opts = dict(classes=classes, precision=precision, seed=seed, points=points, near=near)
    values = {p: system.parameter_values[p] for p in valued}
    exact = {p: _exact(v) for p, v in values.items()}
    generic, _, notes, hits, close = _examine(system, (), values=values, **opts)
    notes = list(notes)
    warnings = _close_warnings(close, values)
    current, verdict, conditions, substitution = system, generic, [], {}
    for depth in range(max_depth + 1):
        if not hits:
            break
        if depth == max_depth:
            warnings.append(f"depth bound {max_depth} hit: the values are also where "
                            + "; ".join(r for r, _ in hits) + " (not examined further)")
            break
        left = [p for p in current.parameters if p in values]
        involved = tuple(dict.fromkeys(p for _, inv in hits for p in inv if p in left))
        branch, eqs = None, ()
        if involved and current.n + current.m <= SYMBOLIC_VALUES_SIZE:
            comps = exceptional_conditions(verdict.analysis, involved, seed=seed,
                                           points=points)
            hit = next((c for c in comps if all(
                e.free_symbols <= set(exact) and e.xreplace(exact) == 0
                for e in c.equations)), None)
            if hit is not None:
                branch = next((b for b in _branches(hit.equations, involved, {})
                               if all(sp.simplify(v.xreplace(exact) - exact[p]) == 0
                                      for p, v in b.items())), None)
                eqs = hit.equations
        if branch is None:
            fix = involved or tuple(left)
            branch = {p: exact[p] for p in fix}
            eqs = tuple(p - exact[p] for p in fix)
        substitution = _compose(substitution, branch)
        conditions += [e for e in eqs if e not in conditions]
        spec = _rebuild(system, substitution, values)
        if isinstance(spec, Verdict):
            verdict, current = spec, None
            break
        current = spec
        rest = {p: v for p, v in values.items() if p not in substitution}
        verdict, _, more, hits, close = _examine(spec, (), values=rest, **opts)
        notes += more
        warnings += _close_warnings(close, rest)
    if conditions and generic.analysis is not None:
        # The generic verdict, not the one at the values: a Frobenius term that is a
        # nonzero function vanishing at the values left ``integrable`` undecided there.
        generic = dataclasses.replace(generic,
                                      integrable=generic.analysis.integrability.generic)
    return ValuesVerdict(verdict, generic, tuple(conditions),
                         current if current is not None else system,
                         tuple(dict.fromkeys(warnings + notes)))


def _close_warnings(close, values) -> list:
    names = ", ".join(f"{p.name} = {v}" for p, v in values.items())
    return [f"the parameter values {names} lie within relative distance {d:.1e} of values "
            f"where {reason}: the system is nearly singular there and numbers will be "
            f"ill-conditioned" for reason, d in close]


def exceptional_conditions(analysis: ConstraintAnalysis, parameters: Sequence | None = None,
                           *, seed: int = SEED, points: int = POINTS) -> tuple:
    """The components of the exceptional set of one classification.

    Parameters
    ----------
    analysis : ConstraintAnalysis
        The run whose generic decisions are examined.
    parameters : sequence of sympy.Symbol, optional
        The parameters kept symbolic (default: all of the system's); the others take
        their values, or random rational values when they have none.
    seed : int, optional
    points : int, optional
        Exact points per datum.

    Returns
    -------
    tuple of Condition
    """
    system = analysis.system
    params = tuple(system.parameters if parameters is None else parameters)
    if not params:
        return ()
    return _conditions(_Data(system, analysis, seed, points).symbolic(params), params)


# ================================================================= one run
def _examine(system, params, *, classes, precision, seed, points, values=None,
             near=NEAR):
    """The ordinary classification of ``system`` and the data of its decisions.

    Returns (Verdict, conditions, notes, hits, close): with ``params`` the exceptional
    conditions in those parameters (kept symbolic); with ``values`` the data that
    vanish at those exact values (``hits``) and those within relative distance
    ``near`` of vanishing (``close``).
    """
    analysis = analyze_constraints(system, precision=precision, seed=seed)
    integrable = analysis.integrable
    cls = None
    if classes is not None and analysis.status != "inconsistent":
        cls = classes(analysis)
    data = _Data(system, analysis, seed, points)
    if cls is not None and tuple(cls.labels) == tuple(analysis.final_labels):
        # The second-class set the classification chose (for generic parameters when it
        # decided symbolically): at values where B drops rank its minor is the datum.
        data.use_second_class_set(cls.second_class_indices)
    comps, hits, close = (), [], []
    if params:
        comps = _conditions(data.symbolic(tuple(params)), tuple(params))
    if values:
        hits, close = data.at_values(values, near)
    if cls is not None:
        first, second = int(cls.first_class), int(cls.second_class)
    else:
        if params:
            K = QQ.frac_field(*params)
            rank = data.bracket_rank(data.env(gens=dict(zip(params, K.gens))), K)
        else:
            # the ordinary classification's answer: for generic parameters
            rank = data.bracket_rank(data.env(generic=True), QQ)
        first = second = None
        if analysis.status != "inconsistent" and rank is not None:
            first, second = len(analysis.final_constraints) - rank, rank
    verdict = Verdict(
        status=analysis.status, regular=bool(analysis.regular), rank_C=int(analysis.rank_C),
        stages=len(analysis.stages), free_multipliers=int(analysis.free_multipliers),
        integrable=integrable, first_class=first, second_class=second,
        redundant=tuple(d.label for d in analysis.dropped),
        final_constraints=len(analysis.final_constraints), dimension=analysis.dimension,
        system=system, analysis=analysis, classes=cls)
    return verdict, comps, data.notes, hits, close


# ============================================================ exact evaluation
class _ParameterFieldSampler:
    """Random exact points of M = {equations = 0} with parameters as field generators.

    M_1 without holonomic constraints: coordinates drawn, dependent velocities solved
    at the point over Q(p). Otherwise the exact reduction of
    :class:`~nhham.lagrangian.submanifold.Submanifold` is evaluated at the point
    (NotExact when it leaves residual equations).
    """

    def __init__(self, system, equations, env0, K, rng):
        self.q, self.v = tuple(system.coordinates), tuple(system.velocities)
        self.env0, self.K, self.rng = env0, K, rng
        eqs = tuple(sp.sympify(e) for e in equations)
        phis = set(system.phi)
        self.affine = not system.holonomic and all(e in phis for e in eqs)
        self.dep = None
        if self.affine:
            self.mu = [jacobian_row(e, self.v) for e in eqs]
            self.h = [e.xreplace({x: 0 for x in self.v}) for e in eqs]
        else:
            # The cheap test first: the symbolic reduction of a large M_k with a holonomic
            # constraint no coordinate can be solved from linearly takes minutes, to end
            # in the same NotExact.
            eliminate_coordinates(self.q, system.holonomic)
            red = Submanifold(system, eqs).reduction
            if red.residual:
                raise NotExact("M_k is not parametrised by the exact reduction (residual "
                               "equations " + ", ".join(short(r) for r in red.residual) + ")")
            self.sub = red.substitution

    def _draw(self):
        return MPQ(self.rng.randint(1, 2 ** DRAW_BITS))

    def _angle(self):
        t = self._draw()
        one = 1 + t * t
        return Angle(self._draw(), (1 - t * t) / one, 2 * t / one)

    def point(self) -> dict:
        for _ in range(20):
            try:
                return self._point()
            except ZeroDivisionError:
                continue
        raise NotExact("no exact point found (denominators vanish at every point tried)")

    def _point(self):
        env, K = dict(self.env0), self.K
        if self.affine:
            for q in self.q:
                env[q] = self._angle()
            if not self.mu:
                for x in self.v:
                    env[x] = self._draw()
                return env
            cache = {}
            mu = [[K.convert(x) for x in evaluate(r, env, cache)] for r in self.mu]
            h = [K.convert(x) for x in evaluate(self.h, env, cache)]
            m, n = len(mu), len(self.v)
            if self.dep is None:
                _, piv = DomainMatrix(mu, (m, n), K).rref()
                if len(piv) < m:
                    raise NotExact("the affine constraints are dependent at a random point")
                self.dep = tuple(piv)
            free = [i for i in range(n) if i not in self.dep]
            for i in free:
                env[self.v[i]] = self._draw()
            block = DomainMatrix([[row[j] for j in self.dep] for row in mu], (m, m), K)
            rhs = DomainMatrix([[-(h[k] + sum((mu[k][i] * K.convert(env[self.v[i]])
                                               for i in free), K.zero))] for k in range(m)],
                               (m, 1), K)
            try:
                sol = block.lu_solve(rhs).to_list()
            except Exception as exc:  # singular at this point: draw again
                raise ZeroDivisionError(str(exc)) from exc
            for pos, j in enumerate(self.dep):
                env[self.v[j]] = sol[pos][0]
            return env
        for q in self.q:
            if q not in self.sub:
                env[q] = self._angle()
        for x in self.v:
            if x not in self.sub:
                env[x] = self._draw()
        cache = {}
        for q in self.q:
            if q in self.sub:
                env[q] = _coordinate_value(self.sub[q], env, cache)
        for x in self.v:
            if x in self.sub:
                env[x], = evaluate([self.sub[x]], env, cache)
        return env


def _coordinate_value(expr, env, cache):
    """A solved coordinate's value: an Angle when it is an integer combination of
    drawn coordinates (so sin/cos of it stay exact), else its value."""
    expr = sp.expand(expr)
    if expr == 0:
        return Angle(0, 1, 0)
    terms = expr.as_coefficients_dict()
    if all(isinstance(s, sp.Symbol) and isinstance(env.get(s), Angle) and c.is_Integer
           for s, c in terms.items()):
        out = Angle(0, 1, 0)
        for s, c in terms.items():
            out = out + env[s] * int(c)
        return out
    value, = evaluate([expr], env, cache)
    return value


class _Data:
    """The data the generic decisions of one analysis rest on, as evaluators.

    :meth:`items` gives ``(reason, evaluate)`` pairs; ``evaluate(env0, K)`` returns the
    values of the datum's functions at seeded exact points of its M_k, the parameters
    taking the values of ``env0`` (generators of K = Q(p) to keep them symbolic, or
    exact rationals). The same seed gives the same free coordinates and velocities
    for every ``env0``, so values at nearby parameter points can be compared.
    """

    def __init__(self, system, analysis, seed, points):
        self.system, self.analysis = system, analysis
        self.seed, self.points = seed, int(points)
        rng = random.Random(seed + 104729)
        values = dict(system.parameter_values)
        # Parameters without values (and without generators) take these fixed values.
        self.fixed = {p: (_exact_mpq(values[p]) if p in values else
                          MPQ(rng.randint(1, 2 ** DRAW_BITS))) for p in system.parameters}
        self.random = {p: MPQ(rng.randint(1, 2 ** DRAW_BITS)) for p in system.parameters}
        geo = analysis.geometry
        self.W = [list(geo.hessian.row(i)) for i in range(system.n)]
        self.notes: list[str] = []
        self._pivots: dict = {}
        self._points_cache: dict = {}
        self._memos: dict = {}

    def env(self, gens=None, at=None, generic=False) -> dict:
        """Parameter values: ``gens`` (symbol -> field element) first, then ``at``
        (symbol -> exact value), then random values (``generic``) or the system's."""
        out = dict(self.random if generic else self.fixed)
        out.update(at or {})
        out.update(gens or {})
        return out

    # --------------------------------------------------------------- points
    @contextlib.contextmanager
    def _first_point_only(self):
        """Evaluate data at the first seeded point only (the same point as always)."""
        saved, self.points = self.points, 1
        try:
            yield
        finally:
            self.points = saved

    def _pts(self, eqs, env0, K, tag):
        # The points stay exact when the data are evaluated in another field. The same
        # (stage, parameter values) gives the same points for every datum: drawn once,
        # and a shorter list is a prefix of a longer one (one seeded stream).
        exact = QQ if K.is_RealField or K.is_FiniteField else K
        try:
            key = (tag, tuple(eqs), exact, frozenset(env0.items()))
            known = self._points_cache.get(key, [])
        except TypeError:  # unhashable parameter values: no caching
            key, known = None, []
        if len(known) >= self.points:
            return known[:self.points]
        sampler = _ParameterFieldSampler(self.system, eqs, env0, exact, random.Random(f"{self.seed}:{tag}"))
        out = [sampler.point() for _ in range(self.points)]
        if key is not None:
            self._points_cache[key] = out
        return out

    def _memo(self, env) -> dict:
        """The memo of subexpression values at one point, shared by every datum (the
        point is kept alive with it, so its id stays its own)."""
        return self._memos.setdefault(id(env), (env, {}))[1]

    @staticmethod
    def _val(K, x):
        x = x.r if isinstance(x, Angle) else x
        if K is FLOAT64:
            return float(MPQ(x))
        if K.is_FiniteField or K.is_RealField:
            q = MPQ(x)
            if K.is_RealField:  # rounded once, directly (K.convert goes through sympy)
                return K.dtype(from_rational(int(q.numerator), int(q.denominator),
                                             K.precision, "n"))
            den = int(q.denominator)
            if den == 1:
                return K(int(q.numerator))
            try:
                return K(int(q.numerator) * pow(den, -1, int(K.characteristic())))
            except ValueError as exc:  # p divides the denominator: not a value mod p
                raise ZeroDivisionError(str(exc)) from exc
        return K.convert(x)

    def _matrix(self, K, rows, env, cache):
        vals = [[self._val(K, x) for x in evaluate(r, env, cache)] for r in rows]
        shape = (len(vals), len(vals[0]) if vals else 0)
        if K is FLOAT64:
            return FloatMatrix(np.array(vals, dtype=float).reshape(shape))
        return DomainMatrix(vals, shape, K)

    # ---------------------------------------------------------------- items
    def items(self) -> list:
        """[(reason, evaluate)] for every datum of the analysis."""
        analysis, system = self.analysis, self.system
        stages = analysis.stages
        if not stages:
            return []
        out = []
        m1 = stages[0].constraints
        out.append(("the Lagrangian is singular (det W = 0)", lambda env0, K: [
            field_det(self._matrix(K, self.W, env, self._memo(env)))
            for env in self._pts(m1, env0, K, 1)]))
        if system.m:
            out.append(("the constraint one-forms become dependent (a constraint is "
                        "redundant)", lambda env0, K: self._mu_minors(m1, env0, K)))
        for stage in stages:
            out += self._stage_items(stage)
        if analysis.integrability.generic is False and system.m and system.n - system.m > 1:
            out.append(("the constraint distribution becomes integrable",
                        lambda env0, K: self._frobenius(m1, env0, K)))
        if analysis.status != "inconsistent" and analysis.final_constraints:
            out.append(("the rank of the bracket matrix on M_f drops (the first/second-class "
                        "split changes)", lambda env0, K: self._bracket_minor(env0, K)))
        return out

    def _mu_minors(self, eqs, env0, K):
        system = self.system
        m = system.m
        rows = [list(system.mu.row(i)) for i in range(m)]
        vals = []
        for env in self._pts(eqs, env0, K, 1):
            M = self._matrix(K, rows, env, self._memo(env))
            if not K.is_RealField:  # floating point reuses the exact pivot columns
                self._pivots["mu"] = list(M.rref()[1])
            pivots = self._pivots.get("mu")
            # Beyond MAX_MINORS, the minors next to the pivot block: they vanish together
            # exactly where all do (rank mu < m), at a cost of m (n - m) + 1.
            subsets = None if math.comb(system.n, m) <= MAX_MINORS or pivots is None or \
                len(pivots) < m else adjacent_column_sets(pivots, system.n)
            vals += maximal_minors(M, pivots, subsets)
        return vals

    def _stage_items(self, stage):
        k = stage.index
        system = self.system
        index = {lab: c for lab, c in zip(stage.labels, stage.constraints)}
        rows, cols = stage.block
        r = len(rows)
        out = []
        if r:
            phi_idx = [int(s.name.rsplit("_", 1)[1]) - 1 for s in cols]
            mu_I = [list(system.mu.row(i)) for i in phi_idx]
            Jv = [jacobian_row(index[lab], system.velocities) for lab in rows]

            def block_det(env0, K, eqs=stage.constraints, mu_I=mu_I, Jv=Jv, r=r, k=k):
                vals = []
                for env in self._pts(eqs, env0, K, k):
                    cache = self._memo(env)
                    W = self._matrix(K, self.W, env, cache)
                    MI = self._matrix(K, mu_I, env, cache)
                    JJ = self._matrix(K, Jv, env, cache)
                    top = W.hstack(MI.transpose())
                    zeros = (FloatMatrix.zeros((r, r)) if K is FLOAT64 else
                             DomainMatrix.zeros((r, r), K))
                    bottom = JJ.hstack(zeros)
                    vals.append(field_det(top.vstack(bottom)))
                return vals

            out.append((f"the rank of (Z_i(chi_j)) on M_{k} drops below {r}"
                        + (" (C singular)" if k == 1 else ""), block_det))
        for label, psi in stage.conditions:
            def condition(env0, K, eqs=stage.constraints, psi=psi, k=k):
                return [self._val(K, evaluate([psi], env, self._memo(env))[0])
                        for env in self._pts(eqs, env0, K, k)]

            out.append((f"the condition from {label} on M_{k} vanishes", condition))
        return out

    def _frobenius(self, eqs, env0, K):
        system = self.system
        m, n = system.m, system.n
        q = system.coordinates
        rows = [list(system.mu.row(i)) for i in range(m)]
        grads = [[jacobian_row(system.mu[i, A], q) for A in range(n)] for i in range(m)]
        dmu = [[[grads[i][B][A] - grads[i][A][B] for B in range(n)] for A in range(n)]
               for i in range(m)]
        vals = []
        for env in self._pts(eqs, env0, K, 1):
            cache = self._memo(env)
            M = self._matrix(K, rows, env, cache)
            if "dep" not in self._pivots or not K.is_RealField:
                # Floating point reuses the exact choice of the kernel basis (the
                # values depend on it) instead of deciding pivots on rounded numbers.
                self._pivots["dep"] = list(M.rref()[1])
            dep = self._pivots["dep"]
            if len(dep) < m:
                continue
            free = [j for j in range(n) if j not in dep]
            block = M.extract(list(range(m)), list(dep))
            sol = field_solve(block, -M.extract(list(range(m)), free)).to_list()
            basis = []
            for a, j in enumerate(free):
                col = [K.zero] * n
                col[j] = K.one
                for t, d in enumerate(dep):
                    col[d] = sol[t][a]
                basis.append(col)
            for i in range(m):
                D = [[self._val(K, x) for x in evaluate(r, env, cache)] for r in dmu[i]]
                for a in range(len(free)):
                    for b in range(a + 1, len(free)):
                        X, Y = basis[a], basis[b]
                        vals.append(sum((X[A] * D[A][B] * Y[B] for A in range(n)
                                         for B in range(n) if D[A][B]), K.zero))
        return vals

    def _brackets(self, env0, K, count=None):
        """B = ({chi_a, chi_b}_L) over the final constraints at points of M_f."""
        analysis, system = self.analysis, self.system
        cons = list(analysis.final_constraints)
        geo = analysis.geometry
        n = system.n
        Mx = [list(geo.mixed_hessian.row(i)) for i in range(n)]
        Jq = [jacobian_row(c, system.coordinates) for c in cons]
        Jv = [jacobian_row(c, system.velocities) for c in cons]
        mats = []
        pts = self._pts(cons, env0, K, "f")
        for env in pts[:count]:
            cache = self._memo(env)
            W = self._matrix(K, self.W, env, cache)
            M = self._matrix(K, Mx, env, cache)
            U = field_solve(W, self._matrix(K, Jv, env, cache).transpose())
            JU = self._matrix(K, Jq, env, cache) * U
            mats.append(JU - JU.transpose() - U.transpose() * (M - M.transpose()) * U)
        return mats

    def bracket_rank(self, env0, K):
        """Rank of the bracket matrix on M_f (None when not evaluated exactly)."""
        if self.analysis.status == "inconsistent":
            return None
        if not self.analysis.final_constraints:
            return 0
        try:
            if K.is_QQ:
                # Rank modulo p at the first point is a lower bound of the rank over Q
                # at every point of the datum: full there, it is the answer.
                k = len(self.analysis.final_constraints)
                try:
                    with self._first_point_only():
                        B, = self._brackets(env0, MODULAR, count=1)
                    if B.rank() == k:
                        return k
                except ZeroDivisionError:
                    pass
            return max(B.rank() for B in self._brackets(env0, K))
        except (NotExact, ZeroDivisionError) as exc:
            self.notes.append(f"bracket matrix on M_f not evaluated exactly ({exc})")
            return None

    def use_second_class_set(self, indices) -> None:
        """Take the principal block of the bracket datum from a classification."""
        self._pivots["R"] = list(indices)

    def _bracket_minor(self, env0, K):
        if "R" not in self._pivots:
            # The principal block is chosen for generic parameters (modulo p, at random
            # parameter values): at the given values its minor may vanish, which is the
            # very event the datum detects.
            with self._first_point_only():
                (B,) = self._brackets(self.env(generic=True), MODULAR)
            full = B.shape[0] and B.det()  # all second class, the usual case: no rref
            self._pivots["R"] = list(range(B.shape[0])) if full else list(B.rref()[1])
        mats = self._brackets(env0, K)
        R = self._pivots["R"]
        if not R:
            return []
        return [field_det(B.extract(R, R)) for B in mats]

    # ------------------------------------------------------------ the modes
    def symbolic(self, params):
        """[(reason, values)] with ``params`` as generators of Q(params)."""
        K = QQ.frac_field(*params)
        env0 = self.env(gens=dict(zip(params, K.gens)))
        out = []
        items = self.items()
        try:
            if self.analysis.stages:
                self._pts(self.analysis.stages[0].constraints, env0, K, 1)
        except (NotExact, ZeroDivisionError) as exc:
            self.notes.append(f"the exceptional sets were not computed: no exact points of "
                              f"M_1 with symbolic parameters ({exc})")
            return out
        for reason, fn in items:
            try:
                vals = fn(env0, K)
            except (NotExact, ZeroDivisionError) as exc:
                self.notes.append(f"not examined ({exc}): whether {reason}")
                continue
            if any(vals):
                out.append((reason, vals))
        return out

    def _with_shifts(self, fn, base, values, K=QQ):
        """The datum at the values and at each value moved by a relative 1e-4, in K."""
        at = fn(base, K)  # first: structural choices (pivots) are made there
        shifted = {}
        for p, x in values.items():
            h = abs(x) / 10 ** 4 if x else MPQ(1, 10 ** 4)
            shifted[p] = (h, fn(self.env(at={**values, p: x + h}), K))
        return at, shifted

    def _modular(self, fn, base):
        """The datum at the values modulo p at the first point (None: not evaluable)."""
        try:
            with self._first_point_only():
                return fn(base, MODULAR)
        except ZeroDivisionError:  # p divides a denominator: decide over Q instead
            return None

    def at_values(self, values, near):
        """Data that vanish at exact parameter ``values`` and data nearly vanishing.

        A datum nonzero modulo p at the first point is nonzero at the values (a
        proof); its nearness is then estimated in float64, and again in
        ``SHIFT_FIELD`` when float64 finds it within ``near * FLOAT_MARGIN``. Only a
        datum that vanishes modulo p is evaluated over Q, at every point.

        Returns
        -------
        hits : list of (reason, involved parameters)
            Data nonzero for generic parameters that vanish identically at the values.
        close : list of (reason, relative distance)
        """
        hits, close = [], []
        values = {p: _exact_mpq(x) for p, x in values.items()}
        base = self.env(at=values)
        items = self.items()
        try:
            if self.analysis.stages:
                self._pts(self.analysis.stages[0].constraints, base, QQ, 1)
        except (NotExact, ZeroDivisionError) as exc:
            self.notes.append(f"the parameter values were not checked against the "
                              f"exceptional sets: no exact points of M_1 ({exc})")
            return hits, close
        for reason, fn in items:
            try:
                if not reason.startswith("the condition"):
                    pass  # nonzero for generic parameters by construction
                elif not any(fn(self.env(generic=True), QQ)):
                    continue  # zero for generic parameters: not a generic assumption
                # The first point decides almost always (a datum nonzero there is not
                # hit); the others only confirm a vanishing. The nearness estimate uses
                # the first point too: every term must vanish on the exceptional set, so
                # one point's largest |P| / |grad P| already bounds the distance.
                mod = self._modular(fn, base)
                if mod is not None and any(mod):
                    nonzero = [bool(x) for x in mod]
                    with self._first_point_only():
                        v0, shifted = self._estimate(fn, base, values, nonzero, near)
                else:
                    v0, shifted = self._with_shifts(fn, base, values)
                    nonzero = [bool(x) for x in v0]
            except (NotExact, ZeroDivisionError) as exc:
                self.notes.append(f"not examined at the values ({exc}): whether {reason}")
                continue
            if not v0:
                continue  # nothing assumed nonzero (e.g. a bracket matrix of rank 0)
            if not any(nonzero):
                involved = tuple(p for p, (h, vals) in shifted.items() if any(vals))
                hits.append((reason, involved))
                continue
            distance = _relative_distance(v0, nonzero, shifted, values)
            if distance < near:
                close.append((reason, distance))
        return hits, close

    def _estimate(self, fn, base, values, nonzero, near):
        """(value, shifted values) of a datum for its nearness: in float64 when that
        puts it farther than ``near * FLOAT_MARGIN`` from vanishing, else (closer, not
        finite, or a float pivot vanished) in ``SHIFT_FIELD``."""
        try:
            v0, shifted = self._with_shifts(fn, base, values, FLOAT64)
            if _relative_distance(v0, nonzero, shifted, values) >= near * FLOAT_MARGIN:
                return v0, shifted
        except ZeroDivisionError:
            pass
        return self._with_shifts(fn, base, values, SHIFT_FIELD)


def _relative_distance(v0, nonzero, shifted, values) -> float:
    """Relative distance of the values to where a datum vanishes: over its nonzero terms,
    the largest |P| / |grad P| (every term must vanish there), over |values|.

    Scale-free: each term enters through its logarithmic derivative
    (P(x + h) - P(x)) / (h P(x)), formed in the field of the values before it becomes
    a float, so a determinant of a large system (|P| beyond 1e308 or below 1e-308) neither
    overflows nor underflows. Raises ZeroDivisionError when a float64 value is not
    usable (zero by underflow, or not finite): the caller then works in a wider field.
    """
    scale = math.hypot(*(float(x) for x in values.values())) or 1.0
    worst = 0.0
    for i, val in enumerate(v0):
        if not nonzero[i]:
            continue
        slope = math.hypot(*(_log_slope(vals[i], val, h) for h, vals in shifted.values()))
        worst = max(worst, 1.0 / slope if slope else math.inf)
    return worst / scale


def _log_slope(moved, value, h) -> float:
    """(moved - value) / (h value) as a float, computed in the field of the values."""
    if isinstance(value, float):
        if value == 0.0 or not (math.isfinite(value) and math.isfinite(moved)):
            raise ZeroDivisionError("a float64 value underflowed or overflowed")
        return (moved / value - 1.0) / float(h)
    step = h if isinstance(value, MPQ) else SHIFT_FIELD.convert(h)
    return float((moved - value) / (step * value))


# ============================================================ the components
def _conditions(data, params) -> tuple:
    """Components of the union of the exceptional sets of every datum, deduplicated."""
    found: dict = {}
    for reason, values in data:
        for eqs in _components(values, params):
            key = tuple(sp.srepr(e) for e in eqs)
            found.setdefault(key, (eqs, []))[1].append(reason)
    return tuple(Condition(eqs, tuple(dict.fromkeys(reasons)))
                 for eqs, reasons in found.values())


def _components(values, params) -> list:
    """Components of the common zero set of the numerators of ``values``."""
    nums = [v.numer for v in values if v]
    if not nums or not params:
        return []
    g = reduce(lambda a, b: a.gcd(b), nums)
    out = []
    if not g.is_ground:
        _, factors = sp.factor_list(g.as_expr(), *params)
        for f, _ in factors:
            if f.free_symbols:
                out.append((_normal(f),))
    rest = [a.exquo(g) for a in nums]
    if all(r.is_ground for r in rest):
        return out
    exprs = list(dict.fromkeys(r.as_expr() for r in rest))
    try:
        basis = sp.groebner(exprs, *params, order="lex")
    except Exception:  # pragma: no cover - sympy failure
        return out
    if list(basis.exprs) == [1]:
        return out
    try:
        sols = sp.solve(list(basis.exprs), list(params), dict=True)
    except Exception:  # pragma: no cover - sympy cannot solve: carry the relations
        sols = None
    if not sols:
        out.append(tuple(_normal(e) for e in basis.exprs))
        return out
    for sol in sols:
        eqs = tuple(_normal(sp.numer(sp.together(p - v))) for p, v in sol.items())
        out.append(tuple(sorted(eqs, key=sp.default_sort_key)))
    return out


def _distance_to_zero(expr, at, syms) -> float:
    """|e| / |grad e| at the exact point ``at``, formed exactly before it becomes a
    float (a polynomial of high degree in large values would overflow float64)."""
    grad2 = sum(sp.diff(expr, p).xreplace(at) ** 2 for p in syms)
    if not grad2:
        return math.inf
    try:
        return math.sqrt(float(expr.xreplace(at) ** 2 / grad2))
    except OverflowError:
        return math.inf


def _normal(expr):
    """A factored polynomial with a positive leading coefficient, content removed."""
    expr = sp.factor(sp.expand(expr))
    c, rest = expr.as_coeff_Mul()
    out = rest if c.is_number and c != 0 else expr
    syms = sorted(out.free_symbols, key=sp.default_sort_key)
    if syms:
        try:
            if sp.Poly(out, *syms).LC() < 0:
                out = sp.factor(-out)
        except sp.PolynomialError:  # pragma: no cover
            pass
    return out


# ======================================================== signs and solving
def _declared_positive(system, positive) -> list:
    by_name = {p.name: p for p in system.parameters}
    out, bad = [], []
    for item in positive:
        name = item.name if isinstance(item, sp.Symbol) else str(item)
        if name not in by_name:
            bad.append(name)
        elif by_name[name] not in out:
            out.append(by_name[name])
    if bad:
        raise InputError(f"positive: {', '.join(repr(b) for b in bad)} "
                         f"{'is not a parameter' if len(bad) == 1 else 'are not parameters'} "
                         f"of the system (parameters: "
                         f"{', '.join(sorted(by_name)) or 'none'})")
    for p in system.parameters:
        if p.is_positive and p not in out:
            out.append(p)
    return out


def _sign_dummies(params, positive) -> dict:
    """Parameter -> a real Dummy carrying its declared sign."""
    out = {}
    for p in params:
        kw = {"real": True}
        if p in positive:
            kw["positive"] = True
        for name in ("negative", "nonnegative", "nonpositive"):
            if getattr(p, f"is_{name}"):
                kw[name] = True
        out[p] = sp.Dummy(p.name, **kw)
    return out


def _no_real_solution(eqs, signs) -> str | None:
    """Why equations in the parameters have no real solution under the signs, else None."""
    for e in eqs:
        d = sp.sympify(e).xreplace(signs)
        try:
            definite = bool(d.is_positive) or bool(d.is_negative)
        except Exception:  # pragma: no cover
            definite = False
        if definite:
            decl = sorted((s.name for s in sp.sympify(e).free_symbols
                           if signs.get(s) is not None and signs[s].is_positive),
                          key=str)
            return (f"{short(e)} never vanishes for real parameters"
                    + (f" with {', '.join(n + ' > 0' for n in decl)}" if decl else ""))
    return None


def _bad_substitution(sub, signs) -> str | None:
    for p, v in sub.items():
        d = sp.sympify(v).xreplace(signs)
        if d.is_real is False:
            return f"{p.name} = {short(v)} is not real"
        s = signs.get(p)
        if s is not None and s.is_positive and d.is_nonpositive:
            return f"{p.name} = {short(v)} contradicts {p.name} > 0"
    return None


def _branches(eqs, params, signs) -> list:
    """Substitutions {parameter: expression} solving ``eqs``, one per branch."""
    branches = [{}]
    for e in eqs:
        nxt = []
        for sub in branches:
            f = sp.expand(sp.sympify(e).xreplace(sub))
            if f == 0:
                nxt.append(sub)
                continue
            if f.is_number:
                continue
            for p, val in _solve_one(f, [p for p in params if p not in sub]):
                nxt.append(_compose(sub, {p: val}))
        branches = nxt
    return branches


def _solve_one(f, params):
    """[(parameter, value)] solving f = 0: linear with constant coefficient first,
    then linear, then the real roots in the parameter of lowest degree."""
    present = [p for p in params if p in f.free_symbols]
    if not present:
        return []
    linear = []
    for p in present:
        poly = sp.Poly(f, p)
        if poly.degree() == 1:
            a, b = poly.all_coeffs()
            linear.append((bool(a.free_symbols), p, sp.factor(-b / a)))
    if linear:
        linear.sort(key=lambda t: t[0])
        _, p, val = linear[0]
        return [(p, val)]
    p = min(present, key=lambda s: sp.Poly(f, s).degree())
    roots = sp.solve(f, p)
    return [(p, r) for r in roots if r.is_real is not False]


def _compose(sub, new) -> dict:
    out = {k: sp.simplify(sp.sympify(v).xreplace(new)) for k, v in sub.items()}
    out.update(new)
    return out


def _canonical(sub) -> tuple:
    return tuple(sorted((p.name, sp.srepr(sp.simplify(v))) for p, v in sub.items()))


# ======================================================== systems and order
def _rebuild(system, sub, values):
    """The system with ``sub`` substituted (a Verdict "invalid" when it is not valid).

    ``values`` gives the remaining parameters their values (None: all symbolic).
    """
    remaining = [p for p in system.parameters if p not in sub]
    params = {p.name: (values.get(p) if values else None) for p in remaining}
    x = (lambda e: sp.sympify(e).xreplace(sub)) if sub else sp.sympify
    try:
        return System(system.coordinates, x(system.lagrangian),
                      [x(c) for c in system.constraints], [x(g) for g in system.holonomic],
                      parameters=params, name=system.name, drop_redundant=True)
    except SingularLagrangianError:
        why = "the Lagrangian is singular (det W = 0): outside nhham's scope"
    except NhhamError as exc:
        why = f"the system is not valid there: {exc}"
    return Verdict(status="invalid", regular=None, rank_C=None, stages=0, free_multipliers=0,
                   integrable=None, first_class=None, second_class=None, note=why)


def _order_cases(nodes) -> list:
    """Cases, invalid ones and then the most specific first, each with the inequations
    excluding earlier ones.

    A node whose verdict equals the verdict of the set containing it (its parent) is
    not a case of its own; its sub-cases are kept.
    """
    kept = [(full, sub, v, why) for full, sub, v, parent, why in nodes if v != parent]
    # Where nhham does not apply (singular W) holds on the whole set, whatever else
    # holds there: those cases first; then the most specific first.
    kept.sort(key=lambda t: (t[2].status != "invalid", -len(t[1])))
    # A case whose points would fall, without it, into a case with the same verdict is
    # dropped: the first later case containing it, with no case in between meeting it.
    j = 0
    while j < len(kept):
        full, sub, verdict, _ = kept[j]
        fallback = None
        for k in range(j + 1, len(kept)):
            extra = _restricted(kept[k][0], sub)
            if any(e.is_number and e != 0 for e in extra):
                continue  # disjoint
            if all(e == 0 for e in extra):
                fallback = kept[k][2]
                break
            fallback = False  # meets part of it: keep the case
            break
        if fallback is not None and fallback is not False and fallback == verdict:
            del kept[j]
        else:
            j += 1
    cases = []
    for full, sub, verdict, why in kept:
        excluding = []
        for earlier in cases:
            extra = _restricted(earlier.conditions, sub)
            if any(e.is_number and e != 0 for e in extra):
                continue  # disjoint
            extra = [e for e in extra if e != 0]
            if not extra:
                continue
            excluding.append(extra[0] if len(extra) == 1
                             else sp.Add(*[e ** 2 for e in extra]))
        cases.append(Case(conditions=tuple(full), excluding=tuple(dict.fromkeys(excluding)),
                          verdict=verdict, substitution=MappingProxyType(dict(sub)),
                          reasons=tuple(why)))
    return cases


def _restricted(conditions, sub) -> list:
    """Conditions restricted to a case's set (its substitution applied), factored."""
    return [sp.factor(sp.expand(sp.sympify(e).xreplace(sub))) for e in conditions]


def _near_warnings(conds, values, near) -> list:
    """Warnings for values within relative distance ``near`` of a condition's set."""
    out = []
    if not near:
        return out
    for eqs, _ in conds:
        syms = set().union(*[sp.sympify(e).free_symbols for e in eqs]) if eqs else set()
        if not syms or not syms <= set(values):
            continue
        at = {p: _exact(values[p]) for p in syms}
        if all(sp.sympify(e).xreplace(at) == 0 for e in eqs):
            continue
        scale = math.hypot(*(float(at[p]) for p in syms)) or 1.0
        dist = max(_distance_to_zero(sp.sympify(e), at, syms) for e in eqs)
        rel = dist / scale
        if rel < near:
            out.append("the parameter values "
                       + ", ".join(f"{p.name} = {values[p]}" for p in sorted(syms, key=str))
                       + f" lie within relative distance {rel:.1e} of the exceptional set "
                       + ", ".join(f"{short(e)} = 0" for e in eqs)
                       + ": the system is nearly singular there and numbers will be "
                         "ill-conditioned")
    return out


def _dedupe(items) -> list:
    """One entry per reason (the shortest conditions that gave it)."""
    best: dict = {}
    for eqs, why in items:
        if why not in best or len(eqs) < len(best[why]):
            best[why] = tuple(eqs)
    return [(eqs, why) for why, eqs in best.items()]


def _exact(value):
    return sp.Rational(str(value)) if not isinstance(value, sp.Basic) else value


def _exact_mpq(value):
    r = sp.Rational(str(value))
    return MPQ(int(r.p), int(r.q))
