"""The two questions every submanifold answers, for :func:`~nhham.lagrangian.engine.decide`.

:class:`Vanishing` ("does f vanish identically on M?") and :class:`Rank` ("the generic
rank of a matrix of functions on M"): exact reduction first (substitution,
cancellation, a Groebner remainder, a nonzero maximal minor), sampled points last
(:meth:`Submanifold.vanishes <nhham.lagrangian.submanifold.Submanifold.vanishes>` and
:meth:`Submanifold.rank <nhham.lagrangian.submanifold.Submanifold.rank>` ask them).
The manifold supplies the reduction and the sampled tests.
"""

from __future__ import annotations

import sympy as sp

from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.decision import Decision
from nhham.system.expressions import short

__all__ = ["Vanishing", "Rank"]


class Vanishing:
    """"Does ``expr`` vanish identically on M?" for :func:`~nhham.lagrangian.engine.decide`:
    exact reduction (substitution, cancellation, a Groebner remainder), else sampled."""

    what = "vanishing on M"

    def __init__(self, expr, tol: float | None = None):
        self.expr, self.tol = expr, tol
        self.residue = None

    def reduced(self, manifold, policy) -> Decision | None:
        if not manifold.exact:
            return None
        reduced = self.residue = manifold.reduce(self.expr)
        if reduced == 0:
            return Decision(True, "exact", "vanishes after exact reduction")
        verdict, warning = manifold._zero_test(reduced)
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
        return manifold._sampled_vanishes(expr, self.tol)


class Rank:
    """"The generic rank of ``matrix`` on M" for :func:`~nhham.lagrangian.engine.decide`:
    exact when the entries reduce to numbers or all vanish, or a maximal minor (up to
    ``policy.exact_minor_size``) is a nonzero function on M; else sampled, proved by a
    certificate where one is found."""

    what = "rank on M"

    def __init__(self, matrix, tol: float | None = None):
        self.matrix, self.tol = sp.Matrix(matrix), tol
        self.residue = None

    def reduced(self, manifold, policy) -> Decision | None:
        if 0 in self.matrix.shape:
            return Decision(0, "exact", "empty matrix")
        if not manifold.exact:
            return None
        reduced = self.residue = self.matrix.applyfunc(manifold.reduce)
        if not reduced.free_symbols:
            r = reduced.rank()
            return Decision(r, "exact", f"entries reduce to numbers; rank {r}")
        if all(manifold._zero_test(e)[0] is True for e in reduced):
            return Decision(0, "exact", "every entry vanishes on M")
        return manifold._exact_full_rank(reduced, policy.exact_minor_size)

    def sampled(self, manifold, policy) -> Decision:
        if self.residue is None:
            # No cancellation: a quotient is 0/0 only on a thin set the seeded
            # points miss, and bringing large entries over one denominator costs.
            return manifold.sampled_ranks([self.matrix], self.tol)[0]
        reduced = self.residue
        sampled = manifold.sampled_ranks([reduced], self.tol)[0]
        if 0 < sampled.value < min(reduced.shape):
            certificate = manifold._rank_certificate(reduced, sampled, policy.exact_minor_size)
            if certificate is not None:
                return certificate
        return sampled
