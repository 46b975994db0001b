"""Points where both sides are compared, and the Lagrangian side evaluated there.

Seeded points of M_f in floating point or mpmath (:class:`ComparisonPoints`), or over
F_p (:class:`ModularComparisonPoints`); the Lagrangian side's projected field,
multipliers, Leg_* and bracket at a point by numeric solves with W
(:class:`NumericLagrangian`), never a symbolic inverse.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from nhham.errors import InputError
from nhham.hamiltonian.checks import CheckResult
from nhham.lagrangian.domains import ModP, NotExact
from nhham.lagrangian.formulas import constrained_motion, lagrangian_bracket
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.linalg import FloatMatrix, ModularBackend, backend_solve, exact_rank
from nhham.lagrangian.points import PointSampler, exact_sampler
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.evaluation import Backend, Lambdified
from nhham.system.expressions import derivative

__all__ = [
    "ComparisonPoints",
    "ModularComparisonPoints",
    "NumericLagrangian",
    "modular_sampler",
    "check_form_sampled",
    "lag_C",
]


# --------------------------------------------------------------- numerics
class ComparisonPoints:
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
        lag = NumericLagrangian(self.system, self.args)
        be = self.backend
        with be.context():
            ranks = []
            for pt in pts:
                try:
                    ranks.append(self.rank(lag_C(lag, be, self.values(pt))))
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
        domain of the dynamics) are skipped and counted in ``self.skipped``.

        Raises
        ------
        InputError
            Every pair is skipped: the two sides are defined at no point of M_f (W
            infinite on all of M_1, pi/q where q = 0 is imposed), which is no
            disagreement between them.
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
            raise InputError(f"the two sides are not finite at any of {self.skipped} points "
                             f"of M_f (the Lagrangian's W or a constraint is singular on "
                             f"the constraint set); nhham needs them defined on M_1")
        return worst_abs, worst_rel, ok

    def note(self) -> str:
        """Text about skipped points of the last comparison."""
        k = getattr(self, "skipped", 0)
        return f" ({k} sample point(s) skipped: not finite there)" if k else ""


class ModularComparisonPoints(ComparisonPoints):
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
    def on(cls, system, constraints, samples, seed) -> "ModularComparisonPoints":
        """Seeded points of M = {constraints = 0} over F_p
        (:func:`~nhham.lagrangian.points.exact_sampler`; NotExact where M has none)."""
        manifold = Submanifold(system, tuple(constraints), seed=seed)
        return cls(system, samples, seed, exact_sampler(manifold, seed, modular=True))

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


class NumericLagrangian:
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
        # Leg's own rate d2L/dt dv where L depends on t (zero otherwise)
        rate = list(geo.momenta.diff(system.time)) if system.lagrangian_depends_on_time \
            else []
        self._rate = Lambdified(args, rate, (n,)) if rate else None
        self.args = args
        self.system = system
        self._grads: dict = {}

    def projected(self, be: Backend, vals):
        """(d/dt Leg along P(xi_L) as a 2n-vector at Leg(x), lambda, C) at x: Leg_* P(xi_L),
        plus d2L/dt dv where L depends on t."""
        W, F, M = self._W(be, vals), self._F(be, vals), self._M(be, vals)
        if self.m:
            mu, drift = FloatMatrix(self._mu(be, vals)), FloatMatrix(self._drift(be, vals))
            acc, lam, C = (x.a for x in constrained_motion(
                FloatMatrix(W), mu, FloatMatrix(F), drift, solve=backend_solve(be)))
        else:
            lam, C, acc = be.zeros(0), be.zeros(0, 0), be.solve(W, F)
        return self._pushed(be, vals, acc, W, M), lam, C

    def field(self, be: Backend, vals, lam):
        """Leg_*(xi_L + lambda^i Z_i) at x for given multipliers lambda, a 2n-vector
        (with Leg's own rate where L depends on t)."""
        W, F, M, mu = self._W(be, vals), self._F(be, vals), self._M(be, vals), \
            self._mu(be, vals)
        return self._pushed(be, vals, be.solve(W, F) - be.solve(W, mu.T) @ lam, W, M)

    def _pushed(self, be, vals, acc, W, M):
        """d/dt Leg along (v, acc): (v, M v + W acc + d2L/dt dv)."""
        n = self.n
        v = np.array(vals[n:2 * n], dtype=object if be.precision else float)
        dp = M @ v + W @ acc
        return np.concatenate([v, dp if self._rate is None else dp + self._rate(be, vals)])

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
                               FloatMatrix(self._M(be, vals)), solve=backend_solve(be))
        return B.a


# ---------------------------------------------------------------- sampled
def modular_sampler(system, side, samples, seed, required=False):
    """An :class:`ModularComparisonPoints` when both sides can be evaluated exactly at exact points
    of M_1 (L quadratic in v, so Leg^-1 is one linear solve; M_1 with exact points),
    else None (or an error naming why, when ``required``)."""
    why = None
    if not side.legendre.is_quadratic:
        why = "L is not quadratic in the velocities (Leg^-1 is solved numerically)"
    else:
        try:
            sampler = ModularComparisonPoints(system, samples, seed)
            sampler.points  # noqa: B018 - draws the points, or raises NotExact
            return sampler
        except (NotExact, ZeroDivisionError) as exc:
            why = f"no exact points of M_1 ({exc})"
    if required:
        raise InputError(f"cross_check: method 'points' is not available: {why}")
    return None


def lag_C(lag: NumericLagrangian, be, vals):
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


def check_form_sampled(side, sampler, lag) -> CheckResult:
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
