"""Chaplygin's multiplier in velocity coordinates, decided at exact points.

The Legendre map Leg: (r, r') -> (r, p = dL_c/dr') of a reduced Lagrangian quadratic in r'
is a diffeomorphism, linear on the fibres (p = W r' + b), so the conformal-factor
equations can be solved in (r, r') instead of (r, p), where nothing needs W^{-1}:

    Omega_v = Leg^* Omega_nh = dr^a ^ d(p_a(r, r')) - 1/2 G_ab(r, r') dr^a ^ dr^b,

polynomial in r' (G = J_a B^a, :mod:`nhham.lagrangian.chaplygin`). Pulling back commutes
with d and ^, so theta ^ Omega_nh = -d Omega_nh has a solution exactly when
theta_v ^ Omega_v = -d Omega_v has one, theta_v = Leg^* theta. Its dr' part is
W theta_p (theta's dp part) and its dr part theta_r + (dp/dr)^T theta_p; so theta is a
one-form of r alone (no dp part, coefficients free of p) exactly when theta_v has no dr'
part and its dr coefficients are free of r', and then d theta_v = Leg^* d theta.

At an exact point x0 = (r0, r0') (rational velocities; angles through rational points of
the unit circle; parameters at their values: :mod:`nhham.lagrangian.points`) the equations
A(x) theta = b(x) become rational. Where A(x0) has full column rank 2k (Omega_v is
nondegenerate there), a solution theta(x) would be defined at x0 and solve the equations
there (Cramer on a nonzero minor), so

- [A | b](x0) of larger rank proves that no solution exists;
- otherwise theta(x0) and its first derivatives, from A d_m theta = d_m b - (d_m A) theta
  on a nonsingular block of rows, prove a dp part, a dependence on p or d theta != 0 by
  one nonzero value each. Each is a proof that no factor exists ("a difference at one
  point is a proof", DESIGN.md §2). Values that vanish at the point prove nothing: the
  caller then finds theta in closed form.

The Jacobiator of the reduced bracket ({r^a, p_b} = delta, {p_a, p_b} = G_ab(r, p)) is
evaluated at the same point from G's derivatives in (r, r'): a nonzero value is a proof
that the bracket is not Poisson.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import sympy as sp

from nhham.lagrangian.domains import NotExact, Program
from nhham.lagrangian.linalg import exact_rank, exact_solve
from nhham.lagrangian.points import PointSampler, circle_parameters
from nhham.settings import SEED
from nhham.system.naming import momentum_symbol

__all__ = ["VelocityEquations", "velocity_equations", "PointVerdict", "decide_at_a_point",
           "jacobiators", "Program_at", "fibre_obstruction"]

#: Points drawn before the decision gives up (a zero denominator or Omega_v degenerate at
#: each of them).
DRAWS = 4


@dataclass(frozen=True)
class VelocityEquations:
    """theta ^ Omega_v = -d Omega_v in the velocity coordinates (r, r').

    Attributes
    ----------
    shape, velocities : tuple of sympy.Symbol
        r and r' (z = r + r', 2k coordinates).
    momenta : tuple of sympy.Expr
        p_a(r, r') = dL_c/dr'^a.
    W : sympy.Matrix, shape (k, k)
        d^2 L_c / dr' dr' (functions of r).
    gyroscopic : sympy.Matrix, shape (k, k)
        G(r, r') = J_a B^a.
    two_form : sympy.Matrix, shape (2k, 2k)
        Omega_v: the dr^dr block (dp_a/dr^c - dp_c/dr^a - G_ac), the dr^dr' block W.
    triples : tuple of (int, int, int)
        The components i < j < l of the 3-form equations, one row each.
    A : tuple of tuple of sympy.Expr
        A[t][n]: the coefficient of theta_n in row t (theta ^ Omega_v).
    b : tuple of sympy.Expr
        -(d Omega_v) of row t.
    """

    shape: tuple
    velocities: tuple
    momenta: tuple
    W: sp.Matrix
    gyroscopic: sp.Matrix
    two_form: sp.Matrix
    triples: tuple
    A: tuple
    b: tuple

    @property
    def k(self) -> int:
        return len(self.shape)

    @property
    def variables(self) -> tuple:
        return self.shape + self.velocities

    def size(self) -> int:
        """sympy operations of Omega_v's upper triangle (what decides the route)."""
        n = 2 * self.k
        return sum(sp.count_ops(self.two_form[i, j]) for i in range(n) for j in range(i + 1, n))


def velocity_equations(reduction) -> VelocityEquations:
    """The conformal-factor equations of a Chaplygin reduction in (r, r').

    Parameters
    ----------
    reduction : ChaplyginReduction
        With L_c quadratic in the shape velocities (the caller checks it).

    Returns
    -------
    VelocityEquations

    Examples
    --------
    The nonholonomic particle z' = y x': p = ((1 + y^2) x', y'), G_xy = y x', so the dr^dr
    block is d p_x/dy - G_xy = 2 y x' - y x' = y x'.

    >>> from nhham import System
    >>> from nhham.lagrangian.chaplygin import chaplygin_reduction
    >>> eqs = velocity_equations(chaplygin_reduction(System(
    ...     ["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", ["z_dot - y*x_dot"])))
    >>> eqs.two_form[0, 1], eqs.W
    (x_dot*y, Matrix([
    [y**2 + 1, 0],
    [       0, 1]]))
    """
    red = reduction
    r, v = tuple(red.shape), tuple(red.shape_velocities)
    k = len(r)
    L = red.lagrangian
    p = tuple(sp.diff(L, w) for w in v)
    W = sp.Matrix(k, k, lambda i, j: sp.diff(p[i], v[j]))
    G = red.gyroscopic_form
    Omega = sp.zeros(2 * k, 2 * k)
    for a, c in itertools.product(range(k), repeat=2):
        if a != c:
            Omega[a, c] = sp.diff(p[a], r[c]) - sp.diff(p[c], r[a]) - G[a, c]
        Omega[a, k + c], Omega[k + c, a] = W[a, c], -W[a, c]
    z = r + v
    triples = tuple(itertools.combinations(range(2 * k), 3))
    A, b = [], []
    for i, j, l in triples:
        row = [sp.S.Zero] * (2 * k)
        row[i] += Omega[j, l]
        row[j] += Omega[l, i]
        row[l] += Omega[i, j]
        A.append(tuple(row))
        b.append(-(sp.diff(Omega[j, l], z[i]) + sp.diff(Omega[l, i], z[j])
                   + sp.diff(Omega[i, j], z[l])))
    return VelocityEquations(r, v, p, W, G, Omega, triples, tuple(A), tuple(b))


@dataclass(frozen=True)
class PointVerdict:
    """What one exact point says about the equations.

    Attributes
    ----------
    proof : str or None
        The obstruction proved at the point ("no solution", "dp part", "depends on p",
        "not closed"), or None (nothing refuted there: the closed form decides).
    detail : str
        The evidence, in words, with the point.
    theta : tuple or None
        theta_v at the point (exact rationals), where the equations solve there.
    jacobiator : tuple of (tuple of str, value)
        The Jacobiators of the (r, p) coordinate functions that are nonzero at the point.
    point : str
        The point, for the record.
    env : dict
        The point: symbol -> exact value (:class:`~nhham.lagrangian.domains.Angle` for
        the shape coordinates).
    dtheta : tuple of ((int, int), value)
        (d theta)_ab at the point for a < b, where it was formed.
    """

    proof: str | None
    detail: str
    theta: tuple | None
    jacobiator: tuple
    point: str
    env: dict = field(default_factory=dict, compare=False, repr=False)
    dtheta: tuple = ()


def decide_at_a_point(eqs: VelocityEquations, system, seed: int = SEED) -> PointVerdict | None:
    """Decide the equations at one exact point (None where no exact point is found:
    a function without an exact value, or Omega_v degenerate at every point drawn).

    Parameters
    ----------
    eqs : VelocityEquations
    system : System
        For the parameters and their values.
    seed : int, optional

    Returns
    -------
    PointVerdict or None

    Examples
    --------
    The particle with a free coordinate w (k = 3): no solution, proved at a point.

    >>> from nhham import System
    >>> from nhham.lagrangian.chaplygin import chaplygin_reduction
    >>> system = System(["x", "y", "z", "w"], "(x_dot**2 + y_dot**2 + z_dot**2 + w_dot**2)/2",
    ...                 ["z_dot - y*x_dot"])
    >>> verdict = decide_at_a_point(velocity_equations(chaplygin_reduction(
    ...     system, symmetry=["z"])), system)
    >>> verdict.proof
    'no solution'
    """
    sampler = PointSampler(eqs.shape, eqs.velocities, system.parameters,
                           dict(system.parameter_values), (), (), seed,
                           circle=circle_parameters(system))
    n = 2 * eqs.k
    try:
        program = Program([e for row in eqs.A for e in row] + list(eqs.b))
    except NotExact:
        return None
    for _ in range(DRAWS):
        try:
            env = sampler.point().env
            values = program.run(env)
        except ZeroDivisionError:
            continue
        except NotExact:
            return None
        A = [values[t * n:(t + 1) * n] for t in range(len(eqs.A))]
        b = values[len(eqs.A) * n:]
        rank, rows, _ = exact_rank(A)
        if rank == n:
            try:
                return _verdict(eqs, env, A, b, rows)
            except ZeroDivisionError:
                continue
    return None


def _verdict(eqs, env, A, b, rows) -> PointVerdict:
    n, k = 2 * eqs.k, eqs.k
    z = eqs.variables
    where = _describe(env, z)
    jac = jacobiators(eqs, Program_at(env), _exact_inverse)
    jac = tuple((t, x) for t, x in jac if x)
    augmented = [list(row) + [x] for row, x in zip(A, b)]
    if exact_rank(augmented)[0] > n:
        with_dp = [t for t, tr in enumerate(eqs.triples) if max(tr) >= k]
        part = exact_rank([augmented[t] for t in with_dp])[0] > exact_rank(
            [A[t] for t in with_dp])[0]
        which = ("; already its components with a dp leg are: they make theta's dp part "
                 "vanish, and then theta_a W_bc - theta_b W_ac = dG_ab/dr'^c has no "
                 "solution" if part else "")
        reason = fibre_obstruction(eqs.shape, jac)
        which += f" ({reason} at the point)" if reason else ""
        return PointVerdict("no solution", f"inconsistent at an exact point where "
                            f"Omega_nh is nondegenerate{which}", None, jac, where, env)
    square = [A[t] for t in rows]
    theta = [x[0] for x in exact_solve(square, [[b[t]] for t in rows])]
    # With L_c quadratic in r' (the caller's condition) the next two cannot happen: the
    # dr^dr'^dr' rows force theta's dr' part to vanish (W invertible, k >= 2) and the
    # dr^dr^dr' rows, theta_a W_bc - theta_b W_ac = dG_ab/dr'^c, are free of r' (G is
    # affine in r'). They stay as proofs for any other L_c.
    if any(theta[k:]):
        return PointVerdict("dp part", "theta has a dp part at the exact point",
                            tuple(theta), jac, where, env)
    d = _derivatives(eqs, env, theta, rows, square)  # d[m][i] = d theta_i / d z_m there
    if any(d[m][i] for m in range(n) for i in range(n) if m >= k or i >= k):
        return PointVerdict("depends on p", "theta's dp part or the p-derivatives of its "
                            "coefficients are nonzero at the exact point",
                            tuple(theta), jac, where, env)
    curl = [(a, c, d[a][c] - d[c][a]) for a, c in itertools.combinations(range(k), 2)]
    if any(x for _, _, x in curl):
        shown = "; ".join(f"d{z[a]}^d{z[c]} = {short_number(x)}" for a, c, x in curl if x)
        return PointVerdict("not closed", f"d theta != 0 at an exact point ({shown}), "
                            f"where theta has no dp part and its coefficients no "
                            f"p-derivative", tuple(theta), jac, where, env,
                            tuple(((a, c), x) for a, c, x in curl))
    return PointVerdict(None, "nothing refuted at the exact point", tuple(theta),
                        jac, where, env, tuple(((a, c), x) for a, c, x in curl))


def short_number(x) -> str:
    """An exact value as a reader takes it in: itself when short, else its leading digits
    (a rational of 200 digits says no more than that it is not 0).

    >>> short_number(3) , short_number(__import__("fractions").Fraction(10**40 + 1, 3 * 10**39))
    ('3', '3.33333 (exact: a rational of 41/40 digits)')
    """
    text = str(x)
    if len(text) <= 24:
        return text
    try:
        num, den = (int(part) for part in text.split("/")) if "/" in text else (int(text), 1)
    except ValueError:  # not a rational's text (a value mod p): say what it is
        return f"{text[:12]}..."
    return f"{num / den:.6g} (exact: a rational of {len(str(abs(num)))}/{len(str(den))} digits)"


def fibre_obstruction(shape, found) -> str:
    """Why the equations with a dp leg fail, read off a nonzero Jacobiator, or "".

    With theta's dp part forced to vanish (k >= 2), the dr^a ^ dr^b ^ dp_c component of
    theta ^ Omega_nh = -d Omega_nh for c other than a, b reads 0 = dG_ab/dp_c, and
    dG_ab/dp_c is minus the Jacobiator of (r^c, p_a, p_b): one such Jacobiator that is
    not zero proves that the equations have no solution.

    Parameters
    ----------
    shape : sequence of sympy.Symbol
    found : sequence of (tuple of str, value)
        Jacobiators known not to vanish (identically, or at an exact point).

    Returns
    -------
    str

    Examples
    --------
    >>> import sympy as sp
    >>> print(fibre_obstruction(sp.symbols("yaw lean spin"),
    ...                         [(("lean", "p_yaw", "p_spin"), 1)])[:51])
    its dyaw^dspin^dp_lean component reads 0 = dG_(yaw,
    """
    names = [str(x) for x in shape]
    momenta = {str(momentum_symbol(x)): str(x) for x in shape}
    for triple, _ in found:
        c, pa, pb = triple
        if c in names and pa in momenta and pb in momenta and c not in (momenta[pa],
                                                                        momenta[pb]):
            a, b = momenta[pa], momenta[pb]
            pc = str(momentum_symbol(shape[names.index(c)]))
            return (f"its d{a}^d{b}^d{pc} component reads 0 = dG_({a}, {b})/d{pc}, but that "
                    f"derivative is minus the Jacobiator of ({c}, {pa}, {pb}), not zero")
    return ""


def _derivatives(eqs, env, theta, rows, square) -> list:
    """d theta / d z_m at the point, m over (r, r'), from the rows ``rows``."""
    z = eqs.variables
    exprs = []
    for m in z:
        for t in rows:
            exprs.append(sp.diff(eqs.b[t], m))
            exprs.extend(sp.diff(e, m) for e in eqs.A[t])
    values = Program(exprs).run(env)
    n, width = len(z), 1 + len(z)
    out = []
    for m in range(n):
        rhs = []
        for pos, t in enumerate(rows):
            chunk = values[(m * len(rows) + pos) * width:(m * len(rows) + pos + 1) * width]
            rhs.append([chunk[0] - sum((a * x for a, x in zip(chunk[1:], theta)), 0)])
        out.append([x[0] for x in exact_solve(square, rhs)])
    return out


def Program_at(env):
    """The values of sympy expressions at an exact point (a ``values`` for
    :func:`jacobiators`)."""
    return lambda exprs: Program(exprs).run(env)


def _exact_inverse(W):
    k = len(W)
    return exact_solve(W, [[1 if i == j else 0 for j in range(k)] for i in range(k)])


def jacobiators(eqs: VelocityEquations, values, inverse, triples=None) -> tuple:
    """(triple, value) of the Jacobiators of the (r, p) coordinate functions, composed
    with the Legendre map.

    The reduced bracket is Pi = [[0, 1], [-1, G(r, p)]] with G(r, p) = G(r, r'(r, p));
    its derivatives follow by the chain rule through dr'/dp = W^{-1} and
    dr'/dr|_p = -W^{-1} dp/dr, so nothing is inverted but W.

    Parameters
    ----------
    eqs : VelocityEquations
    values : callable
        sympy expressions -> their values: exact numbers at a point
        (:func:`Program_at`), or the expressions themselves (``list``) for closed forms
        in (r, r').
    inverse : callable
        W's values (list of rows) -> W^{-1} (list of rows).
    triples : sequence of tuple of str, optional
        The triples wanted (default: all).

    Returns
    -------
    tuple of (tuple of str, value)

    Examples
    --------
    The particle z' = y x': {p_x, p_y} = G_xy = y x' = y p_x/(1 + y^2), so the Jacobiator
    of (x, p_x, p_y) is -dG_xy/dp_x = -y/(1 + y^2).

    >>> import sympy as sp
    >>> from nhham import System
    >>> from nhham.lagrangian.chaplygin import chaplygin_reduction
    >>> eqs = velocity_equations(chaplygin_reduction(System(
    ...     ["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", ["z_dot - y*x_dot"])))
    >>> inverse = lambda W: sp.Matrix(W).inv().tolist()
    >>> found = jacobiators(eqs, list, inverse, [("x", "p_x", "p_y")])
    >>> found[0][0], sp.simplify(found[0][1])
    (('x', 'p_x', 'p_y'), -y/(y**2 + 1))
    """
    k, r, v = eqs.k, eqs.shape, eqs.velocities
    G, p = eqs.gyroscopic, eqs.momenta
    pairs = list(itertools.combinations(range(k), 2))
    exprs = [G[a, b] for a, b in pairs]
    exprs += [sp.diff(G[a, b], x) for a, b in pairs for x in r + v]
    exprs += [sp.diff(p[c], x) for c in range(k) for x in r]
    exprs += list(eqs.W)
    vals = list(values(exprs))
    g = {pair: vals[i] for i, pair in enumerate(pairs)}
    pos = len(pairs)
    dG = {}
    for pair in pairs:
        dG[pair] = vals[pos:pos + 2 * k]
        pos += 2 * k
    dpdr = [vals[pos + c * k:pos + (c + 1) * k] for c in range(k)]
    pos += k * k
    W = [vals[pos + i * k:pos + (i + 1) * k] for i in range(k)]
    Winv = inverse(W)
    dvdr = [[-sum((Winv[g_][c] * dpdr[c][d] for c in range(k)), 0) for d in range(k)]
            for g_ in range(k)]
    size = 2 * k

    def G_at(a, b):
        if a == b:
            return 0
        return g[(a, b)] if a < b else -g[(b, a)]

    def dG_at(a, b, m):  # d G_ab(r, p) / d z_m, z = (r, p)
        if a == b:
            return 0
        sign, pair = (1, (a, b)) if a < b else (-1, (b, a))
        row = dG[pair]
        if m < k:
            out = row[m] + sum((row[k + gm] * dvdr[gm][m] for gm in range(k)), 0)
        else:
            out = sum((row[k + gm] * Winv[gm][m - k] for gm in range(k)), 0)
        return sign * out

    def Pi(i, j):
        if i < k <= j:
            return 1 if j - k == i else 0
        if j < k <= i:
            return -1 if i - k == j else 0
        return G_at(i - k, j - k) if i >= k and j >= k else 0

    def dPi(j, l, m):
        return dG_at(j - k, l - k, m) if j >= k and l >= k else 0

    names = [str(x) for x in r] + [str(momentum_symbol(x)) for x in r]
    found = []
    for i, j, l in itertools.combinations(range(size), 3):
        triple = (names[i], names[j], names[l])
        if triples is not None and triple not in triples:
            continue
        value = -sum((Pi(i, m) * dPi(j, l, m) + Pi(j, m) * dPi(l, i, m)
                      + Pi(l, m) * dPi(i, j, m) for m in range(size)), 0)
        found.append((triple, value))
    return tuple(found)


def _describe(env, z) -> str:
    """The point's velocities and the tangent half-angles' circle points, short."""
    parts = []
    for s in z:
        x = env[s]
        if hasattr(x, "c"):
            parts.append(f"{s} = {x.r} with (cos, sin)({s}) = ({x.c}, {x.s})")
        else:
            parts.append(f"{s} = {x}")
    return "{" + ", ".join(parts) + "}"
