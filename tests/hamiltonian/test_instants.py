"""Where the first/second-class split of a time-dependent system changes with t
(nhham.hamiltonian.instants), against brackets worked out by hand."""

import pytest
import sympy as sp

from nhham import System, classify_constraints
from nhham.hamiltonian.instants import split_instants

L3 = "(x_dot**2 + y_dot**2 + z_dot**2)/2"


def twisted(rate, **parameters):
    """x' = 0 and y' = rate(t) x z': Ψ = (p_x, p_y − rate x p_z), {Ψ_1, Ψ_2} = rate p_z
    (H = |p|²/2): second class where rate(t) ≠ 0, both first class where it vanishes."""
    return System(["x", "y", "z"], L3, constraints=["x_dot", f"y_dot - ({rate})*x*z_dot"],
                  parameters=parameters)


@pytest.mark.parametrize("rate, parameters, condition, instants", [
    ("t", {}, "t", ["0"]),
    ("t**2 - a", {"a": 2.0}, "t**2 - 2", ["-sqrt(2)", "sqrt(2)"]),  # a at its value
    ("sin(t)", {}, "sin(t)", None),                                  # infinitely many
    ("1 + t**2", {}, "t**2 + 1", []),                                # no real root
])
def test_the_split_changes_where_the_bracket_vanishes_on_M_f(rate, parameters, condition,
                                                             instants):
    classes = classify_constraints(twisted(rate, **parameters))
    assert (classes.first_class, classes.second_class) == (0, 2)  # a generic instant
    found = split_instants(classes).to_dict()
    assert found["instants"] == instants
    if instants == []:
        assert found["changes"] is False and found["text"] == "the same at every instant"
    else:
        assert sp.simplify(sp.sympify(found["condition"]) - sp.sympify(condition)) == 0
        assert found["changes"] is True


def test_a_moving_holonomic_constraint_keeps_its_split():
    """The bead on a wire turning at Ω: g = y cos Ωt − x sin Ωt and its lift, {g, g^c} =
    (cos² + sin²)/m ≠ 0 at every t: the same split at every instant."""
    bead = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2",
                  holonomic=["y*cos(Omega*t) - x*sin(Omega*t)"],
                  parameters={"m": 1.0, "Omega": 2.0})
    found = split_instants(classify_constraints(bead))
    assert found.changes is False


def test_an_autonomous_system_has_no_instants():
    assert split_instants(classify_constraints(twisted("1"))) is None
