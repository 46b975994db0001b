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
import math
import random
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp

from nhham.settings import SEED
from nhham.errors import InputError
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.hamiltonian.legendre import Backend, ModularBackend, Lambdified, canonical_form_matrix
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.domains import PRIME, ModP, NotExact
from nhham.lagrangian.formulas import lagrangian_bracket
from nhham.lagrangian.linalg import FloatMatrix, exact_rank, exact_solve
from nhham.lagrangian.points import PointSampler, eliminate_coordinates, jacobian_row
from nhham.system.expressions import derivative
from nhham.lagrangian.submanifold import Submanifold

__all__ = ["CheckResult", "CrossCheckReport", "cross_check", "METHODS"]

# "exact": symbolic differences; "points": both sides in exact arithmetic modulo p at
# seeded exact points of M_1; "sampled": both sides in floating point at sampled points.
METHODS = ("auto", "exact", "points", "sampled")

# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class CheckResult:
    """One comparison of the cross-check.

    Attributes
    ----------
    name : str
    agree : bool
    exact : bool
        True when agreement was decided exactly (the symbolic difference
        cancels, or reduces to zero on M_f by exact reduction).
    max_abs_difference, max_rel_difference : float
        Over the sample points (0 when the check has no numeric part).
    samples : int
    detail : str
    decisions : tuple of Decision
        Decisions on M_f behind ``exact`` (when a difference had to be reduced).
    method : str
        How the numbers were compared: ``"exact"`` (symbolic), ``"points"``
        (exact arithmetic modulo p at exact points: each difference is exactly 0,
        which is a proof at those points, not of the identity) or ``"sampled"``.
    """

    name: str
    agree: bool
    exact: bool
    max_abs_difference: float = 0.0
    max_rel_difference: float = 0.0
    samples: int = 0
    detail: str = ""
    decisions: tuple = ()
    method: str = ""

    @property
    def how(self) -> str:
        """``method``, defaulting to "exact" or "sampled" from ``exact``."""
        return self.method or ("exact" if self.exact else "sampled")

    def to_dict(self) -> dict:
        return {"agree": self.agree, "exact": self.exact,
                "max_abs_difference": self.max_abs_difference,
                "max_rel_difference": self.max_rel_difference, "samples": self.samples,
                "detail": self.detail, "method": self.how}


@dataclass(frozen=True)
class CrossCheckReport:
    """Lagrangian <-> Hamiltonian agreement through the Legendre map.

    Attributes
    ----------
    agree : bool
        Every check agrees.
    exact : bool
        Every check was decided exactly.
    max_abs_difference, max_rel_difference : float
        Largest over the checks' sampled differences.
    samples : int
        Number of seeded points of M_f.
    tolerance : float
        Relative tolerance of sampled agreement.
    precision : str
        ``"float64"``, ``"mpmath:<digits>"`` or ``"exact mod p = 2^61 - 1"``.
    method : str
        ``"exact"``, ``"points"`` or ``"sampled"``.
    checks : tuple of CheckResult
    lagrangian_stages, hamiltonian_stages : tuple of dict
        Per stage: index, number of constraints, rank, augmented rank, labels.
    statuses : tuple of str
        (TQ status, T*Q status).
    seconds : float
        Wall time of the cross-check.
    skipped_points : int
        Seeded points dropped because C is not of its generic rank there.
    """

    agree: bool
    exact: bool
    max_abs_difference: float
    max_rel_difference: float
    samples: int
    tolerance: float
    precision: str
    method: str
    checks: tuple
    lagrangian_stages: tuple
    hamiltonian_stages: tuple
    statuses: tuple
    seconds: float
    skipped_points: int = 0

    @property
    def detail(self) -> dict:
        """``{check name: CheckResult}``."""
        return {c.name: c for c in self.checks}

    def describe(self) -> str:
        head = (f"cross-check ({self.method}, {self.precision}): "
                f"{'AGREE' if self.agree else 'DISAGREE'}"
                f"{' exactly' if self.exact and self.agree else ''}; max |difference| "
                f"{self.max_abs_difference:.3g} (relative {self.max_rel_difference:.3g}) at "
                f"{self.samples} seeded points of M_f, tolerance {self.tolerance:g}"
                + (f" ({self.skipped_points} non-generic point(s) skipped)"
                   if self.skipped_points else ""))
        lines = [head]
        for c in self.checks:
            lines.append(f"  {c.name}: {'agrees' if c.agree else 'DIFFERS'} "
                         f"({c.how}): {c.detail}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready (keys used by ``nhham compare --json``)."""
        return {
            "agree": self.agree, "exact": self.exact,
            "max_abs_difference": self.max_abs_difference,
            "max_rel_difference": self.max_rel_difference,
            "samples": self.samples, "tolerance": self.tolerance,
            "precision": self.precision, "method": self.method,
            "checks": {c.name: c.to_dict() for c in self.checks},
            "lagrangian_stages": [dict(s) for s in self.lagrangian_stages],
            "hamiltonian_stages": [dict(s) for s in self.hamiltonian_stages],
            "statuses": list(self.statuses),
            "seconds": self.seconds, "skipped_points": self.skipped_points,
        }


# --------------------------------------------------------------- numerics
class _ComparisonPoints:
    """Seeded points of M_f in TQ and comparisons of numeric vectors there."""

    def __init__(self, system, equations, precision, samples, seed, tol, exact=True):
        self.system = system
        self.backend = Backend(precision)
        self.tol = tol
        self.manifold = Submanifold(system, tuple(equations), precision=precision,
                                    samples=samples, seed=seed, exact=exact)
        self.dropped = 0
        self.args = (tuple(system.coordinates) + tuple(system.velocities)
                     + tuple(system.parameters))

    @cached_property
    def all_points(self):
        return self.manifold.points()[0]

    @cached_property
    def points(self):
        """The sample points where C has its generic (largest) rank.

        Newton projection can land on the singular set of C (the snakeboard at
        phi = +-pi/2), where the dynamics is not defined; such points are
        dropped and counted in :attr:`dropped`.
        """
        pts = self.all_points
        if not self.system.m:
            return pts
        lag = _NumericLagrangian(self.system, self.args)
        be = self.backend
        with be.context():
            ranks = []
            for pt in pts:
                try:
                    ranks.append(self.rank(_lag_C(lag, be, self.values(pt))))
                except (np.linalg.LinAlgError, ZeroDivisionError, ValueError):
                    ranks.append(-1)
        top = max(ranks)
        keep = [pt for pt, r in zip(pts, ranks) if r == top]
        self.dropped = len(pts) - len(keep)
        return keep

    def values(self, pt) -> list:
        return [self.backend.scalar(pt[s]) for s in self.args]

    def rank(self, C) -> int:
        return _numeric_rank(C, self.tol)

    def compare(self, pairs) -> tuple[float, float, bool]:
        """(max abs, max rel, agree) over an iterable of (a, b) numeric arrays.

        The relative difference is |a - b| / max(1, |a|, |b|) (infinity
        norms): the quantity compared with the tolerance. Pairs where either
        side is not finite (a sample point where C is singular, outside the
        domain of the dynamics) are skipped and counted in ``self.skipped``;
        if every pair is skipped the comparison fails.
        """
        worst_abs, worst_rel, ok, used = 0.0, 0.0, True, 0
        self.skipped = 0
        for a, b in pairs:
            a = np.asarray(a).ravel()
            b = np.asarray(b).ravel()
            if a.size == 0:
                used += 1
                continue
            fa = [float(abs(x)) for x in a]
            fb = [float(abs(y)) for y in b]
            if not (all(np.isfinite(fa)) and all(np.isfinite(fb))):
                self.skipped += 1
                continue
            used += 1
            d = float(max(abs(x - y) for x, y in zip(a, b)))
            scale = max(1.0, max(fa), max(fb))
            worst_abs = max(worst_abs, d)
            worst_rel = max(worst_rel, d / scale)
            ok = ok and d <= self.tol * scale
        if self.skipped and not used:
            return float("inf"), float("inf"), False
        return worst_abs, worst_rel, ok

    def note(self) -> str:
        """Text about skipped points of the last comparison."""
        k = getattr(self, "skipped", 0)
        return f" ({k} sample point(s) skipped: not finite there)" if k else ""


class _ModularComparisonPoints(_ComparisonPoints):
    """Seeded points of M_1 over F_p (:class:`~nhham.lagrangian.points.PointSampler`
    with ``modular=True``): every quantity is computed exactly modulo p, so a
    difference is zero or it is not."""

    def __init__(self, system, samples, seed, sampler: PointSampler | None = None):
        self.system = system
        self.backend = ModularBackend()
        self.tol = 0.0
        self.dropped = 0
        self.args = (tuple(system.coordinates) + tuple(system.velocities)
                     + tuple(system.parameters))
        self.count = int(samples)
        self.sampler = sampler or PointSampler.on_M1(system, seed, modular=True)

    @classmethod
    def on(cls, system, constraints, samples, seed) -> "_ModularComparisonPoints":
        """Seeded points of M = {constraints = 0} over F_p: the constraints free of
        velocities are solved for coordinates, those affine in the velocities for
        dependent velocities (NotExact for any other constraint)."""
        vels = set(system.velocities)
        holonomic: list = []
        rest = [sp.sympify(c) for c in constraints]
        # A constraint that becomes free of velocities once the coordinates solved so far
        # are substituted (q2 - 2 q1 v1^2 where q1 = 0) is solved for a coordinate too.
        while True:
            solved = eliminate_coordinates(system.coordinates, holonomic)
            reduced = [sp.expand(c.xreplace(solved)) for c in rest]
            more = [c for c in reduced if c != 0 and not c.free_symbols & vels]
            if not more:
                break
            holonomic += more
            rest = [c for c, r in zip(rest, reduced) if r.free_symbols & vels]
        affine = [c for c in reduced if c != 0]
        for c in affine:
            if any(e.free_symbols & vels for e in jacobian_row(c, system.velocities)):
                raise NotExact(f"{c} is not affine in the velocities")
        return cls(system, samples, seed, PointSampler(
            system.coordinates, system.velocities, system.parameters,
            dict(system.parameter_values), holonomic, affine, seed, modular=True))

    @cached_property
    def all_points(self):
        # Velocities in F_p (solved ones may come out as exact 0); coordinates stay
        # angles or exact numbers so that sin and cos of them stay exact.
        vels = set(self.system.velocities)
        return [{s: ModP.lift(x) if s in vels else x for s, x in self.sampler.point().env.items()}
                for _ in range(self.count)]

    def values(self, pt) -> list:
        return [pt[s] for s in self.args]

    def rank(self, C) -> int:
        return exact_rank([list(row) for row in C])[0] if C.size else 0

    def compare(self, pairs) -> tuple[float, float, bool]:
        """(0, 0, True) when every difference is 0 modulo p; (nan, nan, False) otherwise
        (F_p has no absolute value: a nonzero difference has no size)."""
        self.skipped = 0
        ok = all(all(x == y for x, y in zip(np.asarray(a).ravel(), np.asarray(b).ravel()))
                 for a, b in pairs)
        return (0.0, 0.0, True) if ok else (math.nan, math.nan, False)


class _NumericLagrangian:
    """P(xi_L), lambda, Leg_* and {f, g}_L at points of TQ by numeric solves with W."""

    def __init__(self, system, args):
        geo = lagrangian_geometry(system)
        ing = geo.ingredients
        n, m = system.n, system.m
        self.n, self.m = n, m
        self._W = Lambdified(args, list(ing.W), (n, n))
        self._F = Lambdified(args, list(ing.forcing), (n,))
        self._mu = Lambdified(args, list(ing.mu), (m, n))
        self._drift = Lambdified(args, list(ing.drift), (m,))
        self._M = Lambdified(args, list(geo.mixed_hessian), (n, n))
        self.args = args
        self.system = system
        self._grads: dict = {}

    def projected(self, be: Backend, vals):
        """(Leg_* P(xi_L) as a 2n-vector at Leg(x), lambda, C) at x."""
        n = self.n
        W, F, M = self._W(be, vals), self._F(be, vals), self._M(be, vals)
        v = np.array(vals[n:2 * n], dtype=object if be.precision else float)
        a = be.solve(W, F)
        if self.m:
            mu, drift = self._mu(be, vals), self._drift(be, vals)
            WmT = be.solve(W, mu.T)
            C = -(mu @ WmT)
            xi_phi = drift + mu @ a
            lam = -be.solve(C.T, xi_phi)
            acc = a - WmT @ lam
        else:
            lam, C, acc = be.zeros(0), be.zeros(0, 0), a
        return self._pushed(v, acc, W, M), lam, C

    def field(self, be: Backend, vals, lam):
        """Leg_*(xi_L + lambda^i Z_i) at x for given multipliers lambda, a 2n-vector."""
        n = self.n
        W, F, M, mu = self._W(be, vals), self._F(be, vals), self._M(be, vals), \
            self._mu(be, vals)
        v = np.array(vals[n:2 * n], dtype=object if be.precision else float)
        return self._pushed(v, be.solve(W, F) - be.solve(W, mu.T) @ lam, W, M)

    @staticmethod
    def _pushed(v, acc, W, M):
        """Leg_* (v, acc) = (v, M v + W acc)."""
        return np.concatenate([v, M @ v + W @ acc])

    def gradients(self, be, vals, exprs):
        key = tuple(exprs)
        if key not in self._grads:
            q, v = self.system.coordinates, self.system.velocities
            k, n = len(exprs), self.n
            self._grads[key] = (
                Lambdified(self.args, [derivative(e, s) for e in exprs for s in q], (k, n)),
                Lambdified(self.args, [derivative(e, s) for e in exprs for s in v], (k, n)))
        gq, gv = self._grads[key]
        return gq(be, vals), gv(be, vals)

    def bracket_matrix(self, be, vals, exprs):
        """{f_a, f_b}_L = f_q W^{-1} g_v - (W^{-1} f_v) g_q - (W^{-1} f_v)^T A (W^{-1} g_v)."""
        Gq, Gv = self.gradients(be, vals, exprs)
        B = lagrangian_bracket(FloatMatrix(Gq), FloatMatrix(Gv), FloatMatrix(self._W(be, vals)),
                               FloatMatrix(self._M(be, vals)),
                               solve=lambda A, X: FloatMatrix(be.solve(A.a, X.a)))
        return B.a


# ------------------------------------------------------------- the driver
def cross_check(system, precision: int | None = None, samples: int = 6, seed: int = SEED,
                tol: float | None = None, method: str = "auto",
                max_stages: int | None = None,
                side: HamiltonianSide | None = None) -> CrossCheckReport:
    """Check that the Lagrangian and Hamiltonian sides agree through the Legendre map.

    Parameters
    ----------
    system : nhham.System
    precision : int or None
        None for float64, an integer for mpmath digits (sample points and
        numeric evaluation).
    samples, seed : int
        Seeded points of M_f for the numeric comparisons and sampled decisions.
    tol : float, optional
        Relative tolerance of sampled agreement (default 1e-9 in float64,
        10**(3 - digits) in mpmath).
    method : {"auto", "exact", "points", "sampled"}
        ``"exact"``: symbolic differences (cancelled, or reduced on M_f) plus
        the sampled numbers; ``"points"``: both sides evaluated in exact
        rational arithmetic at ``samples`` seeded exact points of M_1 (no
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
        v, ``precision`` is None and M_1 has exact points, else sampled.
    max_stages : int, optional
        Bound of the constraint algorithm (default 2n).
    side : HamiltonianSide, optional
        The T*Q side of ``system`` when the caller has it (its numeric layer is
        built once for several checks).

    Returns
    -------
    CrossCheckReport
    """
    if method not in METHODS:
        raise InputError(f"cross_check: method must be one of {', '.join(map(repr, METHODS))}, "
                         f"got {method!r}")
    start = time.perf_counter()
    if side is None:
        # closed forms only where symbolic_affordable chose them
        side = hamiltonian_side(system, precision=precision, samples=samples, seed=seed,
                                closed_form=True)
    requested, tol_given = method, tol
    sampler = None
    if method == "auto":
        method = "exact" if side.symbolic_affordable else "sampled"
        if method == "sampled" and precision is None:
            sampler = _modular_sampler(system, side, samples, seed)
            method = "points" if sampler is not None else "sampled"
    elif method == "points":
        sampler = _modular_sampler(system, side, samples, seed, required=True)
    def float_sampler():
        return _ComparisonPoints(system, tuple(system.holonomic) + tuple(system.phi), precision,
                        samples, seed, tol_given if tol_given is not None else
                        Backend(precision).default_tol(), exact=False)

    if method != "exact" and sampler is None:
        sampler = float_sampler()
    be = sampler.backend if sampler is not None else Backend(precision)
    tol = be.default_tol() if tol is None or method == "points" else float(tol)
    if method == "exact":
        checks, stages_L, stages_H, statuses, (npts, skipped) = _exact(
            system, side, precision, samples, seed, tol, max_stages)
    else:
        try:
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
                got = _staged_at_points(system, side, samples, seed, max_stages)
            except (NotExact, ZeroDivisionError):
                got = None
        if got is None:
            # C is singular at the samples: stages need the symbolic algorithm.
            method, be = "exact", Backend(precision)
            tol = be.default_tol()
            got = _exact(system, side, precision, samples, seed, tol, max_stages)
        checks, stages_L, stages_H, statuses, (npts, skipped) = got
    return CrossCheckReport(
        agree=all(c.agree for c in checks), exact=all(c.exact for c in checks),
        max_abs_difference=max((c.max_abs_difference for c in checks), default=0.0),
        max_rel_difference=max((c.max_rel_difference for c in checks), default=0.0),
        samples=npts, tolerance=tol, precision=be.label, method=method, checks=tuple(checks),
        lagrangian_stages=stages_L, hamiltonian_stages=stages_H, statuses=statuses,
        seconds=time.perf_counter() - start, skipped_points=skipped)


def _stage_summaries(stages) -> tuple:
    return tuple({"index": st.index, "constraints": len(st.constraints), "rank": st.rank,
                  "augmented_rank": st.augmented_rank, "labels": list(st.labels)}
                 for st in stages)


# ---------------------------------------------------------------- exact
def _exact(system, side: HamiltonianSide, precision, samples, seed, tol, max_stages):
    from nhham.lagrangian.analysis import analyze_constraints

    leg = side.legendre
    analysis = analyze_constraints(system, precision=precision, samples=samples, seed=seed,
                                   max_stages=max_stages, decompose=False)
    run_H = side.analysis(max_stages)
    stages_L, stages_H = _stage_summaries(analysis.stages), _stage_summaries(run_H.stages)
    statuses = (analysis.status, run_H.status)
    checks = [_check_stages(system, side, analysis, run_H)]
    final = analysis.final_constraints if analysis.status != "inconsistent" else (
        tuple(system.holonomic) + tuple(system.phi))
    sampler = _ComparisonPoints(system, final, precision, samples, seed, tol)
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
            lhs = leg.tangent_map(analysis.dynamics)
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
    """Is lhs - rhs = 0 on all of TQ? (holds, exact, decisions)."""
    diff = (sp.Matrix(lhs) - sp.Matrix(rhs)).applyfunc(cancel)
    decisions = [tq_everywhere.vanishes(d) for d in diff if d != 0]
    return (all(d.value for d in decisions), all(d.method == "exact" for d in decisions),
            decisions)


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
        ("Leg_* xi_L = X_H o Leg", leg.tangent_map(geo.euler_lagrange_field),
         side.X_H.applyfunc(pull)),
        ("Leg_* Z_j = Z_j^H o Leg",
         sp.Matrix.hstack(*[leg.tangent_map(geo.vertical_fields.row(j).T)
                            for j in range(system.m)]) if system.m else sp.zeros(0, 1),
         side.vertical_fields.T if system.m else sp.zeros(0, 1)),
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
            ("field", parts + lam_parts, field_pairs, "Leg_*(P(xi_L)) against X o Leg")):
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
    lag = _NumericLagrangian(system, sampler.args)
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


def _compare_exact(name, lhs, rhs, sampler: _ComparisonPoints, free, what) -> CheckResult:
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


def _check_inverse_exact(side, sampler) -> CheckResult:
    leg = side.legendre
    to_p = dict(zip(leg.momentum_symbols, leg.momenta))
    back = sp.Matrix([cancel(leg.inverse[v].xreplace(to_p) - v) for v in leg.velocities]) \
        if leg.has_exact_inverse else None
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
    return CheckResult("legendre inverse", exact_ok and ok, exact_ok, ab, rel, len(pairs),
                       f"Leg^-1 o Leg = id ({leg.inverse_kind} inverse): "
                       + ("cancels identically" if exact_ok else f"residual {list(back)}"))


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


# ---------------------------------------------------------------- sampled
def _modular_sampler(system, side, samples, seed, required=False):
    """An :class:`_ModularComparisonPoints` when both sides can be evaluated exactly at exact points
    of M_1 (L quadratic in v, so Leg^-1 is one linear solve; M_1 with exact points),
    else None (or an error naming why, when ``required``)."""
    why = None
    if not side.legendre.is_quadratic:
        why = "L is not quadratic in the velocities (Leg^-1 is solved numerically)"
    else:
        try:
            sampler = _ModularComparisonPoints(system, samples, seed)
            sampler.points  # noqa: B018 - draws the points, or raises NotExact
            return sampler
        except (NotExact, ZeroDivisionError) as exc:
            why = f"no exact points of M_1 ({exc})"
    if required:
        raise InputError(f"cross_check: method 'points' is not available: {why}")
    return None


def _sampled(system, side: HamiltonianSide, sampler):
    """Checks at points of M_1 for a regular system, in floating point or (an
    :class:`_ModularComparisonPoints`) exactly; None when C is singular there."""
    primary = tuple(system.holonomic) + tuple(system.phi)
    exactly = isinstance(sampler, _ModularComparisonPoints)
    how = "exact solves modulo p" if exactly else "numeric solves"
    be = sampler.backend
    lag = _NumericLagrangian(system, sampler.args)
    num = side.numeric
    field_pairs, lam_pairs, inv_pairs, br_pairs = [], [], [], []
    ranks_L, ranks_H = [], []
    m = system.m
    with be.context():
        for pt in sampler.points:
            vals = sampler.values(pt)
            hp = num.point_from_tq(be, pt)
            inv_pairs.append((hp.v, np.array(vals[system.n:2 * system.n])))
            ranks_L.append(sampler.rank(_lag_C(lag, be, vals)))
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
             "labels": list(_labels(system))}
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
                              f"Leg_*(P(xi_L)) against X o Leg, both by {how}" + skip))
    ab, rel, ok = sampler.compare(lam_pairs)
    checks.append(CheckResult("multipliers", ok, False, ab, rel, len(lam_pairs),
                              "lambda^L against lambda^H o Leg"))
    checks.append(_check_form_sampled(side, sampler, lag))
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


# ------------------------------------------- singular C: exact points of every M_k
@dataclass(frozen=True)
class _Tangency:
    """The stage data of one side at one point: T (k, m) with T[j, i] = Z_i(chi_j) and
    xi (k,) with xi[j] = xi(chi_j), for the constraints chi of a stage."""

    T: np.ndarray
    xi: np.ndarray


def _tangency_L(lag: _NumericLagrangian, be, vals, chis) -> _Tangency:
    """On TQ: Z_i = -W^{AB} mu_iB d/dv^A and xi_L = v d/dq + W^{-1} F d/dv."""
    n = lag.n
    W, F, mu = lag._W(be, vals), lag._F(be, vals), lag._mu(be, vals)
    v = np.array(vals[n:2 * n], dtype=object)
    Gq, Gv = lag.gradients(be, vals, chis)
    return _Tangency(-(Gv @ be.solve(W, mu.T)), Gq @ v + Gv @ be.solve(W, F))


def _tangency_H(num, be, hp, chis) -> _Tangency:
    """On T*Q, of chi o Leg^{-1}: Z_i^H = -mu_iA d/dp_A and X_H = (dH/dp, -dH/dq)."""
    _, dq, dp = num.gradients(be, hp, chis)
    return _Tangency(-(dp @ hp.mu.T), dq @ hp.Hp - dp @ hp.Hq)


def _solutions(t: _Tangency):
    """(rank, augmented rank, particular lambda, kernel basis) of T lambda = -xi over F_p.

    The particular solution is zero off the pivot columns; the kernel has one vector
    per non-pivot column. Both are None when the system is inconsistent.
    """
    k, m = t.T.shape
    rows = [list(r) for r in t.T]
    r, prow, pcol = exact_rank(rows) if k and m else (0, [], [])
    aug = exact_rank([row + [x] for row, x in zip(rows, t.xi)])[0] if k else 0
    if aug > r:
        return r, aug, None, None
    zero = ModularBackend().zeros(m)
    block = [[rows[i][j] for j in pcol] for i in prow]
    lam = zero.copy()
    if r:
        for j, x in zip(pcol, exact_solve(block, [[-t.xi[i]] for i in prow])):
            lam[j] = x[0]
    kernel = []
    for j in (j for j in range(m) if j not in pcol):
        vec = zero.copy()
        vec[j] = ModP(1)
        if r:
            for c, x in zip(pcol, exact_solve(block, [[rows[i][j]] for i in prow])):
                vec[c] = -x[0]
        kernel.append(vec)
    return r, aug, lam, kernel


def _staged_at_points(system, side: HamiltonianSide, samples, seed, max_stages):
    """The checks of a system whose C is singular, at exact points of every M_k.

    The constraint algorithm on TQ is the inverse-free one; the T*Q algorithm is
    not run symbolically (that would need H through Leg^{-1}). Instead its data at
    Leg of exact points of each M_k, Z_i^H(chi_j^H) and X_H(chi_j^H) with chi^H =
    chi o Leg^{-1}, are computed modulo p and compared with Z_i(chi_j) and
    xi_L(chi_j): equal data give the same ranks, conditions and multipliers on both
    sides, so the T*Q algorithm's stages are the TQ ones at those points. On M_f
    each side solves its own final tangency system for lambda and the fields are
    compared at common multipliers (free multipliers given the same seeded values).

    Raises
    ------
    NotExact
        When some M_k has no exact points (a constraint neither solvable for a
        coordinate nor affine in the velocities), or the ranks at the points are not
        the algorithm's generic ones (parameter values where they drop).
    """
    from nhham.lagrangian.analysis import analyze_constraints

    analysis = analyze_constraints(system, samples=samples, seed=seed,
                                   max_stages=max_stages, decompose=False)
    inconsistent = analysis.status == "inconsistent"
    samplers = [_ModularComparisonPoints.on(system, st.constraints, samples, seed + st.index)
                for st in analysis.stages]
    # No M_f when the run is inconsistent: the round trip, the form and the brackets of
    # the primary constraints are then checked at the points of M_1.
    if inconsistent:
        final, chis = samplers[0], tuple(system.holonomic) + tuple(system.phi)
    else:
        final = _ModularComparisonPoints.on(system, analysis.final_constraints, samples, seed)
        chis = tuple(analysis.final_constraints)
    for smp in samplers + [final]:
        smp.all_points  # noqa: B018 - draws the points, or raises NotExact
    be = final.backend
    lag = _NumericLagrangian(system, final.args)
    num = side.numeric
    m = system.m
    checks, problems, data_pairs, stages_H, dropped = [], [], [], [], 0
    for st, smp in zip(analysis.stages, samplers):
        seen_L, seen_H = [], []
        for pt in smp.all_points:
            vals = smp.values(pt)
            hp = num.point_from_tq(be, pt)
            tL = _tangency_L(lag, be, vals, st.constraints)
            tH = _tangency_H(num, be, hp, st.constraints)
            data_pairs += [(tL.T, tH.T), (tL.xi, tH.xi)]
            seen_L.append(_solutions(tL)[:2])
            seen_H.append(_solutions(tH)[:2])
        rank_L, rank_H = max(seen_L), max(seen_H)
        dropped += sum(1 for x in seen_L if x[0] < rank_L[0])
        stages_H.append({"index": st.index, "constraints": len(st.constraints),
                         "rank": rank_H[0], "augmented_rank": rank_H[1],
                         "labels": list(st.labels)})
        if rank_L != (st.rank, st.augmented_rank):
            # The points carry the parameter values, the algorithm's ranks are generic:
            # the values are exceptional, which the symbolic route handles.
            raise NotExact(f"stage {st.index}: ranks {rank_L[0]}/{rank_L[1]} at the points, "
                           f"{st.rank}/{st.augmented_rank} generically")
        if rank_H != rank_L:
            problems.append(f"stage {st.index}: ranks {rank_L[0]}/{rank_L[1]} (TQ) vs "
                            f"{rank_H[0]}/{rank_H[1]} (T*Q)")
    _, _, same_data = final.compare(data_pairs)
    if not same_data:
        problems.append("Z_i^H(chi^H), X_H(chi^H) differ from Z_i(chi), xi_L(chi) at "
                        "exact points of some M_k")
    # On M_f every stage's T*Q system is consistent: Leg(M_f) lies in the T*Q M_f.
    field_pairs, lam_pairs, inv_pairs, br_pairs, kernel_dims = [], [], [], [], set()
    rng = random.Random(seed + 7)
    top = analysis.stages[-1].rank
    for pt in final.all_points:
        vals = final.values(pt)
        hp = num.point_from_tq(be, pt)
        inv_pairs.append((hp.v, np.array(vals[system.n:2 * system.n], dtype=object)))
        br_pairs.append((num.bracket_matrix(be, hp, chis), lag.bracket_matrix(be, vals, chis)))
        if inconsistent:
            continue
        for st in analysis.stages:
            if _solutions(_tangency_H(num, be, hp, st.constraints))[2] is None:
                problems.append(f"stage {st.index}: the T*Q tangency equations are "
                                f"inconsistent at Leg of a point of M_f")
        tL = _tangency_L(lag, be, vals, analysis.final_constraints)
        tH = _tangency_H(num, be, hp, analysis.final_constraints)
        rL, _, lamL, kernel = _solutions(tL)
        rH, _, lamH, _ = _solutions(tH)
        if lamL is None or lamH is None or rL < top or rH < top:
            dropped += 1  # not a generic point of M_f
            continue
        kernel_dims.add(len(kernel))
        # The two sides' solutions agree when they differ by a kernel vector of T.
        lam_pairs.append((tL.T @ lamH, -tL.xi))
        lam = lamL + sum((k * ModP(rng.randrange(1, PRIME)) for k in kernel), be.zeros(m))
        field_pairs.append((lag.field(be, vals, lam), hp.X_H + hp.vertical().T @ lam))
    free = len(analysis.free_multiplier_symbols)
    if kernel_dims and kernel_dims != {free}:
        problems.append(f"{sorted(kernel_dims)} free multipliers at the points of M_f, "
                        f"{free} from the algorithm")
    if not field_pairs and not inconsistent:
        problems.append("no generic exact point of M_f")
    k = len(data_pairs) // 2
    how = "exact solves modulo p at exact points"
    checks.append(CheckResult(
        "stages", not problems, False, samples=k,
        detail="; ".join(problems) if problems else (
            f"{analysis.status} with {len(analysis.stages)} stage(s), ranks "
            f"{[st.rank for st in analysis.stages]}: Z_i^H(chi^H) and X_H(chi^H) on T*Q equal "
            f"Z_i(chi) and xi_L(chi) at {k} exact points of the M_k (so the T*Q algorithm "
            f"has the same stages, ranks and conditions there)" + (
                ", so the same inconsistency" if inconsistent else
                ", and every stage's T*Q tangency equations are consistent at Leg of the "
                "points of M_f"))))
    _, _, ok = final.compare(inv_pairs)
    checks.append(CheckResult("legendre inverse", ok, False, 0.0, 0.0, len(inv_pairs),
                              f"v -> p = dL/dv -> Leg^-1(q, p) ({how}) against v"))
    if inconsistent:
        none = ("no dynamics: the problem is inconsistent on both sides (equal stage data "
                "at the points of every M_k)" if not problems else
                "the TQ run is inconsistent and the T*Q data differ")
        checks += [CheckResult("field", not problems, False, detail=none),
                   CheckResult("multipliers", not problems, False, detail=none)]
    else:
        _, _, ok = final.compare(field_pairs)
        checks.append(CheckResult(
            "field", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
            len(field_pairs),
            f"Leg_*(xi_L + lambda^i Z_i) against X_H + lambda^i Z_i^H on M_f, lambda "
            f"solving the TQ tangency equations ({free} free multiplier(s) given the same "
            f"seeded values), by {how}"))
        _, _, ok = final.compare(lam_pairs)
        checks.append(CheckResult(
            "multipliers", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
            len(lam_pairs),
            "lambda^H (solving the T*Q tangency equations on M_f) solves the TQ ones: "
            "lambda^L - lambda^H o Leg lies in the kernel (the free multipliers)"))
    checks.append(_check_form_sampled(side, final, lag))
    _, _, ok = final.compare(br_pairs)
    checks.append(CheckResult(
        "Poisson map", ok, False, 0.0 if ok else math.nan, 0.0 if ok else math.nan,
        len(br_pairs),
        f"{{f, g}} o Leg against {{Leg^* f, Leg^* g}}_L for the {len(chis)} "
        f"{'primary' if inconsistent else 'final'} constraints, by {how}"))
    checks = [dataclasses.replace(c, method="points") for c in checks]
    stages_L = _stage_summaries(analysis.stages)
    h_status = analysis.status if not problems else (
        "inconsistent" if inconsistent else "determined" if top == m else "underdetermined")
    return (checks, stages_L, tuple(stages_H), (analysis.status, h_status),
            (len(final.all_points), dropped))


def _labels(system):
    nh = len(system.holonomic)
    return tuple(f"holonomic[{i}]" for i in range(nh)) + tuple(
        f"{lab}.lift" if k < nh else lab for k, lab in enumerate(system.constraint_labels))


def _lag_C(lag: _NumericLagrangian, be, vals):
    """C = -mu W^{-1} mu^T numerically at a point of TQ."""
    if not lag.m:
        return be.zeros(0, 0)
    W, mu = lag._W(be, vals), lag._mu(be, vals)
    return -(mu @ be.solve(W, mu.T))


def _numeric_rank(C, tol) -> int:
    if C.size == 0:
        return 0
    s = np.linalg.svd(np.asarray(C, dtype=float), compute_uv=False)
    return int(sum(x > tol * max(s[0], 1.0) for x in s))


def _check_form_sampled(side, sampler, lag) -> CheckResult:
    """Leg^* omega_Q = J^T Omega_Q J against omega_L at the points (J numeric)."""
    be = sampler.backend
    n = side.n
    one, zero = be.scalar(1), be.scalar(0)
    I = be.zeros(n, n)
    for i in range(n):
        I[i, i] = one
    Z = be.zeros(n, n)
    O = np.block([[Z, I], [-I, Z]])
    pairs = []
    geo = lagrangian_geometry(side.system)
    fo = Lambdified(sampler.args, list(geo.poincare_cartan_2form), (2 * n, 2 * n))
    with be.context():
        for pt in sampler.points:
            vals = sampler.values(pt)
            W, M = lag._W(be, vals), lag._M(be, vals)
            J = np.block([[I, Z], [M, W]])
            pairs.append((J.T @ O @ J, fo(be, vals)))
    del zero
    ab, rel, ok = sampler.compare(pairs)
    return CheckResult("symplectic form", ok, False, ab, rel, len(pairs),
                       "J^T Omega_Q J (J = d Leg) against omega_L at the points")
