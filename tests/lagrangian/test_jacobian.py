"""The exact Jacobian of the reduced field (nhham.lagrangian.jacobian) against Jacobians
written down by hand from the equations of motion, with exact rational entries."""

import pytest
import sympy as sp

from nhham import System
from nhham.errors import InputError
from nhham.lagrangian.jacobian import exact_jacobian, exact_number

R = sp.Rational


def test_exact_numbers():
    """Floats are read as the decimal they print as; sympy numbers are kept."""
    assert exact_number(0.1) == R(1, 10) and exact_number(2.0) == 2
    assert exact_number(-1.25) == R(-5, 4)
    assert exact_number(sp.sqrt(2)) == sp.sqrt(2)


def test_a_particle_in_a_magnetic_field_and_a_spring():
    """L = (x'^2 + y'^2)/2 + B (x y' - y x')/2 - k (x^2 + y^2)/2 gives x'' = B y' - k x,
    y'' = -B x' - k y: linear, so J is the same matrix at every state, in the chart
    (x, y, x', y'): [[0, 0, 1, 0], [0, 0, 0, 1], [-k, 0, 0, B], [0, -k, -B, 0]]."""
    system = System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + B*(x*y_dot - y*x_dot)/2"
                                "- k*(x**2 + y**2)/2", parameters={"B": 0.5, "k": 3.0})
    J = exact_jacobian(system, {"x": 0.3, "y": -1, "x_dot": 2, "y_dot": 0.25},
                       {"B": 0.5, "k": 3.0}, ["x", "y", "x_dot", "y_dot"])
    B, k = R(1, 2), 3
    assert J.chart == ("x", "y", "x_dot", "y_dot")
    assert J.matrix == sp.Matrix([[0, 0, 1, 0], [0, 0, 0, 1], [-k, 0, 0, B], [0, -k, -B, 0]])
    # the accelerations at the state, exactly: (B y' - k x, -B x' - k y)
    assert J.accelerations == sp.Matrix([B * R(1, 4) - k * R(3, 10), -B * 2 + k])


def test_the_cartesian_pendulum_in_the_chart_of_x():
    """x^2 + y^2 = l^2 at the bottom (0, -l) at rest: with x the chart's coordinate the
    motion is x'' = -(g/l) x to first order, so J = [[0, 1], [-g/l, 0]] exactly
    (g = 49/5, l = 2: -49/10)."""
    system = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - m*g*y",
                    holonomic=["x**2 + y**2 - l**2"], parameters={"m": 1.5, "g": 9.8, "l": 2})
    J = exact_jacobian(system, {"x": 0, "y": -2, "x_dot": 0, "y_dot": 0},
                       {"m": 1.5, "g": 9.8, "l": 2}, ["x", "x_dot"])
    assert J.chart == ("x", "x_dot")
    assert J.matrix == sp.Matrix([[0, 1], [R(-49, 10), 0]])
    assert J.accelerations == sp.zeros(2, 1)


def test_a_chart_that_does_not_fit_is_refused():
    system = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - m*g*y",
                    holonomic=["x**2 + y**2 - l**2"], parameters={"m": 1.5, "g": 9.8, "l": 2})
    state, params = {"x": 0, "y": -2, "x_dot": 0, "y_dot": 0}, {"m": 1.5, "g": 9.8, "l": 2}
    with pytest.raises(InputError, match="unknown name"):
        exact_jacobian(system, state, params, ["x", "theta"])
    with pytest.raises(InputError, match="1 independent coordinates and 1 velocities"):
        exact_jacobian(system, state, params, ["x", "y", "x_dot"])
