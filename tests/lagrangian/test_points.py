"""Exact points of M_1 (nhham.lagrangian.points): they satisfy the constraints exactly."""

import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.domains import ModP, NotExact, evaluate
from nhham.lagrangian.points import PointSampler

q1, q2 = sp.symbols("q1 q2")


def test_points_lie_on_the_constraints_exactly():
    """Dependent velocities solved exactly: every constraint vanishes at the point."""
    th, ph = sp.symbols("theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    X, Y = sp.symbols("x y")
    R = sp.Symbol("R")
    cons = [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd]
    sampler = PointSampler((X, Y, th, ph), (xd, yd, thd, phd), (R,), {}, (), cons, seed=3)
    for _ in range(3):
        pt = sampler.point()
        assert evaluate(cons, pt.env) == [0, 0]
    modular = PointSampler((X, Y, th, ph), (xd, yd, thd, phd), (R,), {}, (), cons, seed=3,
                           modular=True)
    assert evaluate(cons, modular.point().env) == [ModP(0), ModP(0)]


def test_holonomic_constraints_linear_in_a_coordinate_are_eliminated():
    q3 = sp.Symbol("q3")
    sampler = PointSampler((q1, q2, q3), (), (), {}, (q3 - q1 + q2,), (), seed=1)
    pt = sampler.point()
    (g,) = evaluate([q3 - q1 + q2], pt.env)
    assert g == 0
    with pytest.raises(NotExact):
        PointSampler((q1, q2), (), (), {}, (q1**2 + q2**2 - 1,), (), seed=1).point()


def test_parameter_values_are_taken_as_exact_decimals():
    m = sp.Symbol("m")
    sampler = PointSampler((q1,), (), (m,), {m: 0.1}, (), (), seed=1)
    assert sampler.point().env[m] == MPQ(1, 10)
