"""The polynomial-ring normal form modulo sin^2 + cos^2 = 1 (ring_fraction, trig_reduce)."""

import sympy as sp
from sympy.polys.rings import sring

from nhham.lagrangian.algebra import normal_form, ring_fraction, trig_reduce

t, u, a, b = sp.symbols("t u a b")


def test_trig_reduce_is_a_normal_form():
    """cos^2 -> 1 - sin^2: two polynomials equal modulo the identity reduce to the same one,
    with cos of degree at most 1."""
    e1 = sp.cos(t) ** 4 * a + sp.sin(t) * sp.cos(t) ** 3
    e2 = a * (1 - sp.sin(t) ** 2) ** 2 + sp.sin(t) * sp.cos(t) * (1 - sp.sin(t) ** 2)
    ring, (p1, p2) = sring([sp.expand(e1), sp.expand(e2)])
    r1, r2 = trig_reduce(p1), trig_reduce(p2)
    assert r1 == r2
    cos_index = ring.symbols.index(sp.cos(t))
    assert max(m[cos_index] for m in r1.monoms()) <= 1


def test_ring_fraction_cancels_what_only_the_identity_shows():
    """(a sin^2 + a cos^2 + b)(sin u) / ((a + b) sin u): the common factor a + b appears only
    after the reduction; two angles reduced independently."""
    e = (a * sp.sin(t) ** 2 + a * sp.cos(t) ** 2 + b) * sp.sin(u) * (sp.sin(u) ** 2
                                                                     + sp.cos(u) ** 2)
    num, den = ring_fraction(e / ((a + b) * sp.sin(u)))
    assert num.as_expr() / den.as_expr() == 1
    assert normal_form(sp.exp(t) + 1) == sp.exp(t) + 1          # opaque generators pass
    assert normal_form(sp.Integer(5)) == 5


def test_solve_for_coordinates_by_hand():
    """The one coordinate elimination: linear with a constant coefficient, repeatedly
    (x y - 1 becomes linear once y = 2 is known), velocities left alone, the rest kept."""
    from nhham.lagrangian.algebra import solve_for_coordinates

    x, y, z, xd = sp.symbols("x y z x_dot")
    sub, unsolved = solve_for_coordinates((x, y, z), [x * y - 1, y - 2, xd - z, z**2 - 1],
                                          skip={xd})
    assert sub == {y: 2, x: sp.Rational(1, 2)}
    assert unsolved == [xd - z, z**2 - 1]
    sub, unsolved = solve_for_coordinates((x, y), [x - 2 * y, y - 3, x - 6])
    assert sub == {x: 6, y: 3} and unsolved == []
