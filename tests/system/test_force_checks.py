"""The checks of the forces: a Rayleigh function that dissipates, forces defined where a
run starts (``nhham.system.force_checks``). Expected values by hand: the Hessians in the
velocities below are written out in each case."""

import pytest

import nhham
from nhham.errors import InputError, ValidationError
from nhham.system.force_checks import check_forces_at, singular_force

L2 = "(x_dot**2 + y_dot**2)/2"


@pytest.mark.parametrize("R, params, words", [
    # d2R/dv2 = [[-c]] = [[-1]]: negative definite, decided exactly
    ("-c*x_dot**2/2", {"c": 1.0}, ["not positive semi-definite", "-1", "decided exactly"]),
    # [[0, 1], [1, 0]]: eigenvalues +-1, indefinite
    ("x_dot*y_dot", {}, ["not positive semi-definite", "eigenvalue -1 ", "decided exactly"]),
    # [[2c, 0], [0, -2]] with c = 3: one negative eigenvalue
    ("c*x_dot**2 - y_dot**2", {"c": 3.0}, ["eigenvalue -2 ", "decided exactly"]),
    # 2(1 - x^2) < 0 for |x| > 1: found at a sampled state, named
    ("(1 - x**2)*x_dot**2", {}, ["at the state x = ", "seeded states"]),
    # [[2 yd^2, 4 xd yd], [4 xd yd, 2 xd^2]]: det = -12 xd^2 yd^2 < 0 off the axes
    ("x_dot**2*y_dot**2", {}, ["at the state", "seeded states"]),
    # no velocity at all: a potential, not a dissipation function
    ("k*x**2/2", {"k": 1.0}, ["has no velocity in it", "[forces]"]),
])
def test_a_rayleigh_function_that_does_not_dissipate_is_refused(R, params, words):
    with pytest.raises(ValidationError) as err:
        nhham.System(["x", "y"], L2, parameters=params, dissipation=R)
    assert err.value.key == "dissipation"
    for w in words:
        assert w in str(err.value), (w, str(err.value))


@pytest.mark.parametrize("R, params", [
    ("c*x_dot**2/2", {"c": 0.5}),                       # [[c]] = [[1/2]]
    ("(x_dot - y_dot)**2/2", {}),                       # [[1, -1], [-1, 1]]: semi-definite
    ("(1 + x**2)*x_dot**2 + y_dot**2", {}),             # 2(1 + x^2) > 0, 2 > 0
    ("c*x_dot**2/2", {"c": None}),                      # c without a value: not judged
    ("u*x_dot**2/2", {}),                               # an input: not judged
])
def test_a_dissipating_or_undecidable_rayleigh_function_is_taken(R, params):
    inputs = ["u"] if "u" in R else []
    s = nhham.System(["x", "y"], L2, parameters=params, dissipation=R, inputs=inputs)
    assert s.dissipation != 0


def test_a_scene_with_a_negative_dissipation_exits_2_naming_it():
    from nhham.system.scene import loads_scene

    with pytest.raises(ValidationError) as err:
        loads_scene('coordinates = ["x"]\nparameters = { c = 2.0 }\n'
                    'lagrangian = "x_dot**2/2"\ndissipation = "-c*x_dot**2/2"\n')
    assert err.value.key == "dissipation" and "eigenvalue -2 " in str(err.value)


def test_a_force_not_defined_at_the_state_is_named():
    s = nhham.System(["x", "y"], L2, parameters={"k": 1.0}, constraints=["x_dot - y_dot"],
                     forces={"x": "k/x", "y": "log(y)"}, dissipation="x_dot**2/(2*y**2)")
    assert singular_force(s, {"x": 1.0, "y": 1.0, "x_dot": 0.0, "y_dot": 0.0}) is None
    assert singular_force(s, {"x": 0.0, "y": 1.0, "x_dot": 0.0, "y_dot": 0.0})[0] == "forces.x"
    assert singular_force(s, {"x": 1.0, "y": 0.0, "x_dot": 0.0, "y_dot": 0.0})[0] == "forces.y"
    with pytest.raises(InputError) as err:
        check_forces_at(s, {"x": 0.0, "y": 1.0, "x_dot": 1.0, "y_dot": 1.0},
                        where="the initial state")
    assert err.value.key == "forces.x"
    assert "the force k/x on x is not defined at the initial state (x = 0, y = 1" in str(err.value)


def test_a_force_singular_only_through_the_time_or_an_input():
    s = nhham.System(["x"], "x_dot**2/2", forces={"x": "1/(t - 1) + u"}, inputs=["u"])
    at = {"x": 0.0, "x_dot": 0.0}
    assert singular_force(s, at, t=0.0) is None            # u unknown: not infinite
    assert singular_force(s, at, t=1.0)[0] == "forces.x"   # 1/(1 - 1)
    assert singular_force(s, {**at, "u": 2.0}, t=0.0) is None
