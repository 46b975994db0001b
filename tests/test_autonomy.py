"""Time as one datum (System.time_slot) and the one home of the refusals of time.

The expected messages are the texts the six places wrote themselves before they were
gathered in nhham.autonomy (a user sees the same words).
"""

import pytest
import sympy as sp

from nhham.autonomy import require_autonomous
from nhham.errors import InputError
from nhham.system.description import System
from nhham.system.naming import TIME


def test_time_slot_is_the_index_of_t_among_the_parameters():
    timed = System(["x"], "m*x_dot**2/2", parameters={"m": 1.0}, inputs=["u"],
                   forces=["u*sin(t)"])
    assert timed.time == TIME and timed.time_slot == 2
    assert timed.parameters[timed.time_slot] == sp.Symbol("t")
    plain = System(["x"], "m*x_dot**2/2", parameters={"m": 1.0}, forces=["-x"])
    assert plain.time is None and plain.time_slot is None
    closed = timed.closed_loop({"u": "cos(t)"})
    assert closed.time_slot == len(closed.parameters) - 1 == 1


@pytest.mark.parametrize("where, details, key, text", [
    ("secondary", {"label": "secondary[0]", "expression": "x - u", "names": "u"}, "forces",
     "forces: the secondary constraint secondary[0] = x - u depends on u; the constraint "
     "algorithm needs forces that do not depend on inputs where C is singular (give "
     "the inputs as parameters with values)"),
    ("method", {"method": "rattle"}, "method", "method: 'rattle' does not take time-dependent "
     "forces (t in the forces); choose an adaptive method such as DOP853"),
    ("linearize", {}, "forces", "linearize: the forces depend on time t; a steady motion "
     "needs autonomous forces (give the inputs constant values instead)"),
    ("linearize_geometry", {"key": "lagrangian"}, "lagrangian", "lagrangian: depends on "
     "time t; a steady motion (and its linearisation) needs L and the constraints "
     "autonomous"),
])
def test_the_refusals_raise_with_their_key(where, details, key, text):
    require_autonomous(where, False, **details)  # nothing to refuse
    with pytest.raises(InputError) as caught:
        require_autonomous(where, True, **details)
    assert str(caught.value) == text and caught.value.key == key


def test_a_scene_reads_t_in_the_lagrangian_and_the_constraints_as_the_time():
    from nhham.system.scene import loads_scene

    scene = loads_scene('coordinates = ["x", "y"]\nlagrangian = "(x_dot**2 + y_dot**2)/2 + t*x"\n'
                        'constraints = ["y_dot - t*x_dot"]\n')
    system = scene.system
    assert system.time == TIME and system.parameters == (TIME,) and system.time_slot == 0
    assert system.time_dependent == (True,) and system.lagrangian_depends_on_time


def test_a_parameter_named_t_is_no_time():
    system = System(["x"], "x_dot**2/2 + t*x", parameters={"t": 2.0})
    assert system.time is None and system.time_slot is None


def test_the_complete_lift_of_a_moving_holonomic_constraint_has_its_time_derivative():
    # g = x - sin(t): d/dt g = x_dot - cos(t) along a motion
    system = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", holonomic=["x - sin(t)"])
    x_dot, t = sp.Symbol("x_dot"), TIME
    assert sp.simplify(system.phi[0] - (x_dot - sp.cos(t))) == 0
    assert system.time_dependent == (True, True)
