"""The two questions every submanifold answers, for :func:`~nhham.lagrangian.engine.decide`.

:class:`Vanishing` ("does f vanish identically on M?") and :class:`Rank` ("the generic
rank of a matrix of functions on M"), by every step of the cascade: exact reduction
(substitution, cancellation, a Groebner remainder, a nonzero maximal minor), a proof at
a random point over F_p (a nonzero value, a full rank), the values at random exact
points with their error bound (rational points; smooth points over F_p on a curved M),
sampled points last (:meth:`Submanifold.vanishes
<nhham.lagrangian.submanifold.Submanifold.vanishes>` and :meth:`Submanifold.rank
<nhham.lagrangian.submanifold.Submanifold.rank>` ask them). The manifold supplies the
reduction and the sampled tests.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from typing import cast

import sympy as sp

from nhham.errors import ComputationError
from nhham.lagrangian.algebra import cancel, determinant
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import (PRIME, Angle, Degree, ModP, NotExact, evaluate,
                                     minor_degree)
from nhham.lagrangian.linalg import exact_rank
from nhham.settings import SEED
from nhham.system.expressions import short

__all__ = ["Vanishing", "Rank", "exact_full_rank", "rank_certificate"]


class Vanishing:
    """"Does ``expr`` vanish identically on M?" for :func:`~nhham.lagrangian.engine.decide`:
    exact reduction (substitution, cancellation, a Groebner remainder), else sampled."""

    what = "vanishing on M"
    residues = True

    def __init__(self, expr, tol: float | None = None):
        self.expr, self.tol = expr, tol
        self.residue = None
        self.nonzero = False

    def value(self, env, degrees: bool = False):
        return evaluate([self.expr if self.residue is None else self.residue], env)[0]

    def proved_modulo_p(self, value) -> Decision | None:
        if not value:
            return None
        return Decision(False, "exact", "nonzero at a random point of M modulo the prime "
                        "2^61 - 1 (proof)", samples=1, error_bound=0.0)

    def observe(self, value) -> bool:
        self.nonzero = self.nonzero or bool(value)
        return self.nonzero

    def pending_error(self, degree, count, bound):
        return None if self.nonzero else bound(Degree.of(degree).num, count)

    def conclude(self, count, degree, bound) -> Decision:
        if self.nonzero:
            return Decision(False, "exact", "nonzero at an exact point of M (proof)",
                            samples=count, error_bound=0.0)
        d = Degree.of(degree).num
        return Decision(True, "exact at points", f"vanishes at {count} random exact "
                        f"point{'s' if count > 1 else ''} of M ({bound.describe(d)})",
                        samples=count, error_bound=bound(d, count))

    def reduced(self, manifold, policy) -> Decision | None:
        if not manifold.exact or not _reducible(manifold, policy):
            return None
        reduced = self.residue = manifold.reduce(self.expr)
        if reduced == 0:
            return Decision(True, "exact", "vanishes after exact reduction")
        verdict, warning = manifold.exact_zero_test(reduced)
        if verdict is True:
            return Decision(True, "exact",
                            "Groebner remainder 0 modulo sin^2+cos^2=1 and the equations the "
                            "reduction could not eliminate")
        if verdict is False:
            return Decision(False, "exact",
                            f"reduces to the nonzero function {short(reduced)} on M",
                            warnings=(warning,) if warning else ())
        return None

    def sampled(self, manifold, policy) -> Decision:
        expr = cancel(self.expr) if self.residue is None else self.residue
        return manifold.sampled_vanishes(expr, self.tol)


class Rank:
    """"The generic rank of ``matrix`` on M" for :func:`~nhham.lagrangian.engine.decide`:
    exact when the entries reduce to numbers or all vanish, or a maximal minor (up to
    ``policy.exact_minor_size``) is a nonzero function on M; else sampled, proved by a
    certificate where one is found."""

    what = "rank on M"
    residues = True

    def __init__(self, matrix, tol: float | None = None):
        self.matrix, self.tol = sp.Matrix(matrix), tol
        self.residue = None
        self.best = 0
        self.certify: Callable[[Decision], Decision | None] | None = None

    @property
    def full(self) -> int:
        return min(self.matrix.shape)

    def value(self, env, degrees: bool = False):
        matrix = self.matrix if self.residue is None else self.residue
        cache: dict = {}
        return [evaluate(matrix.row(i), env, cache) for i in range(matrix.rows)]

    def proved_modulo_p(self, values) -> Decision | None:
        r = exact_rank(values)[0]
        if r < self.full:
            return None
        return Decision(r, "exact", f"rank {r}, full, at a random point of M modulo the "
                        f"prime 2^61 - 1 (proof)", samples=1, error_bound=0.0)

    def observe(self, values) -> bool:
        self.best = max(self.best, exact_rank(values)[0])
        return self.best >= self.full

    def pending_error(self, degrees, count, bound):
        if self.best >= self.full:
            return None
        return bound(minor_degree(degrees, self.best + 1), count)

    def conclude(self, count, degrees, bound) -> Decision:
        r = self.best
        if r >= self.full:
            return Decision(r, "exact", f"rank {r}, full, at an exact point of M (proof)",
                            samples=count, error_bound=0.0)
        d = minor_degree(degrees, r + 1)
        at_points = Decision(r, "exact at points", f"rank {r} at {count} random exact "
                             f"point{'s' if count > 1 else ''} of M: every {r + 1} x {r + 1} "
                             f"minor vanishes there ({bound.describe(d)})", samples=count,
                             error_bound=bound(d, count))
        # A deficient rank is proved by a certificate where one is found.
        certificate = None if self.certify is None or not r else self.certify(at_points)
        return certificate or at_points

    def reduced(self, manifold, policy) -> Decision | None:
        if 0 in self.matrix.shape:
            return Decision(0, "exact", "empty matrix")
        if not manifold.exact or not _reducible(manifold, policy):
            return None
        reduced = self.residue = self.matrix.applyfunc(manifold.reduce)
        self.certify = lambda d: rank_certificate(manifold, reduced, d,
                                                            policy.exact_minor_size)
        if not reduced.free_symbols:
            r = reduced.rank()
            return Decision(r, "exact", f"entries reduce to numbers; rank {r}")
        if all(manifold.exact_zero_test(e)[0] is True for e in reduced):
            return Decision(0, "exact", "every entry vanishes on M")
        return exact_full_rank(manifold, reduced, policy.exact_minor_size)

    def sampled(self, manifold, policy) -> Decision:
        if self.residue is None:
            # No cancellation: a quotient is 0/0 only on a thin set the seeded
            # points miss, and bringing large entries over one denominator costs.
            return manifold.sampled_ranks([self.matrix], self.tol)[0]
        reduced = self.residue
        sampled = manifold.sampled_ranks([reduced], self.tol)[0]
        if 0 < sampled.value < min(reduced.shape):
            certificate = rank_certificate(manifold, reduced, sampled, policy.exact_minor_size)
            if certificate is not None:
                return certificate
        return sampled


def _reducible(manifold, policy) -> bool:
    """Whether the exact reduction is tried: not on a curved M with more than
    ``policy.closed_form_size`` coordinates, where solving the velocities symbolically
    costs minutes (the bicycle's M_1) and the points over F_p answer in milliseconds."""
    return len(manifold.system.coordinates) <= policy.closed_form_size or not manifold.curved


def exact_full_rank(manifold, reduced, size: int) -> Decision | None:
    """Full rank proved exactly: a maximal minor of ``reduced`` (a matrix reduced on
    ``manifold``, at most ``size`` rows or columns) is a nonzero function on M.

    Only for small matrices and when the reduction parametrises M
    completely (no residual equations), so that a nonzero reduced
    expression is a nonzero function on M.
    """
    k = min(reduced.shape)
    if k > size or manifold.reduction.residual:
        return None
    if _deficient_at_random_points(reduced, k):
        return None   # what the cancellation below would find (seconds with radicals)
    square = reduced if reduced.rows == reduced.cols else (
        reduced * reduced.T if reduced.rows < reduced.cols else reduced.T * reduced)
    det = cancel(determinant(square))
    verdict, warning = ((False, None) if det.is_number and det != 0
                        else manifold.exact_zero_test(det))
    if verdict is not False:
        return None
    return Decision(k, "exact", f"full rank {k}: the determinant reduces to the nonzero "
                                f"function {short(det)} on M",
                    warnings=(warning,) if warning else ())


def _deficient_at_random_points(matrix, k: int, tries: int = 2) -> bool:
    """Whether ``matrix`` has rank below ``k`` at ``tries`` random points over F_p, every
    symbol an angle with a value and a circle point of its own (seeded: the same points
    every run).

    Then its maximal minors vanish identically (a nonzero one vanishes at both points
    with probability at most about (degree / p)^tries, p = 2^61 - 1), and
    :func:`exact_full_rank` has nothing to prove:
    cancelling the determinant of the relativistic particle's radicals took 2.6 s to
    find 0. False where the entries have no value over F_p (then the cancellation
    decides, as before).
    """
    rng = random.Random(f"{SEED}:deficient")
    symbols = sorted(matrix.free_symbols, key=str)
    seen = 0
    for _ in range(4 * tries):   # a point where a radicand is not a square: another
        env = {}
        for x in symbols:
            t = ModP(rng.randrange(PRIME))
            env[x] = Angle.on_circle(ModP(rng.randrange(PRIME)), t)
        cache: dict = {}
        try:
            if None in env.values():   # 1 + t^2 = 0 modulo p
                raise ZeroDivisionError
            rows = [evaluate(matrix.row(i), env, cache) for i in range(matrix.rows)]
        except ZeroDivisionError:
            continue
        except NotExact:
            return False
        if exact_rank(rows)[0] >= k:
            return False
        seen += 1
        if seen == tries:
            return True
    return False


def rank_certificate(manifold, reduced, sampled: Decision, size: int) -> Decision | None:
    """Prove the sampled rank r of ``reduced`` exactly: a nonzero r x r minor on
    ``manifold`` (r at most ``size``) whose Schur complement vanishes on M; None when no
    such certificate is found."""
    r = cast(int, sampled.value)  # a sampled rank
    if r > size or manifold.reduction.residual:
        return None
    # radicals (sqrt(1 - v^2)) make the Schur complement's cancellation unbounded: the
    # sampled rank stands, said as sampled
    if any(_radical(e) for e in reduced):
        return None
    try:
        rows, cols, _ = manifold.regular_block(reduced, r)
    except ComputationError:
        return None
    B = reduced.extract(rows, cols)
    det = cancel(determinant(B))
    verdict, warning = ((False, None) if det.is_number and det != 0
                        else manifold.exact_zero_test(det))
    if verdict is not False:
        return None
    other_rows = [i for i in range(reduced.rows) if i not in rows]
    other_cols = [j for j in range(reduced.cols) if j not in cols]
    X = B.LUsolve(reduced.extract(rows, other_cols))
    schur = reduced.extract(other_rows, other_cols) - reduced.extract(other_rows, cols) * X
    if not all(manifold.exact_zero_test(cancel(e))[0] is True for e in schur):
        return None
    return Decision(
        r, "exact",
        f"rank {r}: the minor (rows {rows}, columns {cols}) is the nonzero function "
        f"{short(det)} on M and its Schur complement vanishes on M",
        singular_values=sampled.singular_values, warnings=(warning,) if warning else (),
    )


def _radical(expr) -> bool:
    """Whether ``expr`` has a non-integer power (a root) of a non-constant expression."""
    return any(e.is_Pow and not e.exp.is_Integer and not e.base.is_number
               for e in sp.preorder_traversal(expr))
