"""Where the first/second-class split of a time-dependent system changes with t.

``classify`` answers at a generic instant (t a parameter without a value, DESIGN.md §2):
the rank of B = {chi_a, chi_b} on M_f is its largest, and a maximal second-class set R has
B_RR invertible there. At a particular instant t* the split is another exactly when
det B_RR vanishes on all of M_f(t*): then fewer constraints are second class (or another
set R). Written on M_f as a polynomial in the phase variables (and in the functions of
them that occur, such as sin q), det B_RR vanishes identically at t* exactly when every
coefficient does, i.e. where their greatest common divisor g(t) does: the split changes
at the roots of g. The parameters are at the scene's values (the verdict is for them).

Decided on a symbolic B reduced on M_f: the classification's own where it was exact, else
formed again symbolically up to n = :data:`EXACT_MAX_N`; past that, and where det B_RR is
not polynomial in the phase variables, the instants are not determined and the result
says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.hamiltonian.classification import classify_constraints
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.engine import Policy

__all__ = ["SplitInstants", "split_instants", "EXACT_MAX_N"]

#: Largest n for which a split decided at points is formed again with a symbolic B.
EXACT_MAX_N = 6


@dataclass(frozen=True)
class SplitInstants:
    """The instants where the class split differs from the generic instant's.

    Attributes
    ----------
    condition : sympy.Expr or None
        g(t): the split changes exactly where g(t) = 0 (1 for never); None when not
        determined.
    instants : tuple of sympy.Expr or None
        The real roots of g when they are finitely many and found (empty: the split is
        the same at every instant); None otherwise.
    detail : str
        How it was decided, in words.
    """

    condition: sp.Expr | None
    instants: tuple | None
    detail: str

    @property
    def changes(self) -> bool | None:
        """True where some instant changes the split, None when not determined."""
        if self.condition is None:
            return None
        return True if self.instants is None else bool(self.instants)

    def text(self) -> str:
        """One line for ``classify``'s table."""
        if self.changes is None:
            return self.detail
        if not self.changes:
            return "the same at every instant"
        where = (f"t = {', '.join(map(str, self.instants))}" if self.instants
                 else f"{self.condition} = 0")
        return f"changes where {where} (fewer second-class constraints there)"

    def to_dict(self) -> dict:
        return {"condition": None if self.condition is None else str(self.condition),
                "instants": None if self.instants is None else [str(t) for t in self.instants],
                "changes": self.changes, "detail": self.detail, "text": self.text()}


def split_instants(classes) -> SplitInstants | None:
    """Where the split of ``classes`` (a ConstraintClasses) changes with the time t.

    Returns None for an autonomous system.

    Examples
    --------
    A particle with x' = 0 and y' = t x z': {p_x, p_y - t x p_z} = t p_z, so both
    constraints are second class at every instant but t = 0, where both are first class.

    >>> from nhham import System, classify_constraints
    >>> s = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...            constraints=["x_dot", "y_dot - t*x*z_dot"])
    >>> found = split_instants(classify_constraints(s))
    >>> found.condition, found.instants
    (t, (0,))
    """
    system = classes.side.system
    time = system.time
    if time is None:
        return None
    if classes.method != "exact" or classes.bracket_matrix is None or classes.manifold is None:
        if system.n > EXACT_MAX_N:
            return SplitInstants(None, None, f"not determined: the split was decided "
                                             f"{classes.method}, and n = {system.n} > "
                                             f"{EXACT_MAX_N} for a symbolic B on M_f")
        # B on M_f symbolically (the ball on a spun-up turntable, n = 5: 2.4 s)
        classes = classify_constraints(classes.side, classes.constraints_TQ, classes.labels,
                                       method="exact", policy=Policy(combination_size=0))
    R = list(classes.second_class_indices)
    if not R:
        return SplitInstants(sp.S.One, (), "no second-class constraint at a generic instant: "
                             "B vanishes on M_f at every t")
    det = classes.manifold.reduce(cancel(classes.bracket_matrix.extract(R, R).det()))
    values = {p: v for p, v in system.exact_parameter_values.items() if p != time}
    numerator = sp.numer(sp.together(sp.sympify(det).xreplace(values)))
    phase = set(classes.side.variables)
    gens = sorted(phase, key=str) + sorted(
        (f for f in numerator.atoms(sp.Function, sp.Pow)
         if f.free_symbols & phase and not (isinstance(f, sp.Pow) and f.exp.is_Integer)),
        key=str)
    try:
        coefficients = sp.Poly(sp.expand(numerator), *gens).coeffs()
    except sp.PolynomialError:
        return SplitInstants(None, None, "not determined: det B_RR on M_f is not a "
                                         "polynomial in the phase variables")
    g = sp.factor(sp.trigsimp(sp.gcd_list(coefficients)))  # sin^2 + cos^2 is 1
    # its square-free part in t: the instants, each once
    g = sp.Mul(*[f for f, _ in sp.factor_list(g)[1] if time in f.free_symbols])
    if time not in g.free_symbols:
        return SplitInstants(sp.S.One, (), "det B_RR on M_f has a coefficient free of t "
                             "that is not zero: the split is the same at every instant")
    roots = sp.solveset(g, time, sp.S.Reals)
    instants = () if roots is sp.S.EmptySet else tuple(
        sorted(roots, key=lambda r: float(r))) if isinstance(roots, sp.FiniteSet) else None
    return SplitInstants(g, instants, "the gcd g(t) of the coefficients of det B_RR on M_f "
                         "(a polynomial in the phase variables): the split changes where "
                         "g(t) = 0" + (", which has no real root" if instants == () else ""))
