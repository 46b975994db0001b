"""The image of the Legendre map of a singular Lagrangian: primary constraints and H_c.

Conventions (``DESIGN.md`` §2, "Singular Lagrangians"): for L at most quadratic in the
velocities, p = dL/dv = W(q) v + b(q). Where W has generic rank r < n, every vector k_a
of a basis of ker W (W k_a = 0) gives a primary constraint

    phi_a = k_a . (p - b)          (the v terms drop: k_a . W v = 0, exactly),

with the denominators of k_a cleared and the common factor of its entries taken out (so
that phi_a has a nonzero gradient wherever k_a is defined). The canonical Hamiltonian is
the energy at a velocity that Leg maps to p,

    H_c = E_L(q, v*),   W_IJ v*_J = (p - b)_I,  v*_A = 0 for A outside J,

for a regular r x r block (I, J) of W; on the primary surface it does not depend on the
block (E_L does not change along ker W at fixed p, since dE_L = v . dp - dL/dq dq there).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.errors import ValidationError
from nhham.lagrangian.algebra import cancel
from nhham.system.naming import momentum_symbol

__all__ = ["LegendreImage", "legendre_image"]


@dataclass(frozen=True)
class LegendreImage:
    """The primary constraints and the canonical Hamiltonian of a singular L (frozen).

    Attributes
    ----------
    coordinates, momenta : tuple of sympy.Symbol, length n
        q^A and p_A (``p_<q>``).
    rank : int
        r, the generic rank of W = d2L/dv dv.
    null_vectors : tuple of tuple of sympy.Expr
        A basis k_a of ker W (n - r vectors, entries in q), denominators cleared.
    constraints : tuple of sympy.Expr
        The primary constraints phi_a = k_a . (p - b), functions of (q, p).
    canonical_hamiltonian : sympy.Expr
        H_c(q, p), defined on the primary surface.
    block : tuple of tuple of int
        (I, J): the rows and columns of the regular block of W that H_c was formed with.
    rank_drops : tuple of sympy.Expr
        The factors of det W_IJ that are not constant: where one vanishes, rank W may be
        below ``rank`` (the primary constraints differ there; the chain answers for the
        generic rank, and a factor of the parameters alone is a case of ``--parametric``).

    Examples
    --------
    Christ-Lee in the plane: W = diag(1, 1, 0), p_xi = 0 is the primary constraint, and
    H_c = |p|^2/2 + xi (x1 p2 - x2 p1) + V.

    >>> from nhham import System
    >>> from nhham.hamiltonian.primary import legendre_image
    >>> s = System(["x1", "x2", "xi"], "((x1_dot + xi*x2)**2 + (x2_dot - xi*x1)**2)/2")
    >>> image = legendre_image(s)
    >>> image.rank, image.constraints
    (2, (p_xi,))
    >>> image.canonical_hamiltonian
    p_x1**2/2 - p_x1*x2*xi + p_x2**2/2 + p_x2*x1*xi
    """

    coordinates: tuple
    momenta: tuple
    rank: int
    null_vectors: tuple
    constraints: tuple
    canonical_hamiltonian: sp.Expr
    block: tuple
    rank_drops: tuple = ()


def legendre_image(system) -> LegendreImage:
    """The primary constraints phi_a(q, p) and H_c of ``system``'s Lagrangian.

    Parameters
    ----------
    system : nhham.System
        A Lagrangian at most quadratic in the velocities (W free of v).

    Returns
    -------
    LegendreImage

    Raises
    ------
    ValidationError
        ``lagrangian``: W depends on the velocities (L not quadratic in v) and is singular;
        the elimination of v that such an L needs is not built.

    Examples
    --------
    L = (q1' - q2)^2 / 2: p1 = q1' - q2, p2 = 0, so phi = p_q2 and H_c = p1^2/2 + p1 q2.

    >>> import sympy as sp
    >>> from nhham import System
    >>> from nhham.hamiltonian.primary import legendre_image
    >>> image = legendre_image(System(["q1", "q2"], "(q1_dot - q2)**2/2"))
    >>> image.constraints, sp.expand(image.canonical_hamiltonian)
    ((p_q2,), p_q1**2/2 + p_q1*q2)
    """
    q, v = tuple(system.coordinates), tuple(system.velocities)
    p = tuple(momentum_symbol(c) for c in q)
    L = system.lagrangian
    W = sp.Matrix(system.hessian)
    if W.free_symbols & set(v):
        return _eliminated(system, q, v, p)
    zero_v = {s: 0 for s in v}
    b = sp.Matrix([sp.diff(L, s) for s in v]).xreplace(zero_v)
    null = W.nullspace(simplify=True)
    vectors = tuple(_cleared(k) for k in null)
    shifted = sp.Matrix(p) - b
    phis = tuple(_primitive(cancel(sum((k[A] * shifted[A] for A in range(len(q))), sp.S.Zero)))
                 for k in vectors)
    rank = len(q) - len(vectors)
    rows, cols = _regular_block(W, rank)
    vstar = dict(zero_v)
    if rank:
        sol = W.extract(rows, cols).LUsolve(shifted.extract(rows, [0]))
        for j, c in enumerate(cols):
            vstar[v[c]] = cancel(sol[j])
    energy = sum((s * sp.diff(L, s) for s in v), sp.S.Zero) - L
    Hc = cancel(sp.expand(energy.xreplace(vstar)))
    drops: tuple = ()
    if rank:
        det = sp.numer(sp.together(cancel(W.extract(rows, cols).det(method="berkowitz"))))
        drops = tuple(f for f, _ in sp.factor_list(det)[1] if f.free_symbols)
    return LegendreImage(coordinates=q, momenta=p, rank=rank, null_vectors=vectors,
                         constraints=phis, canonical_hamiltonian=Hc,
                         block=(tuple(rows), tuple(cols)), rank_drops=drops)


def _eliminated(system, q, v, p) -> LegendreImage:
    """The image of Leg for an L algebraic in v but not quadratic: each square root of an
    expression in v is a new unknown s (s^2 = its radicand, s != 0), the equations
    p = dL/dv and e = E_L are cleared of denominators (each != 0), and a lex Groebner basis
    eliminates v, s (and the inverses that say "!= 0"): its elements free of them and of e
    are the primary constraints, the one linear in e gives H_c."""
    L = system.lagrangian
    roots: dict = {}

    def algebraic(expr):
        expr = sp.sympify(expr)
        for node in sp.preorder_traversal(expr):
            if isinstance(node, sp.Pow) and node.exp.is_Rational and node.exp.q == 2 \
                    and node.base.free_symbols & set(v) and node.base not in roots:
                roots[node.base] = sp.Dummy(f"s{len(roots)}")
        out = expr
        for base, s in roots.items():
            out = out.xreplace({sp.sqrt(base): s, 1 / sp.sqrt(base): 1 / s})
            out = out.replace(lambda e, b=base: isinstance(e, sp.Pow) and e.base == b
                              and e.exp.is_Rational and e.exp.q == 2,
                              lambda e, s=s: s ** int(2 * e.exp))
        return sp.together(out)

    e = sp.Dummy("e")
    energy = sum((s * sp.diff(L, s) for s in v), sp.S.Zero) - L
    exprs = [algebraic(pa - sp.diff(L, s)) for pa, s in zip(p, v)] + [algebraic(e - energy)]
    eqs, nonzero = [], list(roots.values())
    for x in exprs:
        num, den = sp.fraction(x)
        eqs.append(sp.expand(num))
        nonzero += [f for f, _ in sp.factor_list(den)[1] if f.free_symbols & (set(v) | set(roots.values()))]
    eqs += [sp.expand(s**2 - base) for base, s in roots.items()]
    if any(not x.is_polynomial(*v, *roots.values()) for x in eqs):
        raise ValidationError([
            "lagrangian: W depends on the velocities and L is not algebraic in them (square "
            "roots and fractions only): the primary constraints cannot be found by "
            "elimination"])
    inverses = [sp.Dummy(f"w{i}") for i in range(len(nonzero))]
    eqs += [sp.expand(1 - w * f) for w, f in zip(inverses, nonzero)]
    hidden = inverses + list(v) + list(roots.values())
    basis = sp.groebner(eqs, *hidden, e, *p, order="lex").exprs
    free = [g for g in basis if not g.free_symbols & set(hidden)]
    phis = tuple(_primitive(g) for g in free if e not in g.free_symbols)
    energies = [g for g in free if e in g.free_symbols and sp.degree(g, e) == 1]
    if not energies:
        raise ValidationError([
            "lagrangian: the energy E_L is not a function of (q, p) on the image of Leg "
            "found by elimination (no element linear in it)"])
    g = energies[0]
    c = sp.diff(g, e)
    Hc = cancel(-(g - c * e) / c)
    return LegendreImage(coordinates=q, momenta=p, rank=len(q) - len(phis), null_vectors=(),
                         constraints=phis, canonical_hamiltonian=Hc, block=((), ()))


def _cleared(k) -> tuple:
    """The null vector ``k`` times its common denominator, divided by the gcd of its
    entries: a polynomial vector with no common zero of its entries."""
    entries = [sp.together(cancel(e)) for e in k]
    den = sp.lcm_list([sp.denom(e) for e in entries]) if entries else sp.S.One
    nums = [cancel(e * den) for e in entries]
    g = sp.gcd_list([e for e in nums if e != 0]) if any(nums) else sp.S.One
    return tuple(cancel(e / g) for e in nums)


def _primitive(expr) -> sp.Expr:
    """``expr``'s numerator without a numerical content (p_y - B x, not 2 p_y - 2 B x)."""
    num = sp.expand(sp.numer(sp.together(expr)))
    content, prim = sp.primitive(num)
    return prim if content != 0 else num


def _regular_block(W: sp.Matrix, rank: int) -> tuple[list, list]:
    """Rows and columns of a generically regular rank x rank block of W (pivots of its
    row-reduced forms)."""
    if rank == 0:
        return [], []
    _, cols = W.rref(simplify=True)
    _, rows = W.T.rref(simplify=True)
    return list(rows)[:rank], list(cols)[:rank]
