"""t in L and the constraints (DESIGN.md §2): the input accepted, t the last parameter
(after the inputs), the complete lift d/dt g, the initial data at t = 0."""

import sympy as sp

from nhham import System
from nhham.system.naming import TIME
from nhham.system.scene import loads_scene

BEAD = """
name = "bead"
coordinates = ["x", "y"]
parameters = { m = 1.0, Omega = 2.0 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2"
holonomic = ["y*cos(Omega*t) - x*sin(Omega*t)"]
[initial]
x = 1.5
x_dot = 0.0
"""


def test_time_is_the_last_parameter_after_the_inputs():
    s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + t*x", constraints=["y_dot - x_dot"],
               parameters={"k": 1.0}, inputs=["u"], forces={"x": "u"})
    assert [p.name for p in s.parameters] == ["k", "u", "t"] and s.time_slot == 2
    assert s.declared_parameters == (sp.Symbol("k"),)
    assert s.time_dependent == (False,) and s.lagrangian_depends_on_time
    closed = s.closed_loop({"u": "cos(t)"})
    assert closed.time == TIME and closed.time_slot == len(closed.parameters) - 1


def test_the_initial_velocities_of_a_moving_constraint_are_solved_at_t_0():
    # at t = 0 the wire is the x axis turning at Ω: y = 0 and y' = Ω x (the lift's dg/dt)
    scene = loads_scene(BEAD)
    assert scene.initial["y"] == 0.0 and scene.initial["y_dot"] == 2.0 * 1.5
    assert scene.initial_solved == ("y", "y_dot")


def test_an_initial_state_off_the_moving_constraint_is_refused_naming_it():
    import pytest

    from nhham.errors import InputError

    with pytest.raises(InputError, match="holonomic.0. .time derivative."):
        loads_scene(BEAD.replace("x_dot = 0.0", "x_dot = 0.0\ny_dot = 0.0"))
