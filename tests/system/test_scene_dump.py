"""Scene files written from a system (nhham.system.scene_dump): they load back to the
same system, initial data and settings, whatever the names and values."""

import pytest
import sympy as sp

from handmade import DISK_INITIAL as INITIAL
from handmade import DISK_SCENE as DISK
from handmade import DISK_SIMULATE as SIMULATE
from handmade import same
from nhham.errors import SceneError
from nhham.system.scene import SimulateOptions, loads_scene
from nhham.system.scene_dump import dump_scene


def assert_same_system(a, b):
    assert a.name == b.name
    assert a.coordinates == b.coordinates
    assert a.parameters == b.parameters
    assert dict(a.parameter_values) == dict(b.parameter_values)
    assert same(a.lagrangian, b.lagrangian)
    assert len(a.constraints) == len(b.constraints)
    assert all(same(p, q) for p, q in zip(a.constraints, b.constraints))
    assert len(a.holonomic) == len(b.holonomic)
    assert all(same(p, q) for p, q in zip(a.holonomic, b.holonomic))


def test_dump_round_trip_rolling_disk():
    scene = loads_scene(DISK + INITIAL + SIMULATE)
    text = dump_scene(scene.system, scene.initial, scene.simulate)
    again = loads_scene(text)
    assert_same_system(scene.system, again.system)
    assert again.system.lagrangian == scene.system.lagrangian  # structurally equal
    assert again.initial == scene.initial
    assert again.simulate == scene.simulate


def test_dump_round_trip_awkward_names_and_values():
    text = """
name = "odd \\"quoted\\" name\\twith tab"
coordinates = ["θ", "r", "z"]
parameters = { lambda = 0.30000000000000004, I = 1e-3, E = 12345.678901234567 }
symbolic_parameters = ["g", "N"]
lagrangian = "I*θ_dot**2/2 + E*r_dot**2/2 + z_dot**2/2 - g*z + exp(1)*N*r"
constraints = ["θ_dot - Abs(lambda)*r*r_dot"]
holonomic = ["z - atan2(r, 1/3)"]
"""
    scene = loads_scene(text)
    dumped = dump_scene(scene.system, simulate={"method": "RK45", "step": 0.01},
                        description='two\nlines "quoted" \\ backslash')
    again = loads_scene(dumped)
    assert_same_system(scene.system, again.system)
    assert again.name == 'odd "quoted" name\twith tab'
    assert again.description == 'two\nlines "quoted" \\ backslash'
    assert again.simulate == SimulateOptions(method="RK45", step=0.01)
    lam = sp.Symbol("lambda")
    assert again.system.parameter_values[lam] == 0.1 + 0.2


def test_dump_refuses_non_finite_values():
    scene = loads_scene(DISK)
    with pytest.raises(SceneError, match="non-finite"):
        dump_scene(scene.system, initial={"x": float("nan")})


def test_dump_leaves_out_the_velocities_the_constraints_determine():
    """The disk's x' = R cos(theta) phi', y' = R sin(theta) phi' determine x' and y' (the
    first velocities whose columns of mu raise its rank): they are not written, the reader
    solves them, and at another R they follow (a full table would be off the constraints
    there, and a study moving R would project every start)."""
    scene = loads_scene(DISK + INITIAL + SIMULATE)
    text = dump_scene(scene.system, scene.initial, scene.simulate)
    table = text.split("[initial]")[1].split("[")[0]
    assert "x_dot" not in table and "y_dot" not in table and "phi_dot = 2.0" in table
    again = loads_scene(text)
    assert again.initial == scene.initial and set(again.initial_solved) == {"x_dot", "y_dot"}
    moved = loads_scene(text, values={"R": 2.0})
    assert moved.initial["x_dot"] == 4.0   # R phi' at theta = 0
