"""A Lagrangian read as a polynomial in the velocities (nhham.system.velocities): the
quadratic parts L = v.W.v/2 + b.v - V, read term by term and compared with the parts
written by hand, and what is not a polynomial of degree 2."""

import pytest
import sympy as sp

from nhham.system.velocities import quadratic_parts, velocity_free_part, velocity_polynomial


def test_quadratic_parts_read_W_b_V():
    x, y = sp.symbols("x y")
    xd, yd = sp.symbols("x_dot y_dot")
    a = sp.Symbol("a")
    L = (1 + x**2) * (xd + a * yd) ** 2 / 2 + sp.sin(y) * xd - sp.cos(x) * y
    parts = quadratic_parts(L, (xd, yd))
    W = sp.Matrix([[1 + x**2, a * (1 + x**2)], [a * (1 + x**2), a**2 * (1 + x**2)]])
    assert sp.expand(sp.Matrix(parts.W) - W) == sp.zeros(2, 2)
    assert parts.b == (sp.sin(y), 0)
    assert sp.expand(parts.V - sp.cos(x) * y) == 0


@pytest.mark.parametrize("L", ["sin(x_dot)", "x_dot**3", "x_dot**2 * y_dot", "1/x_dot",
                               "sqrt(x_dot**2 + 1)", "exp(x*x_dot)", "Abs(x_dot)**2"])
def test_non_quadratic_lagrangians_take_the_general_path(L):
    x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    expr = sp.sympify(L, locals={"x_dot": xd, "y_dot": yd, "x": x})
    assert velocity_polynomial(expr, (xd, yd), 2) is None
    assert quadratic_parts(expr, (xd, yd)) is None


def test_velocity_polynomial_keeps_degree_before_cancellation_out():
    xd, yd, x = sp.symbols("x_dot y_dot x")
    poly = velocity_polynomial((xd + x) * (xd - x) - xd**2 + yd * sp.cos(x), (xd, yd), 2)
    assert poly == {(): -x**2, (1,): sp.cos(x)}
    assert velocity_polynomial(xd * yd, (xd, yd), 1) is None


def test_velocity_free_part_is_phi_at_v_zero():
    """h = phi(q, 0) read off the terms, against substituting v = 0: affine constraints
    (the snake's, a sleigh's with an offset), and a Chetaev one (v^2: substituted)."""
    q, r, qd, rd, a = sp.symbols("q r q_dot r_dot a")
    vels = [qd, rd]
    for phi in (sp.sin(q - r) * qd + a * sp.cos(r) * (rd - qd),
                (a + qd) * sp.sin(q) - sp.cos(r) * (1 - rd) + a ** 2,
                qd ** 2 + rd ** 2 - a * sp.sin(q), sp.Integer(3)):
        got = velocity_free_part(phi, vels)
        assert sp.expand(got - phi.subs({qd: 0, rd: 0})) == 0, phi
        assert not got.free_symbols & set(vels)
