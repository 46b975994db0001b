"""The initial data of a scene checked against its constraints (nhham.system.initial):
residuals of the constraints and of the holonomic ones' time derivatives, relative to the
size of their terms, with the parameters' values."""

import pytest

from handmade import DISK_INITIAL as INITIAL
from handmade import DISK_SCENE as DISK
from nhham.errors import InconsistentInitialDataError, MissingParameterValueError
from nhham.system.initial import check_initial
from nhham.system.scene import loads_scene


def test_check_initial_residuals():
    scene = loads_scene(DISK + INITIAL)
    assert check_initial(scene) == {"constraints[0]": 0.0, "constraints[1]": 0.0}


def test_check_initial_can_be_skipped():
    text = DISK + INITIAL.replace("x_dot = 2.0", "x_dot = 2.5")
    scene = loads_scene(text, check_initial=False)
    with pytest.raises(InconsistentInitialDataError) as info:
        check_initial(scene)
    message = str(info.value)
    assert "constraints[0]" in message and "0.5" in message
    assert "constraints[1]" not in message


def test_check_initial_tolerance_is_relative():
    # Terms of size 1e6 with a rounding-size residual pass; 1e-3 does not.
    big = DISK.replace("R = 1.0", "R = 1000.0") + INITIAL.replace("phi_dot = 2.0", "phi_dot = 1000.0")
    ok = big.replace("x_dot = 2.0", "x_dot = 1000000.0000001")
    assert abs(check_initial(loads_scene(ok))["constraints[0]"]) < 1e-3
    with pytest.raises(InconsistentInitialDataError, match="constraints\\[0\\]"):
        loads_scene(big.replace("x_dot = 2.0", "x_dot = 1000000.001"))


def test_holonomic_initial_data_checks_position_and_velocity():
    text = """
coordinates = ["x", "y", "z"]
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2 - z"
holonomic = ["x**2 + y**2 - 1"]

[initial]
x = 1.0
y = 0.0
z = 0.0
x_dot = 0.0
y_dot = 1.0
z_dot = 3.0
"""
    residuals = check_initial(loads_scene(text))
    assert residuals == {"holonomic[0]": 0.0, "holonomic[0] (time derivative)": 0.0}
    with pytest.raises(InconsistentInitialDataError) as info:
        loads_scene(text.replace("x_dot = 0.0", "x_dot = 0.25"))
    assert "holonomic[0] (time derivative)" in str(info.value)
    assert "0.5" in str(info.value)  # 2*x*x_dot


def test_missing_parameter_value_for_initial_check():
    text = DISK.replace(", R = 1.0 }", ' }\nsymbolic_parameters = ["R"]') + INITIAL
    with pytest.raises(MissingParameterValueError, match="'R'"):
        loads_scene(text)
    scene = loads_scene(text, check_initial=False)
    with pytest.raises(MissingParameterValueError):
        check_initial(scene)
