"""Exact points of M_1: what decisions "exact at points" rest on.

A function on TQ built from polynomials, quotients, sines and cosines of the
coordinates is evaluated *exactly* at random rational points: every coordinate q
carries a rational value r (where it appears polynomially) and a rational point of
the unit circle (c, s) = ((1 − t²)/(1 + t²), 2t/(1 + t²)) (where it appears inside
sin/cos), with r and t drawn independently. This is legitimate for questions about
functions — vanishing identically, generic rank — because q is algebraically
independent of (cos q, sin q): a polynomial in (q, cos q, sin q) vanishes as a
function exactly when it vanishes at every (r, c, s) with c² + s² = 1. Integer
combinations of coordinates inside sin/cos (θ1 − θ2, 2φ) are exact through
(c + i s) products. Parameters with values take their exact decimal value
(``Rational(str(value))``), except the one parameter with a value inside sin/cos, whose
circle point is drawn (:func:`circle_parameters`); parameters without values are drawn
like coordinates. Dependent velocities are solved exactly from the affine constraints;
holonomic constraints are eliminated when a coordinate enters one linearly with a
constant coefficient; the others make M curved, with points over F_p only, found by
:mod:`nhham.lagrangian.curved` (``modular=True``). Anything else raises
:class:`~nhham.lagrangian.domains.NotExact`, and the caller decides at sampled points
instead, saying so. The arithmetic of the values and of their degree bounds is
:mod:`nhham.lagrangian.domains`.

Two samplers, one per kind of point: :class:`PointSampler` (rational points, or points
over F_p with ``modular=True``) and :class:`ParameterFieldSampler` (points whose values
lie in the field Q(params) of the parameters kept symbolic, for the exceptional sets).
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import sympy as sp
from sympy.external.gmpy import MPQ
from sympy.polys.matrices import DomainMatrix

from nhham.errors import BudgetExceeded
from nhham.lagrangian.algebra import solve_for_coordinates
from nhham.lagrangian.curved import curved_chart
from nhham.lagrangian.domains import (
    PRIME,
    RADICANDS,
    SAMPLE_BITS,
    Angle,
    Degree,
    ErrorBound,
    ModP,
    NotExact,
    evaluate,
    minor_degree,
)
from nhham.lagrangian.linalg import exact_rank, exact_solve, field_solve
from nhham.system.expressions import derivative, short
from nhham.system.derivative import symbols_in
from nhham.system.velocities import velocity_free_part

__all__ = [
    "ExactPoint",
    "PointSampler",
    "ParameterFieldSampler",
    "exact_sampler",
    "circle_parameters",
    "jacobian_row",
    "eliminate_coordinates",
    "DRAW_BITS",
]


# Draws of a sampler per point it returns, and redraws of a point whose datum has a
# zero denominator (the engine's): on a curved M their product is the ``tries`` of the
# error bound.
TRIES = 50
REDRAWS = 3


# ------------------------------------------------------------------ points
@dataclass(frozen=True)
class ExactPoint:
    """One exact point of M_1 with the matching degree bounds.

    Attributes
    ----------
    env : dict
        Symbol -> exact value (``Angle`` for coordinates and free parameters,
        ``MPQ`` for velocities and parameters with values).
    degrees : dict
        Symbol -> :class:`Degree` (or ``Angle`` of degrees) for the same symbols.
    """

    env: dict
    degrees: dict


class PointSampler:
    """Random exact points of M_1 = {g(q) = 0, φ(q, v) = 0}.

    Parameters
    ----------
    coordinates, velocities : sequence of sympy.Symbol
    parameters : sequence of sympy.Symbol
        All parameters; those in ``values`` are fixed, the others drawn.
    values : dict
        Parameter -> value (numbers; taken as exact decimals).
    holonomic : sequence of sympy.Expr
        g(q) = 0; each must be linear, with a constant coefficient, in a
        coordinate not yet eliminated (else :class:`NotExact`).
    affine : sequence of sympy.Expr
        Constraints affine in the velocities (φ = μ(q) v + h(q), lifts included).
    seed : int
    mu : list of list of sympy.Expr, optional
        The velocity coefficients of ``affine`` when the caller has them.
    modular : bool, optional
        Points over F_p (:class:`ModP` values, for proofs of full rank and of
        non-vanishing) instead of rational points. Only these exist where a holonomic
        constraint is curved (:mod:`nhham.lagrangian.curved`).
    circle : sequence of sympy.Symbol, optional
        Parameters with values whose (cos, sin) is drawn on the unit circle (see
        :func:`circle_parameters`).
    context : sequence of sympy.Expr, optional
        The other expressions evaluated at the points (the Lagrangian), for the choice
        of the coordinates solved on a curved M.
    """

    def __init__(self, coordinates, velocities, parameters, values, holonomic, affine, seed,
                 mu=None, modular=False, circle=(), context=()):
        self.coordinates = tuple(coordinates)
        self.velocities = tuple(velocities)
        self.fixed = {p: _exact_number(p, values[p]) for p in parameters if p in values}
        self.circle = tuple(p for p in circle if self.fixed.get(p))
        self.drawn = tuple(p for p in parameters if p not in values)
        self.rng = random.Random(seed)
        affine = tuple(sp.sympify(e) for e in affine)
        vels = self.velocities
        # mu (given: the system's one-forms, in the order of ``affine``) spares the
        # derivatives; a Chetaev constraint's row still depends on v
        rows = mu if mu is not None else [jacobian_row(e, vels) for e in affine]
        nonlinear = [e for e, row in zip(affine, rows)
                     if any(c.free_symbols & set(vels) for c in row)]
        if nonlinear and not modular:
            raise NotExact(f"the velocity constraint {short(nonlinear[0])} = 0 is not affine "
                           f"(Chetaev): M_1 is curved in the velocities, with points over "
                           f"F_p only")
        # Chetaev's constraints join the chart: their dependent velocities are roots of
        # polynomials over F_p (the chart's smooth points: d phi/d v of full rank there)
        self.solved, self.chart = _charts(self.coordinates, holonomic, modular,
                                          (*context, *affine),
                                          affine if nonlinear else (), vels)
        self.affine = () if nonlinear else affine
        self.mu = rows if mu is not None or not nonlinear else []   # the rows of affine
        self.h = [velocity_free_part(e, vels) for e in self.affine]
        self.dependent: tuple | None = None
        self.rejected = 0
        self.modular = modular
        if modular:
            self.fixed = {p: ModP.lift(x) for p, x in self.fixed.items()}

    @classmethod
    def on_M1(cls, system, seed: int, *, modular: bool = False) -> "PointSampler":
        """The sampler of M_1 = {g = 0, φ = 0} of a system (its coordinates, velocities,
        parameters with their values, holonomic constraints and φ with μ)."""
        return cls(system.coordinates, system.velocities, system.parameters,
                   dict(system.parameter_values), system.holonomic, system.phi, seed,
                   mu=[list(system.mu.row(i)) for i in range(len(system.phi))],
                   modular=modular, circle=circle_parameters(system),
                   context=(system.lagrangian,))

    @property
    def scope(self) -> str:
        """What an answer proved at one of these points holds on ("" where M is
        parametrised rationally: all of M)."""
        return self._curved("proved at a smooth point", "the component of M through it")

    def points_scope(self, count: int) -> str:
        """Where an answer decided at ``count`` of these points holds ("" where M is
        parametrised rationally)."""
        return self._curved(f"decided at {count} smooth point{'s' if count > 1 else ''}",
                            "every component of M through them")

    def _curved(self, how: str, where: str) -> str:
        if self.chart is None:
            return ""
        return (f"M is curved ({self.chart.describe()}): {how} of M over F_p with the "
                f"parameters at their values, so on {where}")

    def error_bound(self, degrees: dict) -> ErrorBound:
        """The bound of verdicts taken at these points (:class:`ErrorBound`).

        Parameters
        ----------
        degrees : dict
            The degree environment of a point (``ExactPoint.degrees``) after the data
            were evaluated in it: on a curved M the sqrt it met count in deg X.
        """
        if self.chart is None:
            # The denominators that may vanish at a drawn point (drawn again) count
            # by the degree of their numerators.
            size = PRIME - 1 if self.modular else 2 ** SAMPLE_BITS
            return ErrorBound(size, self._den_degree)
        deg_x = self.chart.variety_degree(degrees)
        own = self.chart.radicands()
        for base, d in degrees.get(RADICANDS, {}).items():
            if base not in own:  # w^2 * den(b) - num(b) = 0
                deg_x *= max(2 + d.den_degree, d.num)
        return ErrorBound(PRIME - 1, variety_degree=deg_x, tries=TRIES * (1 + REDRAWS))

    def _draw(self):
        if self.modular:
            return ModP(self.rng.randrange(1, PRIME))
        return MPQ(self.rng.randint(1, 2 ** SAMPLE_BITS))

    def point(self) -> ExactPoint:
        """A random exact point of M_1 (raises NotExact when there is no exact route)."""
        for _ in range(TRIES):
            pt = self._try_point()
            if pt is not None:
                return pt
            self.rejected += 1
        raise NotExact("no exact point found: the affine constraints are singular at "
                       "every point tried")

    def _try_point(self):
        env, deg = dict(self.fixed), {p: Degree(0) for p in self.fixed}
        dependent = () if self.chart is None else self.chart.dependent
        for p in self.circle:  # the value's (cos, sin) is transcendental: drawn
            env[p] = Angle.on_circle(self.fixed[p], self._draw())
            if env[p] is None:   # 1 + t^2 = 0 modulo p
                return None
            circ = Degree(2, {("circle", p): (2, 1)})
            deg[p] = Angle(Degree(0), circ, circ)
        for s in self.drawn + tuple(q for q in self.coordinates
                                    if q not in self.solved and q not in dependent):
            t = self._draw()
            env[s] = Angle.on_circle(self._draw(), t)
            if env[s] is None:
                return None
            key = ("circle", s)
            circ = Degree(2, {key: (2, 1)})
            deg[s] = Angle(Degree(1), circ, circ)
        if self.chart is not None:
            for v in self.velocities:   # drawn before a chart that solves for some of them
                if v in self.chart.involved and v not in dependent:
                    env[v], deg[v] = self._draw(), Degree(1)
            found = self.chart.solve(env, self.rng)
            if found is None:
                return None
            env.update(found)
            deg.update(self.chart.degree_env())
            deg[RADICANDS] = {}
        for q, expr in self.solved.items():
            try:
                env[q], = evaluate([expr], env)
            except ZeroDivisionError:
                return None
            deg[q], = evaluate([expr], deg)
        vels = self.velocities
        if not self.affine:
            for v in vels:
                if v not in env:
                    env[v], deg[v] = self._draw(), Degree(1)
            self._den_degree = 0
            return ExactPoint(env, deg)
        return self._velocities(env, deg)

    def _velocities(self, env, deg):
        """The point with free velocities drawn and the dependent ones solved from the
        affine constraints (None where they are singular at the point)."""
        vels = self.velocities
        cache, dcache = {}, {}
        try:
            mu = [evaluate(row, env, cache) for row in self.mu]
            h = evaluate(self.h, env, cache)
        except ZeroDivisionError:
            return None
        if self.dependent is None:
            r, rows, cols = exact_rank(mu)
            if r < len(self.affine):
                raise NotExact("the affine constraints are dependent at a random point")
            self.dependent = tuple(cols)
        dep = list(self.dependent)
        free = [i for i in range(len(vels)) if i not in dep]
        for i in free:
            env[vels[i]], deg[vels[i]] = self._draw(), Degree(1)
        block = [[row[j] for j in dep] for row in mu]
        rhs = [[-(h[k] + sum((mu[k][i] * env[vels[i]] for i in free), 0))]
               for k in range(len(mu))]
        # Degrees of the dependent velocities (Cramer): numerator and denominator
        # are minors of [block | rhs].
        dmu = [evaluate(row, deg, dcache) for row in self.mu]
        dh = evaluate(self.h, deg, dcache)
        dblock = [[row[j] for j in dep] + [dh[k] + sum((row[i] * Degree(1) for i in free), 0)]
                  for k, row in enumerate(dmu)]
        size = len(dep)
        top = minor_degree(dblock, size)
        self._den_degree = minor_degree([r[:size] for r in dblock], size)
        try:
            sol = exact_solve(block, rhs)
        except ZeroDivisionError:
            return None
        fresh = ("denominator", next(Degree._fresh))
        for pos, j in enumerate(dep):
            env[vels[j]] = sol[pos][0]
            deg[vels[j]] = Degree(top, {fresh: (self._den_degree, 1)})
        return ExactPoint(env, deg)


def _refuse_nonlinear(system, equations) -> None:
    """NotExact where M has a nonlinear (Chetaev) constraint: its dependent velocities
    solve φ(q, v) = 0, in general no rational function of the others."""
    kinds = getattr(system, "constraint_kinds", None)  # a view of a System may lack it
    if kinds is None:
        from nhham.system.chetaev import constraint_kind

        kinds = [constraint_kind(f, system.velocities) for f in system.phi]
    nonlinear = [f for f, kind in zip(system.phi, kinds) if kind != "affine"]
    if set(nonlinear) & set(equations):
        raise NotExact("nonlinear (Chetaev) constraints: the dependent velocities of M_1 are "
                       "no rational functions of the others")


def exact_sampler(manifold, seed: int, *, modular: bool = False) -> PointSampler:
    """The exact points of a submanifold M = {constraints = 0} over Q (or F_p).

    M_1 = {g = 0, φ = 0} of the manifold's system keeps the system's own order (so its
    points are those of :meth:`PointSampler.on_M1`); M in Q (``manifold.fibre == ()``)
    is {g = 0}; for any other M the constraints free of velocities are solved for
    coordinates (also those that become free of velocities once the coordinates solved
    so far are substituted: q2 - 2 q1 v1^2 where q1 = 0), the rest, affine in the
    velocities, for dependent velocities.

    Parameters
    ----------
    manifold : Submanifold
    seed : int
    modular : bool, optional
        Points over F_p instead of rational points.

    Raises
    ------
    NotExact
        Where a constraint is neither solvable for a coordinate nor affine in the
        velocities, or M has no exact points.
    """
    system = manifold.system
    equations = set(manifold.equations)
    holonomic = tuple(system.holonomic)
    values = dict(system.parameter_values)
    if not manifold.fibre:
        if not equations <= set(holonomic):
            raise NotExact("a submanifold of Q is defined by holonomic constraints")
        return PointSampler(system.coordinates, (), system.parameters, values,
                            [g for g in holonomic if g in equations], (), seed,
                            modular=modular, circle=circle_parameters(system),
                            context=(system.lagrangian,))
    if tuple(manifold.fibre) != tuple(system.velocities):
        raise NotExact("exact points are drawn in TQ and Q")
    if equations == set(holonomic) | set(system.phi):
        return PointSampler.on_M1(system, seed, modular=modular)
    _refuse_nonlinear(system, equations)
    solved, affine = _split(system, manifold.equations)
    return PointSampler(system.coordinates, system.velocities, system.parameters, values,
                        solved, affine, seed, modular=modular,
                        circle=circle_parameters(system), context=(system.lagrangian,))


def _split(system, constraints):
    """(constraints solved for coordinates, constraints affine in the velocities)."""
    vels = set(system.velocities)
    holonomic: list = []
    rest = [sp.sympify(c) for c in constraints]
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
    return holonomic, affine


def _charts(coordinates, holonomic, modular, context, velocity_constraints=(),
            velocities=()):
    """(coordinates solved linearly, the curved chart of the rest or None); the velocity
    constraints given (Chetaev's, nonlinear in v) join the chart with the velocities as
    its unknowns too."""
    solved, unsolved = solve_for_coordinates(coordinates, holonomic)
    if not unsolved and not velocity_constraints:
        return solved, None
    if not modular:
        raise NotExact(f"the holonomic constraint {short(unsolved[0])} = 0 is not linear "
                       f"in a coordinate with a constant coefficient: M is curved, with "
                       f"points over F_p only")
    rest = [sp.sympify(g).xreplace(solved) for g in (*unsolved, *velocity_constraints)]
    free = [q for q in coordinates if q not in solved] + list(velocities)
    return solved, curved_chart(rest, free, context)


def circle_parameters(system) -> tuple:
    """The parameter with a nonzero value that appears inside sin/cos, when it is the
    only parameter with a value there; else ().

    Its (cos a, sin a) is then drawn at random on the unit circle like a coordinate's:
    for a nonzero rational a, e^{ia} is transcendental (Lindemann–Weierstrass), so a
    polynomial identity over Q in (cos a, sin a) holds at the value exactly when it
    holds on the whole circle, and a random circle point decides it as at the value.
    Two such parameters are not independent (e^{ia} and e^{ib} are powers of one
    number for rational a, b): neither is drawn, and sin/cos of them has no exact
    value.
    """
    values = system.parameter_values
    found = set()
    for e in (system.lagrangian, *system.phi, *system.holonomic):
        for f in sp.sympify(e).atoms(sp.sin, sp.cos, sp.tan, sp.cot):
            found |= {p for p in f.args[0].free_symbols if p in values and values[p]}
    return tuple(found) if len(found) == 1 else ()


def jacobian_row(expr, symbols) -> list:
    """[d expr / d s for s in symbols], differentiating only where s occurs."""
    expr = sp.sympify(expr)
    present = symbols_in(expr)
    return [derivative(expr, s) if s in present else sp.S.Zero for s in symbols]


def _exact_number(name, value):
    try:
        r = sp.Rational(str(value))
    except (TypeError, ValueError, sp.SympifyError) as exc:
        raise NotExact(f"parameter {name} = {value!r} is not an exact number") from exc
    return MPQ(int(r.p), int(r.q))


def eliminate_coordinates(coordinates, holonomic) -> dict:
    """Coordinates solved from holonomic constraints linear in them (constant coefficient,
    :func:`~nhham.lagrangian.algebra.solve_for_coordinates`); NotExact naming the first
    constraint that is not."""
    solved, unsolved = solve_for_coordinates(coordinates, holonomic)
    if unsolved:
        raise NotExact(f"the holonomic constraint {unsolved[0]} = 0 is not linear in a "
                       f"coordinate with a constant coefficient")
    return solved


# ----------------------------------------------- points over the parameter field
# Size of the random state values: small numbers keep the arithmetic in Q(p) cheap. A
# value can only add a spurious factor to the gcd of the values (never hide a true
# component), and every component is verified by running the classification on it.
DRAW_BITS = 16


# ============================================================ exact evaluation
class ParameterFieldSampler:
    """Random exact points of M = {equations = 0} with parameters as field generators.

    M_1 without holonomic constraints: coordinates drawn, dependent velocities solved
    at the point over Q(p). Otherwise ``reduction()``, the exact reduction of M
    (:attr:`Submanifold.reduction <nhham.lagrangian.submanifold.Submanifold.reduction>`),
    is evaluated at the point (NotExact when it leaves residual equations).
    """

    def __init__(self, system, equations, env0, K, rng, reduction=None):
        self.q, self.v = tuple(system.coordinates), tuple(system.velocities)
        self.env0, self.K, self.rng = env0, K, rng
        eqs = tuple(sp.sympify(e) for e in equations)
        _refuse_nonlinear(system, eqs)
        phis = set(system.phi)
        self.affine = not system.holonomic and all(e in phis for e in eqs)
        self.dep = None
        if self.affine:
            self.mu = [jacobian_row(e, self.v) for e in eqs]
            self.h = [velocity_free_part(e, self.v) for e in eqs]
        else:
            # The cheap test first: the symbolic reduction of a large M_k with a holonomic
            # constraint no coordinate can be solved from linearly takes minutes, to end
            # in the same NotExact.
            eliminate_coordinates(self.q, system.holonomic)
            red = reduction()
            if red.residual:
                raise NotExact("M_k is not parametrised by the exact reduction (residual "
                               "equations " + ", ".join(short(r) for r in red.residual) + ")")
            self.sub = red.substitution

    def _draw(self):
        return MPQ(self.rng.randint(1, 2 ** DRAW_BITS))

    def _angle(self):
        t = self._draw()
        return Angle.on_circle(self._draw(), t)

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
                sol = field_solve(block, rhs).to_list()
            except BudgetExceeded:  # an expiry is not a singular point
                raise
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
