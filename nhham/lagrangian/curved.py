"""Points over F_p of a curved configuration space: holonomic constraints solved mod p.

A holonomic constraint that no coordinate enters linearly with a constant coefficient
(the bicycle's front contact, a closed linkage, a particle on a sphere) leaves M_1 with
no rational parametrisation, so :mod:`nhham.lagrangian.points` cannot draw it. Over the
finite field F_p (p = 2^61 − 1) it has points all the same: the remaining k constraints
g(q) = 0 become k polynomial equations in k *dependent* coordinates once the others
are drawn at random, and a polynomial system over F_p is solved exactly.

How the equations are made polynomial (done once, symbolically):

* a dependent coordinate q that appears only inside sin/cos (an *angle*) becomes the
  rational parameter t of its circle point, cos q = (1 − t²)/(1 + t²),
  sin q = 2t/(1 + t²); sin/cos of k q + rest are expanded, ``rest`` staying an
  expression of the drawn symbols; a dependent coordinate that never appears inside
  sin/cos is its own unknown; one that appears both ways cannot be dependent;
* every sqrt(b) whose radicand involves a dependent coordinate is a new unknown w with
  w² = b (half-integer powers are its powers);
* numerators are taken; the coefficients, expressions of the drawn coordinates and the
  parameters, are evaluated at each draw by :func:`~nhham.lagrangian.domains.evaluate`.

Per draw, a lex Gröbner basis over F_p gives a triangular system, solved by univariate
roots (:meth:`sympy.Poly.ground_roots` over GF(p)) from the last unknown up. A solution
is a point only when the original constraints vanish there *exactly* (evaluated with
the branch :func:`~nhham.lagrangian.domains.square_root` fixes for every sqrt, which
rejects the other branch and the zeros of denominators) and the Jacobian dg/dq_dep has
full rank there (a *smooth* point, on exactly one component of M).

What a point proves. A function of q (a minor, a bracket, a Frobenius term) that is
nonzero at a smooth point of M over F_p does not vanish identically on the irreducible
component of M through that point (over the algebraic closure of Q): if it vanished
there it would lie in that component's ideal, and a polynomial of that ideal with
p-integral coefficients vanishes at its points mod p. So a full rank there proves the
rank on that component, for the parameter values the point was drawn with. When M is
irreducible (a single hypersurface g = 0 with g irreducible, as the bicycle's contact),
that is M. Where no solution is found the caller falls back to sampled points.

What points prove when the function vanishes there (a rank drop, a vanishing): nothing
for certain, but with a stated bound (:class:`~nhham.lagrangian.domains.ErrorBound`):
by Bézout, a numerator of degree D not zero on a component of the lifted variety X
(deg X ≤ the product of the degrees of the chart's equations and of every w² = b) vanishes
at a drawn point of it with probability ≤ tries · deg X · D / (p − 1); the claim is then
"on every component of M through the points". :meth:`CurvedChart.degree_env` and
:meth:`CurvedChart.variety_degree` give the degrees.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import sympy as sp
from sympy.polys.domains import GF, ZZ
from sympy.polys.galoistools import (
    gf_add,
    gf_edf_zassenhaus,
    gf_eval,
    gf_gcd,
    gf_monic,
    gf_mul,
    gf_neg,
    gf_sqr,
    gf_strip,
    gf_sub,
)
from sympy.polys.groebnertools import groebner
from sympy.polys.rings import ring

from nhham.lagrangian.domains import PRIME, Angle, Degree, ModP, NotExact, evaluate
from nhham.lagrangian.linalg import exact_rank
from nhham.system.expressions import derivative, short

__all__ = ["CurvedChart", "curved_chart"]

# Dependent coordinate sets tried (each built symbolically) before giving up.
MAX_CHOICES = 12


@dataclass(frozen=True)
class CurvedChart:
    """The constraints g(q) = 0 of a curved M as polynomials in its dependent unknowns.

    Attributes
    ----------
    constraints : tuple of sympy.Expr
        The constraints solved here (each = 0), in the coordinates.
    dependent : tuple of sympy.Symbol
        The coordinates solved mod p, one per constraint.
    angles : tuple of bool
        Per dependent coordinate: an angle (solved for its circle point) or a plain
        value.
    unknowns : tuple of sympy.Symbol
        The polynomial unknowns: one per dependent coordinate (t or the value), then
        one per sqrt of a radicand with a dependent coordinate.
    polynomials : tuple of dict
        Each equation as {exponent tuple: coefficient expression in the drawn symbols}.
    degrees : tuple of int
        Total degree of each equation in the unknowns (its Bézout number is their
        product).
    """

    constraints: tuple
    dependent: tuple
    angles: tuple
    unknowns: tuple
    polynomials: tuple
    degrees: tuple

    def describe(self) -> str:
        """What the chart solves, for the decisions' scope."""
        names = ", ".join(q.name for q in self.dependent)
        # a velocity (<q>_dot: no coordinate may have that name) makes a Chetaev chart
        kind = "constraint" if any(q.name.endswith("_dot") for q in self.involved) \
            else "holonomic constraint"
        return (f"the {kind}{'s' if len(self.constraints) > 1 else ''} solved "
                f"for {names} over F_p")

    @property
    def involved(self) -> frozenset:
        """The symbols of the constraints."""
        return frozenset().union(*(sp.sympify(g).free_symbols for g in self.constraints))

    def degree_env(self) -> dict:
        """Degree bounds of the dependent coordinates in the lifted variables: an angle
        is its circle point in its own t, a value its own unknown."""
        out: dict = {}
        for q, angle in zip(self.dependent, self.angles):
            if angle:
                circ = Degree(2, {("circle", q): (2, 1)})
                out[q] = Angle(None, circ, circ)
            else:
                out[q] = Degree(1)
        return out

    def variety_degree(self, degrees: dict) -> int:
        """The Bézout number of the lifted variety X: the product of the total degrees
        of the chart's equations in the drawn variables (their bounds in ``degrees``)
        and the unknowns.

        Parameters
        ----------
        degrees : dict
            Symbol -> :class:`Degree` of every drawn symbol the coefficients use.
        """
        total = 1
        for poly in self.polynomials:
            keys = list(poly)
            coefficients = evaluate([poly[k] for k in keys], degrees)
            equation = Degree(0)
            for c, k in zip(coefficients, keys):
                equation = equation + Degree.of(c) * Degree(sum(k))
            total *= max(1, equation.num)
        return total

    def radicands(self) -> frozenset:
        """The radicands of the sqrt in the constraints (their w are unknowns here)."""
        return frozenset(a.base for g in self.constraints for a in g.atoms(sp.Pow)
                         if a.exp.is_Rational and a.exp.q == 2)

    def solve(self, env: dict, rng) -> dict | None:
        """The dependent coordinates at one smooth point of M above the drawn values.

        Parameters
        ----------
        env : dict
            Values (:class:`ModP`, :class:`Angle` of them) of every other coordinate
            and of the parameters.
        rng : random.Random
            Picks one of the solutions.

        Returns
        -------
        dict or None
            Dependent coordinate -> value (an :class:`Angle` with no polynomial value
            for an angle, a :class:`ModP` otherwise); None when no smooth point lies
            above these values (the caller draws again).
        """
        try:
            system = self._instance(env)
        except ZeroDivisionError:
            return None
        solutions = _triangular_solutions(system, self.unknowns)
        rng.shuffle(solutions)
        for sol in solutions:
            point = self._point(sol)
            if point is not None and self._on_M(env, point):
                return point
        return None

    def _instance(self, env):
        """The equations over F_p at the drawn values (sympy Polys with modulus p)."""
        cache: dict = {}
        out = []
        for poly in self.polynomials:
            keys = list(poly)
            values = evaluate([poly[k] for k in keys], env, cache)
            out.append(sp.Poly.from_dict({k: ModP.lift(v).v for k, v in zip(keys, values)},
                                         *self.unknowns, modulus=PRIME))
        return out

    def _point(self, sol):
        point = {}
        for q, angle, u in zip(self.dependent, self.angles, self.unknowns):
            t = ModP(sol[u])
            if not angle:
                point[q] = t
                continue
            point[q] = Angle.on_circle(None, t)
            if point[q] is None:
                return None
        return point

    def _on_M(self, env, point) -> bool:
        """The constraints vanish exactly at the point (the branch of every sqrt as F_p
        fixes it, no denominator zero) and their Jacobian in the dependent coordinates
        has full rank (a smooth point)."""
        at = {**env, **point}
        try:
            if any(evaluate(self.constraints, at)):
                return False
            jac = [evaluate([derivative(g, q) for q in self.dependent], at)
                   for g in self.constraints]
        except (ZeroDivisionError, NotExact):
            return False
        return exact_rank(jac)[0] == len(self.dependent)


def curved_chart(constraints, coordinates, expressions=()) -> CurvedChart:
    """The chart of ``constraints`` with the dependent coordinates of least degree.

    Parameters
    ----------
    constraints : sequence of sympy.Expr
        The holonomic constraints not solved linearly (each = 0), in the remaining
        coordinates.
    coordinates : sequence of sympy.Symbol
        The coordinates that may be dependent (those not solved linearly).
    expressions : sequence of sympy.Expr, optional
        Everything else evaluated at the points (Lagrangian, constraints): a
        coordinate that appears there outside sin/cos cannot be an angle solved by its
        circle point alone.

    Raises
    ------
    NotExact
        No choice of dependent coordinates makes the constraints polynomial.
    """
    # Memoised: a command asks for the chart of M_1, Q_1 and M_f, often the same one.
    return _best_chart(tuple(sp.sympify(g) for g in constraints), tuple(coordinates),
                       tuple(sp.sympify(e) for e in expressions))


@functools.lru_cache(maxsize=64)
def _best_chart(constraints, coordinates, expressions) -> CurvedChart:
    k = len(constraints)
    involved = set().union(*(g.free_symbols for g in constraints))
    candidates = [q for q in coordinates if q in involved]
    kinds = {q: _kind(q, constraints, expressions) for q in candidates}
    usable = [q for q in candidates if kinds[q] is not None]
    charts, why = [], "no coordinate enters them only through sin/cos or only polynomially"
    for choice in itertools.islice(itertools.combinations(usable, k), MAX_CHOICES):
        try:
            charts.append(_chart(constraints, choice, tuple(kinds[q] for q in choice)))
        except NotExact as exc:
            why = str(exc)
    if not charts:
        raise NotExact(f"the holonomic constraint {short(constraints[0])} = 0 cannot be "
                       f"solved over F_p ({why})")
    return min(charts, key=lambda c: (_bezout(c.degrees), len(c.unknowns)))


def _bezout(degrees) -> int:
    out = 1
    for d in degrees:
        out *= d
    return out


def _kind(q, constraints, expressions) -> str | None:
    """"angle" (q only inside sin/cos everywhere), "value" (never inside sin/cos in
    the constraints nor anywhere else), or None."""
    inside = outside = False
    for e in (*constraints, *expressions):
        i, o = _contexts(sp.sympify(e))
        inside, outside = inside or q in i, outside or q in o
    if inside and outside:
        return None
    return "angle" if inside else "value"


@functools.lru_cache(maxsize=256)
def _contexts(e) -> tuple[frozenset, frozenset]:
    """(symbols inside a sin/cos argument, symbols elsewhere) of ``e``, in one walk of
    its tree (a walk per symbol asking free_symbols at every node was quadratic: 0.25 s
    on the bicycle's Lagrangian)."""
    inside: set = set()
    outside: set = set()
    stack = [(e, False)]
    while stack:
        node, trig = stack.pop()
        if node.is_Symbol:
            (inside if trig else outside).add(node)
            continue
        trig = trig or node.func in (sp.sin, sp.cos, sp.tan, sp.cot)
        stack.extend((a, trig) for a in node.args)
    return frozenset(inside), frozenset(outside)


@functools.lru_cache(maxsize=64)
def _chart(constraints, dependent, kinds) -> CurvedChart:
    """The polynomial equations for one choice of dependent coordinates (memoised: the
    charts of M_1 and of Q_1 differ in their context only)."""
    unknowns, circle = [], {}
    for q, kind in zip(dependent, kinds):
        if kind == "angle":
            t = sp.Dummy(f"t_{q.name}")
            circle[q] = ((1 - t ** 2) / (1 + t ** 2), 2 * t / (1 + t ** 2))
            unknowns.append(t)
        else:
            unknowns.append(q)
    roots: dict = {}
    rewrite = _Rewrite(set(dependent), circle, roots)
    equations = [rewrite(g) for g in constraints]
    for base, w in list(roots.items()):
        equations.append(w ** 2 - base)
    gens = [*unknowns, *roots.values()]
    polys, degrees = [], []
    for eq in equations:
        num = sp.fraction(sp.together(eq))[0]
        try:
            poly = _coefficients(sp.expand(num), gens)
        except sp.PolynomialError as exc:
            raise NotExact(f"not polynomial in {', '.join(q.name for q in dependent)}: "
                           f"{exc}") from exc
        polys.append(poly)
        degrees.append(max((sum(m) for m in poly), default=0))
    return CurvedChart(tuple(constraints), tuple(dependent),
                       tuple(k == "angle" for k in kinds), tuple(gens), tuple(polys),
                       tuple(degrees))


def _coefficients(expanded, gens) -> dict:
    """{exponents: coefficient} of an expanded polynomial in ``gens`` whose coefficients
    are expressions in other symbols, monomials in lex order (as :class:`sympy.Poly`'s).

    Read off the terms: a Poly over the expression domain simplifies every coefficient on
    each operation (a third of a chart's time on the bicycle). Terms that sum to a zero
    coefficient were combined by the expansion already.

    Raises
    ------
    sympy.PolynomialError
        A term is not a coefficient times a monomial in ``gens``.
    """
    index = {g: i for i, g in enumerate(gens)}
    wanted = set(gens)
    terms: dict = {}
    for term in sp.Add.make_args(expanded):
        if term == 0:
            continue
        coeff, monomial = term.as_independent(*gens, as_Add=False)
        exponents = [0] * len(gens)
        for base, k in monomial.as_powers_dict().items():
            if base == 1:
                continue
            if base not in index or not (k.is_Integer and k > 0):
                raise sp.PolynomialError(f"{base**k} contains an element of the set of "
                                         f"generators.")
            exponents[index[base]] += int(k)
        if coeff.free_symbols & wanted:
            raise sp.PolynomialError(f"{coeff} contains an element of the set of generators.")
        terms.setdefault(tuple(exponents), []).append(coeff)
    out = {m: sp.Add(*c) for m, c in terms.items()}
    return {m: out[m] for m in sorted(out, reverse=True) if out[m] != 0}


class _Rewrite:
    """sin/cos of the dependent angles as rational functions of t, sqrt of radicands
    with a dependent coordinate as new unknowns w (w² = radicand)."""

    def __init__(self, dependent, circle, roots):
        self.dependent, self.circle, self.roots = dependent, circle, roots

    def __call__(self, e):
        e = sp.sympify(e)
        if e.is_Atom or not e.free_symbols & self.dependent:
            return e
        if e.func in (sp.sin, sp.cos):
            return self._trig(e.func, e.args[0])
        if e.func in (sp.tan, sp.cot):
            s, c = self._trig(sp.sin, e.args[0]), self._trig(sp.cos, e.args[0])
            return s / c if e.func is sp.tan else c / s
        if e.is_Pow and e.exp.is_Rational and e.exp.q == 2:
            base = self(e.base)
            w = self.roots.setdefault(base, sp.Dummy(f"w{len(self.roots)}"))
            return w ** int(e.exp.p)
        if e.is_Pow and not e.exp.is_Integer:
            raise NotExact(f"the power {short(e)} of a dependent coordinate")
        if e.is_Function and not e.is_Add and not e.is_Mul and not e.is_Pow:
            raise NotExact(f"{e.func} of a dependent coordinate")
        return e.func(*[self(a) for a in e.args])

    def _trig(self, func, arg):
        arg = sp.expand(arg)
        c, s = sp.S.One, sp.S.Zero
        rest = arg
        for q in self.dependent & arg.free_symbols:
            k = arg.coeff(q)
            if not k.is_Integer or q not in self.circle:
                raise NotExact(f"{func}({short(arg)}) is not of an integer multiple of "
                               f"the angle {q.name}")
            ck, sk = _multiple(*self.circle[q], int(k))
            c, s = c * ck - s * sk, s * ck + c * sk
            rest = rest - k * q
        rest = sp.expand(rest)
        if rest.free_symbols & self.dependent:
            raise NotExact(f"{func}({short(arg)}) is not linear in the dependent angles")
        cr, sr = sp.cos(rest), sp.sin(rest)
        if func is sp.cos:
            return c * cr - s * sr
        return s * cr + c * sr


def _multiple(c, s, k: int):
    """(cos k q, sin k q) from (cos q, sin q)."""
    ck, sk = sp.S.One, sp.S.Zero
    for _ in range(abs(k)):
        ck, sk = ck * c - sk * s, sk * c + ck * s
    return (ck, sk) if k >= 0 else (ck, -sk)


def _triangular_solutions(polys, unknowns) -> list:
    """Every solution over F_p of the polynomial system (a list of {unknown: int}); []
    when the system is not zero-dimensional or has no solution there.

    In sympy's sparse polynomial ring over GF(p) with lex order (expressions round
    trips cost 50 ms a point on the bicycle; ring elements 7 ms)."""
    gens = tuple(unknowns)
    R = _ring(len(gens))
    elements = [R.from_dict({k: int(v) for k, v in p.as_dict().items()}) for p in polys]
    direct = _one_unknown(elements, R)
    if direct is not None:
        return [{gens[i]: v for i, v in sol.items()} for sol in direct]
    try:
        basis = groebner(elements, R)
    except (sp.PolynomialError, ZeroDivisionError):
        return []
    if any(b.is_ground and b for b in basis):
        return []
    found = _solve_from(len(gens) - 1, basis, R, {})
    return [{gens[i]: v for i, v in sol.items()} for sol in found]


@functools.lru_cache(maxsize=8)
def _ring(k: int):
    return ring([f"u{i}" for i in range(k)], GF(PRIME), "lex")[0]


def _solve_from(i, basis, R, known) -> list:
    """Solutions extending ``known`` (values of the unknowns after i) by the value of
    unknown i."""
    if i < 0:
        return [dict(known)]
    univariate = None
    for b in basis:
        used = {j for j, d in enumerate(b.degrees()) if d}
        if i not in used or any(j < i for j in used):
            continue
        u = b.subs([(R.gens[j], known[j]) for j in used if j > i]) if len(used) > 1 else b
        if not u:
            continue  # vanishes above this point: no condition on unknown i
        dense = _dense(u, i)
        univariate = dense if univariate is None else gf_gcd(univariate, dense, PRIME, ZZ)
    if univariate is None:
        return []  # unknown i free above this point: not zero-dimensional
    out = []
    for root in _roots(univariate):
        out += _solve_from(i - 1, basis, R, {**known, i: root})
    return out


def _one_unknown(elements, R) -> list | None:
    """The solutions without a Gröbner basis in the two commonest shapes: one unknown
    (its roots), or one unknown t and one sqrt w with f(t, w) = 0 of degree <= 2 in w and
    c(t) w² = b(t) (the bicycle's contact): reduce f to F0(t) + w F1(t) (times c), take
    the roots of c F0² − b F1², then w = −F0/F1 (both square roots where F1 = F0 = 0).
    None for any other shape."""
    if len(R.gens) == 1:
        dense = [_dense(e, 0) for e in elements if e]
        if not dense:
            return None
        f = dense[0]
        for g in dense[1:]:
            f = gf_gcd(f, g, PRIME, ZZ)
        return [{0: r} for r in _roots(f)]
    if len(R.gens) != 2 or len(elements) != 2:
        return None
    f, root = elements
    if root.degree(R.gens[1]) != 2 or any(m[1] == 1 for m in root.monoms()) \
            or f.degree(R.gens[1]) > 2:
        return None
    c = _dense(_part(root, 2), 0)  # c(t) w^2 - b(t) = 0
    b = gf_neg(_dense(_part(root, 0), 0), PRIME, ZZ)
    a = [_dense(_part(f, k), 0) for k in range(3)]  # f = a0 + a1 w + a2 w^2
    F0 = gf_add(gf_mul(a[0], c, PRIME, ZZ), gf_mul(a[2], b, PRIME, ZZ), PRIME, ZZ)
    F1 = gf_mul(a[1], c, PRIME, ZZ)
    g = gf_sub(gf_mul(gf_sqr(F0, PRIME, ZZ), c, PRIME, ZZ),
               gf_mul(b, gf_sqr(F1, PRIME, ZZ), PRIME, ZZ), PRIME, ZZ)
    if not g:
        return None  # t free: not zero-dimensional (left to the general route)
    out = []
    for t in _roots(g):
        ct = gf_eval(c, t, PRIME, ZZ)
        if not ct:
            continue  # the sqrt's equation degenerates here: no point
        f0, f1 = gf_eval(F0, t, PRIME, ZZ), gf_eval(F1, t, PRIME, ZZ)
        if f1:
            out.append({0: t, 1: (-f0 * pow(f1, -1, PRIME)) % PRIME})
            continue
        w2 = gf_eval(b, t, PRIME, ZZ) * pow(ct, -1, PRIME) % PRIME
        w = pow(w2, (PRIME + 1) // 4, PRIME)
        if w * w % PRIME == w2:
            out += [{0: t, 1: w}, {0: t, 1: (-w) % PRIME}] if w else [{0: t, 1: 0}]
    return out


def _part(f, k: int):
    """The coefficient of w^k in f(t, w), as an element of the same ring."""
    R = f.ring
    return R.from_dict({(m[0], 0): c for m, c in f.terms() if m[1] == k}) if f else R(0)


def _dense(e, i: int) -> list:
    """A polynomial in unknown i alone as a dense list of ints (highest degree first)."""
    if not e:
        return []
    dense = [0] * (e.degree(e.ring.gens[i]) + 1)
    for monom, c in e.terms():
        dense[len(dense) - 1 - monom[i]] = int(c)
    return dense


def _roots(f) -> list:
    """The roots in F_p of a dense polynomial over F_p: gcd with x^p − x (x^p mod f by
    squarings in plain integers), then the linear factors (by the formula up to degree 2,
    Cantor–Zassenhaus beyond)."""
    f = gf_strip([c % PRIME for c in f])
    if len(f) < 2:
        return []
    f = gf_monic(f, PRIME, ZZ)[1]
    xp = _x_power_mod(PRIME, f)
    g = gf_monic(gf_gcd(f, gf_sub(xp, [1, 0], PRIME, ZZ), PRIME, ZZ), PRIME, ZZ)[1]
    if len(g) == 2:
        return [(-g[1]) % PRIME]
    if len(g) == 3:  # x^2 + b x + c with two roots in F_p (p = 3 mod 4)
        b, c = g[1], g[2]
        disc = (b * b - 4 * c) % PRIME
        r = pow(disc, (PRIME + 1) // 4, PRIME)
        half = pow(2, -1, PRIME)
        return [((-b + r) * half) % PRIME, ((-b - r) * half) % PRIME]
    if len(g) < 2:
        return []
    return [(-h[-1]) % PRIME for h in gf_edf_zassenhaus(g, 1, PRIME, ZZ)]


def _x_power_mod(e: int, f: list) -> list:
    """x^e mod f for monic f (dense, highest degree first), in plain integers."""
    d = len(f) - 1
    r = [1]
    for bit in bin(e)[2:]:
        r = _reduce(_square(r), f, d)
        if bit == "1":
            r = _reduce(r + [0], f, d)
    return gf_strip(r)


def _square(a: list) -> list:
    n = len(a)
    out = [0] * (2 * n - 1)
    for i, x in enumerate(a):
        if x:
            for j in range(n):
                out[i + j] += x * a[j]
    return out


def _reduce(a: list, f: list, d: int) -> list:
    """a mod f (f monic of degree d), coefficients mod p."""
    a = [x % PRIME for x in a]
    for i in range(len(a) - d):
        c = a[i]
        if c:
            for j in range(1, d + 1):
                a[i + j] = (a[i + j] - c * f[j]) % PRIME
    return a[max(0, len(a) - d):] if len(a) > d else a
