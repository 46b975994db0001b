"""Time as one datum (System.time_slot) and the one home of the refusals of time.

The expected messages are the texts the six places wrote themselves before they were
gathered in nhham.autonomy (a user sees the same words).
"""

import pytest
import sympy as sp

from nhham.autonomy import nonautonomous, require_autonomous
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


@pytest.mark.parametrize("where, details, text", [
    ("scene", {}, " (systems are autonomous: L and the constraints may not depend on time t, "
     "a force may (forces = {...}); if t is a parameter, add it to parameters)"),
    ("screening", {}, "; nhham's systems are autonomous: L and the constraints may not depend "
     "on time t explicitly, a force may (forces=...; if t is a parameter, declare it in "
     "parameters)"),
    ("mechanics", {"t": "t"}, "depends explicitly on time t; nhham handles autonomous "
     "systems only"),
])
def test_the_advice_of_the_parsers(where, details, text):
    assert nonautonomous(where, **details) == text


@pytest.mark.parametrize("where, details, key, text", [
    ("secondary", {"label": "secondary[0]", "expression": "x - t", "names": "t"}, "forces",
     "forces: the secondary constraint secondary[0] = x - t depends on t; the constraint "
     "algorithm needs forces that do not depend on time or inputs where C is singular (give "
     "the inputs as parameters with values)"),
    ("method", {"method": "rk4"}, "method", "method: 'rk4' does not take time-dependent "
     "forces (t in the forces); choose an adaptive method such as DOP853"),
    ("linearize", {}, "forces", "linearize: the forces depend on time t; a steady motion "
     "needs autonomous forces (give the inputs constant values instead)"),
])
def test_the_refusals_raise_with_their_key(where, details, key, text):
    require_autonomous(where, False, **details)  # nothing to refuse
    with pytest.raises(InputError) as caught:
        require_autonomous(where, True, **details)
    assert str(caught.value) == text and caught.value.key == key


def test_a_scene_with_t_in_the_lagrangian_gets_the_advice():
    from nhham.system.scene import loads_scene

    with pytest.raises(InputError, match="systems are autonomous"):
        loads_scene('coordinates = ["x"]\nlagrangian = "x_dot**2/2 + t*x"\n')
