"""``[initial]`` with the dependent values left out: nhham solves them (issue 34, item 4).

Expected values by hand. The rolling disk: x' = R cos(theta) phi', y' = R sin(theta) phi'.
A particle on the sphere x^2 + y^2 + z^2 = R^2 (curved M_1): z = +-sqrt(R^2 - x^2 - y^2),
and the time derivative 2 (x x' + y y' + z z') = 0 gives z' = -(x x' + y y') / z.
"""

from __future__ import annotations

import math

import pytest

from nhham.errors import (
    InconsistentInitialDataError,
    InputError,
    MissingParameterValueError,
    ParseError,
)
from nhham.system.initial import check_initial
from nhham.system.scene import loads_scene

DISK = """name = "vertical rolling disk"
coordinates = ["x", "y", "theta", "phi"]
parameters = { m = 1.0, I1 = 0.5, I2 = 0.25, R = 0.5, v0 = 2.0 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"
constraints = ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"]

[initial]
x = 0.0
y = 0.0
phi = 0.0
"""

SPHERE = """name = "particle on a sphere"
coordinates = ["x", "y", "z"]
parameters = { R = 2.0 }
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2 - z"
holonomic = ["x**2 + y**2 + z**2 - R**2"]

[initial]
x = 1.0
y = 1.0
x_dot = 1.0
y_dot = 0.0
"""


def disk(entries: str, **kw):
    return loads_scene(DISK + entries, **kw)


def test_the_dependent_velocities_of_the_disk_are_solved():
    """theta = pi/4, phi' = v0/R = 4: x' = y' = R cos(pi/4) phi' = sqrt(2)."""
    scene = disk('theta = "pi/4"\ntheta_dot = 1.0\nphi_dot = "v0/R"\n')
    assert scene.initial_solved == ("x_dot", "y_dot")
    assert scene.initial["phi_dot"] == 4.0 and scene.initial["theta"] == math.pi / 4
    assert scene.initial["x_dot"] == pytest.approx(math.sqrt(2), rel=1e-14)
    assert scene.initial["y_dot"] == pytest.approx(math.sqrt(2), rel=1e-14)
    assert max(abs(r) for r in check_initial(scene).values()) < 1e-14
    assert list(scene.initial) == ["x", "y", "theta", "phi", "x_dot", "y_dot", "theta_dot",
                                   "phi_dot"]


def test_the_rolling_rate_is_solved_from_the_velocity_given():
    """theta = 0, x' = 2 given: phi' = x' / (R cos 0) = 4, y' = R sin 0 phi' = 0."""
    scene = disk("theta = 0.0\ntheta_dot = 1.0\nx_dot = 2.0\n")
    assert scene.initial_solved == ("y_dot", "phi_dot")
    assert scene.initial["phi_dot"] == pytest.approx(4.0, rel=1e-14)
    assert scene.initial["y_dot"] == pytest.approx(0.0, abs=1e-15)


def test_velocities_given_that_are_not_independent_are_refused_by_name():
    """x' and phi' are related by constraints[0]; theta' is in no constraint."""
    with pytest.raises(InputError) as info:
        disk("theta = 0.0\nx_dot = 2.0\nphi_dot = 4.0\n")
    assert str(info.value) == (
        "initial: theta_dot is not fixed by the constraints and the velocities given: give "
        "its value; the velocities given are not independent (constraints[0] relates "
        "phi_dot, x_dot): leave one of each out")
    assert info.value.key == "initial"


def test_velocities_that_over_determine_inconsistently_are_refused():
    """x' = 2.5 with phi' = 4, R = 1/2, theta = 0: constraints[0] = 2.5 - 2 = 0.5."""
    with pytest.raises(InconsistentInitialDataError) as info:
        disk("theta = 0.0\ntheta_dot = 1.0\nx_dot = 2.5\nphi_dot = 4.0\n")
    assert str(info.value) == (
        "initial: the velocities given over-determine y_dot: constraints[0] = 0.5 with them "
        "solved; the velocities given are not independent (constraints[0] relates phi_dot, "
        "x_dot): leave one of each out")


def test_a_velocity_solved_where_its_constraint_is_not_real_is_refused_by_name():
    """sqrt(x) x' + y' = 0 at x = -2: the coefficient is i sqrt(2), so no real x' solves
    it (float() of a complex number: an internal error)."""
    text = """coordinates = ["x", "y"]
lagrangian = "(x_dot**2 + y_dot**2)/2"
constraints = ["sqrt(x)*x_dot + y_dot"]
[initial]
x = -2.0
y = 0.0
y_dot = 1.0
"""
    with pytest.raises(InconsistentInitialDataError) as info:
        loads_scene(text)
    assert str(info.value).startswith(
        "initial: constraints[0] is not a finite real number at the initial state (one of "
        "its coefficients is 1.41421*I)")
    assert info.value.key == "initial"
    scene = loads_scene(text.replace("x = -2.0", "x = 4.0"))   # x' = -y'/sqrt(4) = -1/2
    assert scene.initial["x_dot"] == pytest.approx(-0.5, rel=1e-14)


def test_a_constraint_undefined_at_the_initial_state_is_refused_by_name():
    """atan2(y, 1/x) at x = 0, y = 0: sympy's atan2 of (0, zoo) compares NaN and raises a
    TypeError (an internal error of the command)."""
    text = """coordinates = ["x", "y"]
lagrangian = "(x_dot**2 + y_dot**2)/2"
constraints = ["x_dot + atan2(y, 1/x)*y_dot"]
[initial]
x = 0.0
y = 0.0
x_dot = 1.0
"""
    with pytest.raises(InconsistentInitialDataError,
                       match=r"^initial: constraints\[0\] is not a finite real number at the "
                             r"initial state"):
        loads_scene(text)


def test_loading_without_the_check_keeps_the_problem_for_where_the_data_are_used():
    scene = disk("theta = 0.0\nx_dot = 2.0\nphi_dot = 4.0\n", check_initial=False)
    assert scene.initial is None and scene.system.n == 4
    with pytest.raises(InputError, match="theta_dot is not fixed"):
        scene.checked_initial()


def test_a_value_needs_the_parameters_it_uses():
    text = DISK.replace(", v0 = 2.0 }", ' }\nsymbolic_parameters = ["v0"]')
    scene = loads_scene(text + 'theta = 0.0\ntheta_dot = 1.0\nphi_dot = "v0/R"\n',
                        check_initial=False)
    with pytest.raises(MissingParameterValueError) as info:
        scene.checked_initial()
    assert info.value.key == "initial.phi_dot" and "'v0'" in str(info.value)


def test_a_value_may_not_use_a_coordinate():
    with pytest.raises(ParseError) as info:
        disk('theta = 0.0\ntheta_dot = "x"\nphi_dot = 1.0\n').checked_initial()
    assert "initial.theta_dot: unknown name 'x'" in str(info.value)


def test_a_coordinate_left_out_needs_a_holonomic_constraint():
    with pytest.raises(InputError, match="initial: no value for theta: only coordinates that "
                                         "holonomic constraints determine may be left out"):
        disk("theta_dot = 1.0\nphi_dot = 1.0\n")


def test_a_guess_does_not_change_a_velocity_solved_exactly():
    """x' = R cos(0) phi' = 0.5 whatever the guess: it enters its constraint linearly."""
    scene = disk("theta = 0.0\ntheta_dot = 1.0\nphi_dot = 1.0\nx_dot = { guess = 7.0 }\n")
    assert scene.initial["x_dot"] == 0.5 and scene.initial["y_dot"] == 0.0


ISOKINETIC = """name = "isokinetic particle"
coordinates = ["x", "y"]
parameters = { m = 1.0, g = 9.81, c = 2.0 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 - m*g*y"
constraints = ["x_dot**2 + y_dot**2 - c**2"]

[initial]
x = 0.0
y = 0.0
x_dot = 1.2
"""


@pytest.mark.parametrize("guess, sign", [(1.0, 1), (-3.0, -1)])
def test_a_velocity_inside_a_nonlinear_constraint_is_solved_from_its_guess(guess, sign):
    """x'^2 + y'^2 = c^2 with x' = 1.2, c = 2: y' = +-1.6 (the branch of the guess)."""
    scene = loads_scene(ISOKINETIC + f"y_dot = {{ guess = {guess} }}\n")
    assert scene.initial_solved == ("y_dot",)
    assert scene.initial["y_dot"] == pytest.approx(sign * 1.6, rel=1e-14)


def test_a_velocity_inside_a_nonlinear_constraint_without_a_guess_asks_for_one():
    with pytest.raises(InputError) as info:
        loads_scene(ISOKINETIC)
    assert "y_dot enters constraints[0] nonlinearly" in str(info.value)
    assert "y_dot = { guess = 1.0 }" in str(info.value)


def test_a_speed_beyond_the_constraint_has_no_velocity_to_solve():
    """x' = 2.5 > c = 2: x'^2 + y'^2 = 4 has no real y'."""
    with pytest.raises(InconsistentInitialDataError, match="found no velocities y_dot"):
        loads_scene(ISOKINETIC.replace("x_dot = 1.2", "x_dot = 2.5")
                    + "y_dot = { guess = 1.0 }\n")


@pytest.mark.parametrize("guess, sign", [(1.0, 1), (-0.5, -1)])
def test_a_coordinate_on_the_sphere_is_solved_from_the_guess(guess, sign):
    """x = y = 1, R = 2: z = +-sqrt(2) (the branch of the guess), z' = -(x x')/z."""
    scene = loads_scene(SPHERE + f"z = {{ guess = {guess} }}\n")
    assert scene.initial_solved == ("z", "z_dot")
    assert scene.initial["z"] == pytest.approx(sign * math.sqrt(2), rel=1e-14)
    assert scene.initial["z_dot"] == pytest.approx(-sign / math.sqrt(2), rel=1e-14)


def test_newton_from_a_critical_point_asks_for_a_guess():
    """From z = 0 the constraint's gradient in z, 2z, vanishes: no step is possible."""
    with pytest.raises(InconsistentInitialDataError) as info:
        loads_scene(SPHERE)
    assert "Newton's method from z = 0 found no point of the holonomic constraints for z" \
        in str(info.value)
    assert "z = { guess = 1.0 }" in str(info.value)


def test_a_sphere_point_without_a_real_solution_is_refused():
    """x = y = 1.5 lies outside the circle of radius 2: z^2 = 4 - 4.5 < 0."""
    text = SPHERE.replace("y = 1.0", "y = 1.5").replace("x = 1.0", "x = 1.5")
    with pytest.raises(InconsistentInitialDataError, match="found no point"):
        loads_scene(text + "z = { guess = 1.0 }\n")
