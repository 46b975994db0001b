"""First-class combinations with coefficients reduced on M_f (``DESIGN.md`` §2).

The coefficients c_a of a first-class combination gamma_k = sum_a c_a chi_a matter only
on M_f ({gamma_k, chi_b} = sum_a c_a {chi_a, chi_b} there, whatever c_a is off M_f). So
they are formed where M_f is simplest, on TQ in the independent velocities, and only then
written in (q, p):

* the bracket B_ab = {chi_a, chi_b} pulled back to TQ is
  B = J_q U - (J_q U)^T - U^T (M - M^T) U with U = W^{-1} J_v^T, J_q and J_v the
  derivatives of the constraints in q and v and M_AB = d^2 L / dv^A dq^B; with
  Y = delta W^{-1} J_v^T (:func:`nhham.lagrangian.adjugate.scaled_inverse`, no inverse
  written) E = delta (J_q Y - (J_q Y)^T) - Y^T (M - M^T) Y = delta^2 B;
* on M_f the dependent velocities (and the coordinates solved from holonomic
  constraints) are substituted (:class:`nhham.lagrangian.submanifold.Submanifold`), times
  the common denominator D of the substitution, so that D E is a polynomial in the
  parameters, sines and cosines and the independent velocities; every product is reduced
  modulo sin^2 + cos^2 = 1;
* the kernel of D E on R + {k} (R the maximal second-class set) is spanned by its signed
  sub-Pfaffians (:mod:`nhham.hamiltonian.combinations`); the factors of delta they share
  are divided out and c_a = c'_a / c'_k is cancelled;
* the independent velocities v_I are written in (q, p) on M_f from n - m of the momenta
  p = dL/dv (those of v_I themselves when that block of W N is invertible, N the
  solved velocities' dependence on v_I): a left inverse valid on M_f, which is all the
  coefficients need; gamma_k = sum_a c_a (chi_a o Leg^{-1}) is given as that sum.

On the segway (n = 6, m = 3) the coefficients have a few hundred characters (the
combination formed without the reduction: 56,000 and 30,000). Where the reduction does not
apply (a final constraint not affine in v, M_f not solved exactly, L not quadratic in v)
:class:`~nhham.hamiltonian.combinations.NotFormed` is raised and the caller forms the
combinations without it.
"""

from __future__ import annotations

import itertools
import random
import time

import sympy as sp
from sympy.polys.rings import sring

from nhham.errors import ComputationError
from nhham.hamiltonian.combinations import TIME_LIMIT, NotFormed
from nhham.lagrangian.adjugate import scaled_inverse
from nhham.lagrangian.algebra import POLYNOMIAL_ERRORS, cancel, trig_normal, trig_reduce
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED
from nhham.system.naming import momentum_symbol

__all__ = ["reduced_combinations"]

#: Row sets of W N tried for the momenta that give the independent velocities.
MAX_ROW_SETS = 64


def reduced_combinations(system, constraints, second_class, time_limit: float = TIME_LIMIT):
    """The first-class combinations gamma_k (k outside ``second_class``), their
    coefficients reduced on M_f and written in (q, p).

    Parameters
    ----------
    system : System
        With L quadratic in the velocities.
    constraints : sequence of sympy.Expr
        The final constraints chi_a on TQ, each affine in the velocities.
    second_class : sequence of int
        A maximal second-class set R (B_RR invertible on M_f).
    time_limit : float
        Give up (NotFormed) after this many seconds of CPU time.

    Returns
    -------
    (tuple of sympy.Expr, tuple of dict)
        gamma_k for each k not in R, and its coefficients ``{index: c_a}`` (c_k = 1), as
        expressions in (q, p); the coefficients are those of gamma_k on M_f.

    Raises
    ------
    NotFormed
        Where the reduction does not apply (see the module docstring) or out of time.

    Examples
    --------
    A particle in the plane with a heading angle theta and the constraint
    y_dot = x_dot theta (n = 3, m = 1, M_f = M_1): one constraint, first class by itself.

    >>> from nhham import System
    >>> x, y, th = sp.symbols("x y theta")
    >>> xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    >>> s = System([x, y, th], (xd**2 + yd**2 + thd**2) / 2, [yd - th * xd])
    >>> gammas, coeffs = reduced_combinations(s, [yd - th * xd], [])
    >>> gammas[0], coeffs
    (-p_x*theta + p_y, ({0: 1},))
    """
    deadline = time.process_time() + time_limit
    chis = [sp.sympify(c) for c in constraints]
    R = list(second_class)
    q, v = list(system.coordinates), list(system.velocities)
    L = system.lagrangian
    W = sp.hessian(L, v)
    if any(e.free_symbols & set(v) for e in W):
        raise NotFormed("L is not quadratic in the velocities")
    Jv = sp.Matrix([[sp.diff(c, s) for s in v] for c in chis])
    if any(e.free_symbols & set(v) for e in Jv):
        raise NotFormed("a final constraint is not affine in the velocities")
    manifold = Submanifold(system, chis)
    if manifold.reduction.residual:
        raise NotFormed("M_f is not solved exactly for its dependent variables")
    sub = {s: _tidy(e) for s, e in manifold.reduction.substitution.items()}
    try:
        inverse = scaled_inverse(W, q + v)
    except ComputationError as exc:
        raise NotFormed(str(exc)) from None
    free = [s for s in v if s not in sub]
    coefficients = _coefficients(system, chis, R, sub, inverse, Jv, deadline)
    to_p = _velocities_in_momenta(system, sub, free)
    momenta = [momentum_symbol(s) for s in q]
    transported = _transport(system, chis, inverse, momenta)
    gammas, out = [], []
    for c in coefficients:
        c = {a: _in_momenta(e, to_p) for a, e in c.items()}
        _check_time(deadline)
        out.append(c)
        gammas.append(sp.Add(*[c[a] * transported[a] for a in sorted(c)]))
    return tuple(gammas), tuple(out)


def _trig(expr) -> sp.Expr:
    """A small expression reduced modulo sin^2 + cos^2 = 1 (sin(psi)^2 + cos(psi)^2 of
    the solved velocities)."""
    expr = sp.sympify(expr)
    return (trig_normal(expr) or expr) if expr.has(sp.sin, sp.cos) else expr


def _check_time(deadline) -> None:
    if time.process_time() > deadline:
        raise NotFormed("not formed within the CPU time of a closed form")


def _tidy(expr) -> sp.Expr:
    """Cancelled and reduced modulo sin^2 + cos^2 = 1, factored when that is shorter."""
    expr = cancel(sp.sympify(expr))
    if expr.has(sp.sin, sp.cos):
        expr = cancel(trig_normal(expr) or expr)
    try:
        factored = sp.factor(expr)
    except POLYNOMIAL_ERRORS:
        return expr
    return factored if sp.count_ops(factored) < sp.count_ops(expr) else expr


def _ring(exprs):
    """(ring, elements): ``exprs`` as polynomials in their generators, every sine with its
    cosine, each reduced modulo sin^2 + cos^2 = 1."""
    exprs = list(exprs)
    angles = {f.args[0] for e in exprs for f in sp.sympify(e).atoms(sp.sin, sp.cos)}
    extra = [f(u) for u in sorted(angles, key=sp.default_sort_key) for f in (sp.sin, sp.cos)]
    try:
        ring, polys = sring(exprs + extra)
    except POLYNOMIAL_ERRORS as exc:
        raise NotFormed(f"not polynomial in its generators ({exc})") from None
    return ring, [trig_reduce(p) for p in polys[:len(exprs)]]


#: Largest product of two polynomials (terms of the one times terms of the other) the
#: reduction forms before giving up: past it the reduced form is not the small one it is
#: for (a 3-link snake's products run to millions of terms; the segway's to hundreds).
PRODUCT_TERMS = 20000


def _dot(row, col, zero, deadline=None):
    total = zero
    for x, y in zip(row, col):
        if not (x and y):
            continue
        if len(x) * len(y) > PRODUCT_TERMS:
            raise NotFormed(f"a product of {len(x)} by {len(y)} terms: not a small form")
        total += x * y
        if deadline is not None:
            _check_time(deadline)
    if len(total) > PRODUCT_TERMS:
        raise NotFormed(f"a sum of {len(total)} terms: not a small form")
    return trig_reduce(total)


def _coefficients(system, chis, R, sub, inverse, Jv, deadline) -> list:
    """[{a: c_a}] for each k outside R, in (q, v_I) on M_f (c_k = 1)."""
    q, v = list(system.coordinates), list(system.velocities)
    L, k, n = system.lagrangian, len(chis), len(v)
    denominators = [sp.fraction(sp.together(e))[1] for e in sub.values()]
    D = sp.lcm_list(denominators) if denominators else sp.S.One
    moved = {s: e for s, e in sub.items() if s in set(q)}   # coordinates solved on M_f

    def on_mf(e):
        return sp.expand(D * e.xreplace(sub))

    Jq = [on_mf(sp.diff(c, s)) for c in chis for s in q]
    M = sp.Matrix(n, n, lambda a, b: sp.diff(L, v[a], q[b]))
    Om = [on_mf(M[i, j] - M[j, i]) for i in range(n) for j in range(n)]
    S = [e.xreplace(moved) if moved else e for e in inverse.matrix()]
    J = [e.xreplace(moved) if moved else e for e in Jv]
    ring, polys = _ring([inverse.scale.xreplace(moved)] + S + J + Jq + Om)
    d, polys = polys[0], polys[1:]
    Sr = [polys[i * n:(i + 1) * n] for i in range(n)]
    polys = polys[n * n:]
    Jvr = [polys[a * n:(a + 1) * n] for a in range(k)]
    polys = polys[k * n:]
    Jr = [polys[a * n:(a + 1) * n] for a in range(k)]
    polys = polys[k * n:]
    Or = [polys[i * n:(i + 1) * n] for i in range(n)]
    zero = ring.zero
    Y = [[_dot(Sr[i], Jvr[b], zero, deadline) for b in range(k)] for i in range(n)]   # delta W^-1 J_v^T
    Ycols = [[Y[i][b] for i in range(n)] for b in range(k)]
    JY = [[_dot(Jr[a], Ycols[b], zero, deadline) for b in range(k)] for a in range(k)]
    OY = [[_dot(Or[i], Ycols[b], zero, deadline) for b in range(k)] for i in range(n)]
    _check_time(deadline)
    E: dict = {}

    def entry(a, b):
        if (a, b) not in E:
            E[a, b] = trig_reduce(d * (JY[a][b] - JY[b][a])
                                  - _dot(Ycols[a], [OY[i][b] for i in range(n)], zero))
            E[b, a] = -E[a, b]
        return E[a, b]

    out = []
    for kk in (i for i in range(k) if i not in R):
        idx = R + [kk]
        c = {a: (-1) ** (len(idx) - 1 - i) * _pfaffian(
            [[entry(x, y) for y in idx if y != a] for x in idx if x != a], ring)
            for i, a in enumerate(idx)}
        if not c[kk]:
            raise NotFormed("the bracket block of the second-class set vanishes identically")
        c = _divided(c, d)
        _check_time(deadline)
        coeffs = {}
        for a in sorted(idx):
            if not c[a]:
                continue
            num, den = c[a].cancel(c[kk])
            coeffs[a] = _factored(num) / _factored(den)
        out.append(coeffs)
    return out


def _factored(poly) -> sp.Expr:
    """A ring element as the product of its irreducible factors (shorter to read)."""
    if poly.is_ground:
        return poly.as_expr()
    content, factors = poly.factor_list()
    return sp.Mul(content.as_expr() if hasattr(content, "as_expr") else content,
                  *[f.as_expr() ** e for f, e in factors])


def _pfaffian(rows, ring):
    """The Pfaffian of an antisymmetric matrix of ring elements (1 when empty)."""
    n = len(rows)
    if n == 0:
        return ring.one
    if n % 2:
        return ring.zero
    total = ring.zero
    for j in range(1, n):
        if rows[0][j]:
            keep = [i for i in range(1, n) if i != j]
            total += (-1) ** (j - 1) * rows[0][j] * _pfaffian(
                [[rows[x][y] for y in keep] for x in keep], ring)
    return trig_reduce(total)


def _divided(c: dict, delta) -> dict:
    """The c'_a divided by delta as long as it divides all of them (E = delta^2 B: the
    sub-Pfaffians share powers of delta; a trial division, no gcd of large polynomials)."""
    if delta.is_ground:
        return c
    while all(not x or x.rem(delta) == 0 for x in c.values()):
        c = {a: (x.exquo(delta) if x else x) for a, x in c.items()}
    return c


def _velocities_in_momenta(system, sub, free) -> dict:
    """{v_I: expression in (q, p)} on M_f, from n - m of the momenta p = dL/dv at the
    solved velocities (the rows of v_I themselves first)."""
    if not free:
        return {}
    q, v = list(system.coordinates), list(system.velocities)
    grad = [sp.expand(sp.diff(system.lagrangian, s).xreplace(sub)) for s in v]
    P = sp.Matrix([[_trig(sp.diff(g, s)) for s in free] for g in grad])
    p0 = [_trig(g.xreplace({s: 0 for s in free})) for g in grad]
    momenta = [momentum_symbol(s) for s in q]
    own = [v.index(s) for s in free]
    candidates = itertools.chain([own], itertools.islice(
        itertools.combinations(range(len(v)), len(free)), MAX_ROW_SETS))
    rng = random.Random(SEED)
    point = {s: sp.Rational(rng.randint(1, 997), rng.randint(101, 307))
             for s in P.free_symbols}
    for rows in candidates:
        block = P.extract(list(rows), list(range(len(free))))
        # invertible where its determinant is nonzero at a random point (a proof of
        # generic invertibility; the left inverse is valid wherever the block is)
        if abs(sp.N(block.xreplace(point).det(), 30)) < 1e-20:
            continue
        rhs = sp.Matrix([momenta[i] - p0[i] for i in rows])
        solved = block.LUsolve(rhs)
        return {s: sp.factor_terms(cancel(e)) for s, e in zip(free, solved)}
    raise NotFormed("no block of the momenta gives the independent velocities")


def _in_momenta(expr, to_p) -> sp.Expr:
    """A coefficient in (q, v_I) written in (q, p): each factor with v_I substituted."""
    if not expr.free_symbols & set(to_p):
        return expr
    return sp.Mul(*[sp.factor_terms(sp.together(f.xreplace(to_p))) ** e if f.free_symbols
                    & set(to_p) else f ** e for f, e in
                    (x.as_base_exp() for x in sp.Mul.make_args(expr))])


def _transport(system, chis, inverse, momenta) -> list:
    """chi_a o Leg^{-1} = (J_v chi_a . delta W^{-1} (p - dL/dv at v = 0) + delta h_a) /
    delta (chi_a = J_v chi_a . v + h_a), in the ring, cancelled with delta."""
    v = list(system.velocities)
    n, zero = len(v), {s: 0 for s in v}
    a = [sp.diff(system.lagrangian, s).xreplace(zero) for s in v]
    Jv = [sp.diff(c, s) for c in chis for s in v]
    h = [c.xreplace(zero) for c in chis]
    ring, polys = _ring([inverse.scale] + list(inverse.matrix()) + Jv + h
                        + [p - x for p, x in zip(momenta, a)])
    d, polys = polys[0], polys[1:]
    S = [polys[i * n:(i + 1) * n] for i in range(n)]
    polys = polys[n * n:]
    J = [polys[i * n:(i + 1) * n] for i in range(len(chis))]
    polys = polys[len(chis) * n:]
    h, rhs = polys[:len(chis)], polys[len(chis):]
    Sp = [_dot(S[i], rhs, ring.zero) for i in range(n)]
    out = []
    for Ja, ha in zip(J, h):
        num, den = trig_reduce(_dot(Ja, Sp, ring.zero) + d * ha).cancel(d)
        out.append(num.as_expr() / _factored(den))
    return out
