"""Forces, dissipation and inputs in a System and in a scene (keys, checks, control laws)."""

import pytest
import sympy as sp

import nhham
from nhham.errors import SceneError, ValidationError
from nhham.system.naming import TIME
from nhham.system.scene import loads_scene
from nhham.system.scene_dump import dump_scene

x, y, xd, yd, c, u, k = sp.symbols("x y x_dot y_dot c u k")

SCENE = """
name = "cart"
coordinates = ["x", "y"]
parameters = { c = 0.5, k = 2.0 }
lagrangian = "(x_dot**2 + y_dot**2)/2"
constraints = ["x_dot - y*y_dot"]
inputs = ["u"]
forces = { x = "u*sin(t) - k*x" }
dissipation = "c*(x_dot**2 + y_dot**2)/2"

[control]
u = "-x_dot + cos(t)"
"""


def test_generalized_forces_are_the_forces_minus_the_dissipation_gradient():
    s = nhham.System(["x", "y"], (xd**2 + yd**2) / 2, parameters={"c": 2.5},
                     forces=["u*y", 0], dissipation="c*x_dot**2/2 + x_dot*y_dot + y_dot**2",
                     inputs=["u"])
    assert list(s.generalized_forces) == [u * y - c * xd - yd, -xd - 2 * yd]
    assert s.parameters == (c, u) and s.declared_parameters == (c,) and s.time is None
    assert s.has_forces and not nhham.System(["x"], xd**2 / 2).has_forces


def test_time_is_a_parameter_slot_only_when_a_force_uses_it():
    s = nhham.System(["x"], xd**2 / 2, forces={"x": "sin(t)"})
    assert s.time == TIME and s.parameters == (TIME,)


def test_every_problem_is_named_by_its_key():
    with pytest.raises(ValidationError) as err:
        nhham.System(["x", "t"], xd**2 / 2 + sp.Symbol("t_dot")**2 / 2, forces={"x": "1"})
    assert "forces: the name t is the time" in str(err.value)
    with pytest.raises(ValidationError) as err:
        nhham.System(["x"], xd**2 / 2, forces={"z": "1", "x": "w"}, inputs=["x", "u", "u"])
    msg = str(err.value)
    for part in ("inputs[0]: 'x' is already", "inputs[2]: 'u' is already another input",
                 "forces.z: not a coordinate", "forces.x: unknown name 'w'"):
        assert part in msg
    with pytest.raises(ValidationError, match=r"forces: 1 expressions for 2 coordinates"):
        nhham.System(["x", "y"], (xd**2 + yd**2) / 2, forces=["1"])
    with pytest.raises(ValidationError, match=r"forces.x: Abs\(x_dot\) is not smooth"):
        nhham.System(["x"], xd**2 / 2, forces={"x": "-Abs(x_dot)"})
    with pytest.raises(ValidationError, match=r"lagrangian: unknown name 'u'"):
        nhham.System(["x"], "x_dot**2/2 + u*x", inputs=["u"])


def test_a_control_law_closes_the_loop():
    s = nhham.System(["x"], xd**2 / 2, parameters={"c": 0.5}, forces={"x": "u - c*x_dot"},
                     inputs=["u"])
    closed = s.closed_loop({"u": "-2*x + sin(t)"})
    assert closed.inputs == () and closed.time == TIME
    assert sp.expand(closed.generalized_forces[0] - (-2 * x + sp.sin(TIME) - c * xd)) == 0
    assert s.inputs == (u,)          # the open-loop system is unchanged
    with pytest.raises(ValidationError, match=r"control.v: not an input"):
        s.closed_loop({"v": "1"})
    with pytest.raises(ValidationError, match=r"control.u: unknown name 'u'"):
        s.closed_loop({"u": "u + 1"})


def test_scene_keys_and_round_trip():
    scene = loads_scene(SCENE)
    s = scene.system
    assert s.inputs == (u,) and s.time == TIME
    assert sp.expand(s.generalized_forces[0] - (u * sp.sin(TIME) - k * x - c * xd)) == 0
    assert dict(scene.control) == {"u": -xd + sp.cos(TIME)}
    again = loads_scene(dump_scene(s)).system
    assert again.inputs == s.inputs and again.declared_parameters == s.declared_parameters
    assert list(again.generalized_forces) == list(s.generalized_forces)


@pytest.mark.parametrize("change,message", [
    ('forces = { z = "1" }', "forces.z: not a coordinate"),
    ('forces = ["1"]', "forces: expected a table"),
    ('dissipation = 3', "dissipation: expected a string"),
    ('[control]\nv = "1"', "control.v: not an input"),
    ('inputs = ["x"]', "inputs[0]: 'x' is already"),
])
def test_scene_errors_name_the_key(change, message):
    base = SCENE.split("inputs =")[0]
    text = base + 'inputs = ["u"]\n' + change + "\n" if not change.startswith("inputs") else \
        base + change + "\n"
    with pytest.raises((SceneError, ValidationError)) as err:
        dict(loads_scene(text).control)   # [control] is checked where it is read
    assert message in str(err.value)


def test_an_input_named_t_is_refused_in_a_scene_too():
    with pytest.raises(ValidationError, match=r"inputs\[0\]: 't' is already the time"):
        loads_scene('coordinates = ["x"]\nlagrangian = "x_dot**2/2"\ninputs = ["t"]\n'
                    'forces = { x = "t" }\n')


def test_an_input_in_the_lagrangian_is_explained():
    with pytest.raises(ValidationError, match=r"lagrangian: unknown name 'u' \(an input may "
                                              r"appear in the forces"):
        nhham.System(["x"], "x_dot**2/2 + u*x", inputs=["u"], forces={"x": "u"})


def test_forces_as_a_one_form_in_the_differentials():
    s = nhham.System(["x", "y"], (xd**2 + yd**2) / 2, parameters={"k": 2.0},
                     forces="-k*x*dx + u*y*dy", inputs=["u"])
    assert list(s.forces) == [-k * x, u * y]
    dx, dy = sp.symbols("dx dy")
    same = nhham.System(["x", "y"], (xd**2 + yd**2) / 2, parameters={"k": 2.0},
                        forces=-k * x * dx + u * y * dy, inputs=["u"])
    assert same.forces == s.forces
    scene = loads_scene(SCENE.replace('forces = { x = "u*sin(t) - k*x" }',
                                      'forces = "(u*sin(t) - k*x)*dx"'))
    assert list(scene.system.forces) == [u * sp.sin(TIME) - k * x, 0]


@pytest.mark.parametrize("forces, message", [
    (3, r"forces: expected a table by coordinate, one expression per coordinate or a 1-form"),
    ("u", r"forces: a 1-form is linear in the differentials dx, dy"),
    ("x*dx*dy", r"forces: a 1-form is linear in the differentials"),
    (sp.Symbol("u"), r"forces: a 1-form is linear in the differentials"),
])
def test_what_is_not_a_one_form_is_refused(forces, message):
    with pytest.raises(ValidationError, match=message):
        nhham.System(["x", "y"], (xd**2 + yd**2) / 2, forces=forces, inputs=["u"])


def test_a_differential_that_is_also_a_name_is_refused():
    with pytest.raises(ValidationError, match="forces: dx is a name of the system"):
        nhham.System(["x"], xd**2 / 2, parameters={"dx": 1.0}, forces="-dx*x*dx")
    with pytest.raises(nhham.ParseError, match="forces: dx is a name of the scene"):
        loads_scene(SCENE.replace("k = 2.0", "k = 2.0, dx = 1.0")
                    .replace('forces = { x = "u*sin(t) - k*x" }', 'forces = "-k*x*dx"'))
