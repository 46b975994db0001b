"""The [steady] table of scene files: parsing, evaluation, round trip."""

import pytest
import sympy as sp

from nhham import ParseError, SceneError
from nhham.system.scene import loads_scene
from nhham.system.scene_dump import dump_scene

from handmade import SLEIGH_SCENE

STEADY = """
[steady]
x = 0
y = 0.5
theta = 0.0
x_dot = "u*cos(pi/6)"
y_dot = "u/2"
theta_dot = 0
"""


def test_steady_entries_are_expressions_in_the_parameters():
    scene = loads_scene(SLEIGH_SCENE + STEADY)
    values = scene.steady.values({"m": 1.0, "I": 0.25, "a": 0.5, "u": 4.0})
    assert values["x_dot"] == pytest.approx(4.0 * 3 ** 0.5 / 2, abs=1e-15)
    assert values["y_dot"] == 2.0 and values["y"] == 0.5
    fam = scene.steady.family({"u": 4.0})
    assert fam["u"]["y_dot"] == 0.5 and fam["u"]["x"] == 0.0


def steady_of(text):
    """The [steady] table of a scene, read as linearize reads it (its problems raised then:
    a broken [steady] does not stop the commands that do not read it)."""
    scene = loads_scene(text)
    assert scene.system.n == 3
    return scene.steady.expressions


def test_steady_errors_name_the_key():
    with pytest.raises(SceneError, match=r"steady.x_dt: unknown name .*did you mean 'x_dot'"):
        steady_of(SLEIGH_SCENE + STEADY.replace("x_dot =", "x_dt ="))
    with pytest.raises(SceneError, match=r"steady: missing value for 'theta_dot'"):
        steady_of(SLEIGH_SCENE + STEADY.replace("theta_dot = 0\n", ""))
    # coordinates and velocities are not parameters: a steady entry cannot use them
    with pytest.raises(ParseError, match=r"steady.y_dot.*theta"):
        steady_of(SLEIGH_SCENE + STEADY.replace('"u/2"', '"u*theta"'))
    with pytest.raises(SceneError, match=r"steady.theta: expected a number or an expression"):
        steady_of(SLEIGH_SCENE + STEADY.replace("theta = 0.0", "theta = true"))


def test_steady_is_never_evaluated_as_python():
    with pytest.raises(ParseError):
        steady_of(SLEIGH_SCENE + STEADY.replace('"u/2"', '"__import__(\'os\')"'))


def test_dump_round_trip_keeps_the_steady_table():
    scene = loads_scene(SLEIGH_SCENE + STEADY)
    text = dump_scene(scene.system, steady=scene.steady)
    again = loads_scene(text)
    for k, e in scene.steady.expressions.items():
        assert sp.simplify(again.steady.expressions[k] - e) == 0
