"""The Dirac flow against the projected field at exact points of M_f (no symbolic inverse).

X_D − X is one formula (:func:`nhham.lagrangian.formulas.dirac_difference`) on the
Lagrangian data at a point of TQ (W, the mixed Hessian, μ, the forcing, the gradients of
the second-class constraints), so it is decided by the decision engine
(:func:`~nhham.lagrangian.engine.decide`) like every other question on M_f: a component
nonzero at a random point over F_p is a proof that the flows differ (on a curved M_f, on
the component through the point, at the parameter values); zero at every exact point is
"equal" with the engine's error bound (Schwartz–Zippel at rational points, Bézout at
smooth points over F_p of a curved M_f). Where M_f has no exact points the caller
compares at floating-point points instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import Degree, evaluate
from nhham.lagrangian.formulas import dirac_difference
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.linalg import ListMatrix, degree_solve, field_solve
from nhham.lagrangian.points import jacobian_row

__all__ = ["DiracVerdict", "DiracDifference"]


@dataclass(frozen=True)
class DiracVerdict:
    """X_D = X on M_f?, decided at points.

    Attributes
    ----------
    decision : Decision
        ``value`` True when X_D − X vanished at every point (with its error bound);
        False with a proof at a point.
    components : tuple of str
        The (q, p) variables whose component of X_D − X was nonzero at a point (each a
        proof that it is not zero on M_f); empty when equal.
    """

    decision: Decision
    components: tuple = ()


class DiracDifference:
    """"Does X_D − X vanish on M_f?" for :func:`~nhham.lagrangian.engine.decide`: the
    2n components at a point, in any exact arithmetic (residues on a curved M_f).

    Parameters
    ----------
    side : HamiltonianSide
    constraints : sequence of sympy.Expr
        The final constraints on TQ.
    second_class : sequence of int
        The indices of the maximal second-class set R.
    """

    what = "X_D - X on M_f"
    residues = True

    def __init__(self, side, constraints, second_class):
        self.side = side
        self.chis = [constraints[a] for a in second_class]
        self.names = tuple(str(z) for z in side.variables)
        self.nonzero: set = set()

    @cached_property
    def data(self) -> tuple:
        """The rows of W, M, μ, F, drift, v, ∂χ_R/∂q, ∂χ_R/∂v and ∂χ_R/∂t (sympy)."""
        system = self.side.system
        geo = lagrangian_geometry(system)
        n = system.n
        q, v = system.coordinates, system.velocities
        return ([list(geo.hessian.row(i)) for i in range(n)],
                [list(geo.mixed_hessian.row(i)) for i in range(n)],
                [list(system.mu.row(i)) for i in range(system.m)],
                [[e] for e in geo.forcing], [[e] for e in geo.drift], [[s] for s in v],
                [jacobian_row(c, q) for c in self.chis],
                [jacobian_row(c, v) for c in self.chis],
                [[sp.S.Zero if system.time is None else sp.diff(c, system.time)]
                 for c in self.chis])

    def value(self, env, degrees: bool = False) -> list:
        """The 2n components of X_D − X at the point (Degree bounds with ``degrees``)."""
        cache: dict = {}
        n = self.side.system.n
        W, M, mu, F, drift, v, Jq, Jv, Jt = (
            ListMatrix([evaluate(r, env, cache) for r in rows], n) for rows in self.data)
        D = dirac_difference(W, M, mu, F, drift, v, Jq, Jv,
                             solve=degree_solve if degrees else field_solve, Jt=Jt)
        return [row[0] for row in D.to_list()]

    def _differing(self, values) -> tuple:
        return tuple(name for name, x in zip(self.names, values) if x)

    def _differs(self, names, samples) -> DiracVerdict:
        where = "a random point of M_f modulo the prime 2^61 - 1" if samples == 1 else \
            f"one of {samples} exact points of M_f"
        return DiracVerdict(Decision(
            False, "exact", f"X_D - X is nonzero at {where} in the components "
            + ", ".join(f"d/d{z}" for z in names) + " (a proof that the Dirac flow is not "
            "the true dynamics)", samples=samples, error_bound=0.0), names)

    def proved_modulo_p(self, values) -> DiracVerdict | None:
        names = self._differing(values)
        return self._differs(names, 1) if names else None

    def observe(self, values) -> bool:
        self.nonzero |= set(self._differing(values))
        return bool(self.nonzero)

    def pending_error(self, degrees, count, bound):
        if self.nonzero:
            return None
        return bound(_top(degrees), count, terms=len(self.names))

    def conclude(self, count, degrees, bound) -> DiracVerdict:
        if self.nonzero:
            return self._differs(tuple(z for z in self.names if z in self.nonzero), count)
        d = _top(degrees)
        return DiracVerdict(Decision(
            True, "exact at points", f"X_D - X is 0 in all {len(self.names)} components at "
            f"{count} random exact point{'s' if count > 1 else ''} of M_f "
            f"({bound.describe(d)})", samples=count,
            error_bound=bound(d, count, terms=len(self.names))))


def _top(degrees) -> int:
    """The largest numerator degree of the components."""
    return max((Degree.of(d).num for d in degrees), default=0)
