"""The exceptional parameter sets of a classification's generic decisions.

An exact verdict of :func:`nhham.lagrangian.analysis.analyze_constraints` holds for
*generic* parameters: every decision assumed that some function of the state and the
parameters is not identically zero on M_k. This module evaluates those functions
exactly, with the parameters symbolic or at their values, and finds the parameter
values where they vanish identically in the state. The verdicts built on it (every
case, or the case of the scene's values) are in :mod:`nhham.verdict`.

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
solutions of what remains (lower-dimensional components; :mod:`nhham.lagrangian.components`).
Every component is verified
by the case analysis (:mod:`nhham.verdict.parametric`), which runs the classification
there.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import math
import random
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import sympy as sp
from mpmath.libmp import from_rational
from sympy import QQ
from sympy.external.gmpy import MPQ
from sympy.polys.domains import GF, RealField
from sympy.polys.matrices import DomainMatrix
from sympy.polys.polyerrors import CoercionFailed

from nhham.lagrangian.analysis import ConstraintAnalysis
from nhham.lagrangian.components import Condition, exceptional_components
from nhham.lagrangian.domains import PRIME, Angle, ModP, NotExact, evaluate
from nhham.lagrangian.formulas import bordered_matrix, frobenius_terms, lagrangian_bracket
from nhham.lagrangian.linalg import (
    FLOAT64,
    FloatMatrix,
    ListMatrix,
    LogDet,
    adjacent_column_sets,
    log_det,
    maximal_minors,
)
from nhham.lagrangian.points import DRAW_BITS, ParameterFieldSampler, jacobian_row
from nhham.lagrangian.submanifold import Submanifold
from nhham.lagrangian.unexamined import unexamined_notes
from nhham.progress import SLOW, part
from nhham.settings import SEED

__all__ = [
    "Condition",
    "ExceptionalData",
    "exceptional_conditions",
    "exceptional_components",
    "POINTS",
]

# Exact points per decision (each a proof of non-vanishing; the gcd of the values at
# several points gives the content of the function in the parameters).
POINTS = 3
# Plain classification names the condition its values satisfy (symbolically) up to this
# n + m; beyond, the parameters involved are substituted by their values.
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


def _nonzero_claim(value) -> bool:
    """Whether a decision's value says something is not zero (a rank > 0, "does not
    vanish"): the claims that can fail at special parameter values."""
    if isinstance(value, bool):
        return value is False
    return isinstance(value, int) and value > 0


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

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...                       ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    >>> conditions = nhham.exceptional_conditions(nhham.analyze_constraints(system))
    >>> [c.equations for c in conditions]         # det W = a, C = -(1 - b**2)
    [(a,), (b - 1,), (b + 1,)]
    """
    system = analysis.system
    params = tuple(system.parameters if parameters is None else parameters)
    if not params:
        return ()
    return exceptional_components(ExceptionalData(system, analysis, seed, points).symbolic(params), params)


# True while data are evaluated at the first seeded point only (_first_point_only).
_FIRST_POINT_ONLY = contextvars.ContextVar("first_point_only", default=False)


@dataclass(frozen=True, eq=False)
class ExceptionalData:
    """The data the generic decisions of one analysis rest on, as evaluators.

    :meth:`items` gives ``(reason, evaluate)`` pairs; ``evaluate(env0, K)`` returns the
    values of the datum's functions at seeded exact points of its M_k, the parameters
    taking the values of ``env0`` (generators of K = Q(p) to keep them symbolic, or
    exact rationals). The same seed gives the same free coordinates and velocities
    for every ``env0``, so values at nearby parameter points can be compared.

    Frozen (its caches fill as data are evaluated): ``second_class``, the indices of the
    second-class set a classification chose, is the principal block of the bracket
    datum; without it the block is chosen for generic parameters.
    """

    system: Any
    analysis: ConstraintAnalysis
    seed: int
    points: int
    second_class: tuple[int, ...] | None = None
    fixed: dict = field(init=False, repr=False)
    random: dict = field(init=False, repr=False)
    W: list = field(init=False, repr=False)
    notes: list[str] = field(init=False, repr=False, default_factory=list)
    _pivots: dict = field(init=False, repr=False, default_factory=dict)
    _points_cache: dict = field(init=False, repr=False, default_factory=dict)
    _memos: dict = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self):
        params, values = self.system.parameters, dict(self.system.parameter_values)
        rng = random.Random(self.seed + 104729)
        draw = lambda: MPQ(rng.randint(1, 2 ** DRAW_BITS))
        # Parameters without values (and without generators) take these fixed values.
        object.__setattr__(self, "fixed", {p: _exact_mpq(values[p]) if p in values else draw()
                                           for p in params})
        object.__setattr__(self, "random", {p: draw() for p in params})
        hessian = self.analysis.geometry.hessian
        object.__setattr__(self, "W", [list(hessian.row(i)) for i in range(self.system.n)])
        object.__setattr__(self, "points", int(self.points))
        if self.second_class is not None:
            self._pivots["R"] = list(self.second_class)

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
        token = _FIRST_POINT_ONLY.set(True)
        try:
            yield
        finally:
            _FIRST_POINT_ONLY.reset(token)

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
        count = 1 if _FIRST_POINT_ONLY.get() else self.points
        if len(known) >= count:
            return known[:count]
        sampler = ParameterFieldSampler(self.system, eqs, env0, exact,
                                        random.Random(f"{self.seed}:{tag}"),
                                        lambda: Submanifold(self.system, eqs).reduction)
        out = [sampler.point() for _ in range(count)]
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
        """[(reason, evaluate)] for every function the analysis' decisions assumed
        nonzero (:attr:`ConstraintAnalysis.assumptions`), then the bracket datum."""
        analysis = self.analysis
        if not analysis.stages:
            return []
        out = [(a.reason, self._evaluator(a)) for a in analysis.assumptions]
        if analysis.status != "inconsistent" and analysis.final_constraints:
            out.append(("the rank of the bracket matrix on M_f drops (the first/second-class "
                        "split changes)", lambda env0, K: self._bracket_minor(env0, K)))
        return out

    def _evaluator(self, a):
        """The values of the recorded function at the datum's points: (env0, K) -> list."""
        def points(env0, K):
            return self._pts(a.on, env0, K, a.stage)

        def matrices(env0, K):
            for env in points(env0, K):
                cache = self._memo(env)
                yield [self._matrix(K, rows, env, cache) for rows in a.data]

        if a.formula == "det":
            return lambda env0, K: [log_det(self._matrix(K, a.data, env, self._memo(env)))
                                    for env in points(env0, K)]
        if a.formula == "bordered det":
            return lambda env0, K: [log_det(bordered_matrix(*mats))
                                    for mats in matrices(env0, K)]
        if a.formula == "value":
            return lambda env0, K: [self._val(K, evaluate(a.data, env, self._memo(env))[0])
                                    for env in points(env0, K)]
        if a.formula == "maximal minors":
            return lambda env0, K: self._mu_minors(a.on, env0, K)
        if a.formula == "Frobenius terms":
            return lambda env0, K: self._frobenius(a.on, env0, K)
        raise ValueError(f"unknown formula {a.formula!r} of an assumption")

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
            vals += maximal_minors(M, pivots, subsets, det=log_det)
        return vals

    @functools.cached_property
    def _dmu_nonzero(self) -> tuple:
        """d mu_i (d mu_i[A][B] = d mu_iB/dq^A - d mu_iA/dq^B) by its entries that are not
        identically zero, per row A of each d mu_i: ((B, expression), ...). Formed once
        (every evaluation of the Frobenius datum, at the values and at each shift, reads
        it; the Frobenius test too)."""
        from nhham.lagrangian.integrability import one_form_differentials

        return one_form_differentials(self.system.mu, self.system.coordinates)

    def _dmu_at(self, K, env, cache) -> list:
        """d mu at one point in K: the nonzero entries evaluated, the others K's zero."""
        n, zero = self.system.n, self._val(K, 0)
        out = []
        for rows in self._dmu_nonzero:
            block = []
            for entries in rows:
                row = [zero] * n
                values = evaluate([e for _, e in entries], env, cache) if entries else ()
                for (B, _), x in zip(entries, values):
                    row[B] = self._val(K, x)
                block.append(row)
            out.append(block)
        return out

    def _frobenius(self, eqs, env0, K):
        system = self.system
        m = system.m
        rows = [list(system.mu.row(i)) for i in range(m)]
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
            D = self._dmu_at(K, env, cache)
            vals.extend(frobenius_terms(M, D, dep).values())
        return vals

    @functools.cached_property
    def _bracket_rows(self) -> tuple:
        """(dchi/dq, dchi/dv, W, mixed Hessian) as rows, over the final constraints: the
        arguments of :func:`~nhham.lagrangian.formulas.lagrangian_bracket`. Formed once:
        every evaluation of the bracket datum reads them (the 64-link snake's 2 x 64 x 66
        derivatives were formed seven times: its classify took 93 s, 63 s now)."""
        system, cons = self.system, list(self.analysis.final_constraints)
        geometry: Any = self.analysis.geometry   # a LagrangianGeometry (typed loosely there)
        Mx = [list(geometry.mixed_hessian.row(i)) for i in range(system.n)]
        return ([jacobian_row(c, system.coordinates) for c in cons],
                [jacobian_row(c, system.velocities) for c in cons], self.W, Mx)

    def _brackets(self, env0, K, count=None):
        """B = ({chi_a, chi_b}_L) over the final constraints at points of M_f."""
        rows = self._bracket_rows
        mats = []
        pts = self._pts(list(self.analysis.final_constraints), env0, K, "f")
        for env in pts[:count]:
            cache = self._memo(env)
            if K.is_FiniteField:   # on residues (sympy's GF(p) elements: most of the cost)
                B = lagrangian_bracket(*(ListMatrix([[ModP.lift(x) for x in
                                                      evaluate(row, env, cache)]
                                                     for row in r], len(r[0]) if r else 0)
                                         for r in rows))
                mats.append(DomainMatrix([[K(x.v) for x in row] for row in B.rows],
                                         B.shape, K))
            else:
                mats.append(lagrangian_bracket(*(self._matrix(K, r, env, cache)
                                                 for r in rows)))
        return mats

    def _bracket_minor(self, env0, K):
        if "R" not in self._pivots:
            # The principal block is chosen for generic parameters (modulo p, at random
            # parameter values): at the given values its minor may vanish, which is the
            # very event the datum detects.
            with self._first_point_only():
                (B,) = self._brackets(self.env(generic=True), MODULAR)
            full = B.shape[0] and B.det()  # all second class, the usual case: no rref
            self._pivots["R"] = list(range(B.shape[0])) if full else list(B.rref()[1])
        R = self._pivots["R"]
        if R and getattr(K, "is_FractionField", False):
            free = self._ring_bracket_minors(env0, K, R)
            if free is not None:
                return free
        mats = self._brackets(env0, K)  # first: a point not exact here is said so
        if not R:
            return []
        return [log_det(B.extract(R, R)) for B in mats]

    def _ring_bracket_minors(self, env0, K, R):
        """det B_RR at the points of M_f with the parameters symbolic (K = Q(p)), formed
        without division in the polynomial ring of K, or None where an entry has a
        parameter in a denominator.

        In Q(p) every sum cancels a gcd of multivariate polynomials, which grows with
        each step of W⁻¹ J_vᵀ and its products (the roller racer's 2 x 2 B did not end
        in 300 s; this way it takes 0.2 s a point). With U = d W⁻¹ J_vᵀ from the
        fraction-free solve W U = d J_vᵀ, the same formula at d J_q gives d² B
        (:func:`~nhham.lagrangian.formulas.lagrangian_bracket` is quadratic in W⁻¹ J_vᵀ
        and linear in J_q), so det B_RR = det(d² B_RR) / d^(2r): its numerator is that
        determinant divided by its gcd with d^(2r), taken one gcd with d at a time (the
        numerators of the values are what the exceptional set is made of).
        """
        ring = K.get_ring()
        rows = self._bracket_rows
        out = []
        for env in self._pts(list(self.analysis.final_constraints), env0, K, "f"):
            cache = self._memo(env)
            try:
                Jq, Jv, W, M = (self._matrix(K, r, env, cache).convert_to(ring)
                                for r in rows)
            except CoercionFailed:
                return None
            if not W.det():
                return None  # W singular at the point: the field route says so
            # W U = d J_vᵀ without division (sympy's charpoly route fails on constant W)
            U, d = W.solve_den(Jv.transpose(), method="rref")
            scaled = lagrangian_bracket(Jq * d, Jv, W, M, solve=lambda _W, _X: U)
            value = scaled.extract(R, R).det()
            for _ in range(2 * len(R)):
                g = ring.gcd(value, d)
                if g == ring.one or not value:
                    break
                value = ring.exquo(value, g)
            out.append(K.convert_from(value, ring))
        return out

    def _unchecked_note(self) -> str:
        """What the verdict at the values rests on when M_1 has no exact points.

        A decision taken at float points is taken with the parameters at their values
        (:class:`~nhham.lagrangian.submanifold.Submanifold` samples them so): when every
        decision was, the verdict is already the one at the values, and there is no
        generic verdict whose exceptional sets the values could fall in. So does a proof
        at a point of a curved M_1 over F_p (its ``Decision.scope``), drawn with the
        parameters at their values: when every decision is one, there is nothing left
        to check and the note is empty. An exact "vanishes" holds at every value; an
        exact rank or "does not vanish" (and "not integrable") by reduction holds for
        generic parameters: those decisions are named, but for "not integrable" proved
        again at a point over F_p with the parameters at their values.
        """
        analysis = self.analysis
        decisions = [(ev.subject, ev.decision) for st in analysis.stages
                     for ev in st.decisions]
        if analysis.integrable is False:
            decisions += [("integrability", d) for _, d in analysis.integrability.decisions]
        # A decision taken at points (exact ones, or a proof at a point of a curved M_1:
        # a scope) was taken with the parameters at their values; a reduction
        # (samples = 0) for generic ones.
        generic = list(dict.fromkeys(
            subject for subject, d in decisions
            if d.method != "sampled" and not d.scope and not d.samples
            and _nonzero_claim(d.value)))
        if "integrability" in generic and _not_integrable_at_values(self.system, self.seed):
            generic.remove("integrability")
        sampled = any(d.method == "sampled" for _, d in decisions)
        if not generic and not sampled:
            return ""  # every decision proved at the values: nothing left to check
        if not generic:
            drawn = [p.name for p in self.system.parameters
                     if p not in self.system.parameter_values]
            return ("no exact points of M_1: every decision that could change with the "
                    "parameters was taken at float points with the parameters at their "
                    "values" + (f" ({', '.join(drawn)} at random values)" if drawn else "")
                    + " (sampled, not proved), so the verdict is the one at these values; "
                    "there is no generic verdict whose exceptional sets they could fall in")
        return ("the parameter values were not checked against the exceptional sets of the "
                "decisions taken for generic parameters (" + "; ".join(generic[:3])
                + ("; ..." if len(generic) > 3 else "") + "): no exact points of M_1")

    # ------------------------------------------------------------ the modes
    def _has_points(self, env0, K, note) -> bool:
        """Whether M_1 has exact points over K; else a note ``note (why)`` (none when
        ``note`` is empty)."""
        try:
            if self.analysis.stages:
                self._pts(self.analysis.stages[0].constraints, env0, K, 1)
        except (NotExact, ZeroDivisionError) as exc:
            if note:
                self.notes.append(f"{note} ({exc})")
            return False
        return True

    def symbolic(self, params):
        """[(reason, values)] with ``params`` as generators of Q(params)."""
        K = QQ.frac_field(*params)
        env0 = self.env(gens=dict(zip(params, K.gens)))
        out = []
        items = self.items()
        if not self._has_points(env0, K, "the exceptional sets were not computed: no exact "
                                "points of M_1 with symbolic parameters"):
            return out
        unexamined: list = []
        for k, (reason, fn) in enumerate(items):
            try:
                with part(f"where {reason}: values at exact points",
                          f"datum {k + 1} of {len(items)}, {len(params)} parameters symbolic",
                          after=SLOW):
                    vals = fn(env0, K)
            except (NotExact, ZeroDivisionError) as exc:
                unexamined.append((str(exc), reason))
                continue
            if any(vals):
                out.append((reason, vals))
        self.notes.extend(unexamined_notes(self.system, unexamined, "not examined"))
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
        hits, close, unexamined = [], [], []
        values = {p: _exact_mpq(x) for p, x in values.items()}
        base = self.env(at=values)
        items = self.items()
        if not self._has_points(base, QQ, self._unchecked_note()):
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
                unexamined.append((str(exc), reason))
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
        self.notes.extend(unexamined_notes(self.system, unexamined,
                                           "not examined at the values"))
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
    the largest 1 / |(p_i dP/dp_i) / P| (every term must vanish there), to first order the
    smallest change of the parameters, each relative to its own value, that makes it
    vanish.

    Free of units: a parameter's unit changes neither p_i dP/dp_i / P nor the distance
    (dividing an absolute |P| / |grad P| by |values| mixed the units: m = 1e30 kg put a
    sleigh "near" a singular C whose condition number is 1). Each term enters through its
    logarithmic derivative (P(x + h) - P(x)) / (h P(x)), formed in the field of the values
    before it becomes a float, so a determinant of a large system (|P| beyond 1e308 or
    below 1e-308) neither overflows nor underflows. Raises ZeroDivisionError when a float64
    value is not usable (zero by underflow, or not finite): the caller then works in a
    wider field.
    """
    worst = 0.0
    for i, val in enumerate(v0):
        if not nonzero[i]:
            continue
        slope = math.hypot(*(_log_slope(vals[i], val, h) * abs(float(values[p]))
                             for p, (h, vals) in shifted.items()))
        worst = max(worst, 1.0 / slope if slope else math.inf)
    return worst


def _log_slope(moved, value, h) -> float:
    """(moved - value) / (h value) as a float, computed in the field of the values (a
    float64 determinant by its logarithm: :class:`~nhham.lagrangian.linalg.LogDet`)."""
    if isinstance(value, LogDet):
        if not value or not math.isfinite(value.log):
            raise ZeroDivisionError("a float64 determinant vanished or was not finite")
        ratio = LogDet.of(moved) / value
        if not math.isfinite(ratio):
            raise ZeroDivisionError("a float64 determinant ratio was not finite")
        return (ratio - 1.0) / float(h)
    if isinstance(value, float):
        if value == 0.0 or not (math.isfinite(value) and math.isfinite(moved)):
            raise ZeroDivisionError("a float64 value underflowed or overflowed")
        return (moved / value - 1.0) / float(h)
    step = h if isinstance(value, MPQ) else SHIFT_FIELD.convert(h)
    return float((moved - value) / (step * value))


# ======================================================== signs and solving
def _exact_mpq(value):
    r = sp.Rational(str(value))
    return MPQ(int(r.p), int(r.q))


def _not_integrable_at_values(system, seed: int) -> bool:
    """Non-integrability proved at a point of Q_1 over F_p with the parameters at their
    values (a reduction proved it for generic ones)."""
    from nhham.lagrangian.engine import Policy
    from nhham.lagrangian.integrability import integrability_proved_at_values

    at = integrability_proved_at_values(system, Policy(seed=seed))
    return at is not None and at.integrable is False
