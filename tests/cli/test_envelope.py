"""The command's JSON envelope and its parts (nhham.cli.envelope): the envelope of any
subcommand, the error and its exit status by kind, the scene's names, plain JSON values.
Expected values are written out from the contract in the module's docstring."""

import json
import warnings

import jsonschema
import numpy as np
import pytest

from conftest import EXAMPLES
from nhham.cli.envelope import (
    FailureReport,
    capture_warnings,
    error_info,
    jsonable,
    one_line,
    scene_info,
)
from nhham.system.scene import load_scene


def test_envelope_helper_for_any_subcommand():
    from nhham.cli.envelope import envelope

    env = envelope("linearize", {"a_b": 1.0, "c": float("inf")}, warnings=["x\n y", "x y"])
    assert env["result"] == {"a_b": 1.0, "c": None}  # non-finite numbers are null
    assert env["warnings"] == ["x y"]
    assert list(env) == ["command", "nhham_version", "scene", "result", "warnings", "error"]
    assert env["error"] is None


@pytest.mark.parametrize("kind, status", [("usage", 2), ("input", 2), ("internal", 1),
                                          ("budget", 3), ("interrupted", 130)])
def test_a_failure_is_one_line_and_one_envelope_with_its_exit_status(kind, status, capsys,
                                                                     schema):
    """Exit statuses of the contract: 2 bad input or usage, 1 internal, 3 not succeeded,
    130 interrupted. (Kind "failed", also 3, comes with the result that says what did
    not succeed: the schema refuses it without one.)"""
    report = FailureReport("derive", json=True)
    assert report.fail(kind, "went\n  wrong", "--atol", warnings=["w\n1"]) == status
    out, err = capsys.readouterr()
    assert err == "nhham: error: went wrong\n"
    env = json.loads(out)
    jsonschema.validate(env, schema)
    assert env["error"] == {"kind": kind, "message": "went wrong", "key": "--atol"}
    assert env["result"] is None and env["warnings"] == ["w 1"] and env["command"] == "derive"
    assert FailureReport("derive", json=False).fail(kind, "x") == status
    assert FailureReport("simulate", json=False).fail("failed", "x") == 3
    assert capsys.readouterr().out == ""
    with pytest.raises(ValueError, match="error kind 'oops'"):
        error_info("oops", "m")


def test_the_scene_lists_every_name_an_expression_may_use():
    """The rolling disk: 4 coordinates, their velocities and momenta, 4 parameters with
    their values, and lambda_1, lambda_2 for its two constraints."""
    info = scene_info(load_scene(EXAMPLES / "rolling_disk.toml"))
    q = ["x", "y", "theta", "phi"]
    assert info["coordinates"] == q and info["velocities"] == [f"{c}_dot" for c in q]
    assert info["momenta"] == [f"p_{c}" for c in q]
    assert [p["name"] for p in info["parameters"]] == ["m", "I1", "I2", "R"]
    assert info["names"] == (q + [f"{c}_dot" for c in q] + [f"p_{c}" for c in q]
                             + ["m", "I1", "I2", "R", "lambda_1", "lambda_2"])


def test_plain_json_values_and_one_line_warnings():
    data = {"a": np.float64(1.5), "b": (np.int64(2), np.bool_(True)),
            "c": np.array([[1.0, np.nan]]), 3: None, "d": np.inf, "e": 2j}
    assert jsonable(data) == {"a": 1.5, "b": [2, True], "c": [[1.0, None]], "3": None,
                              "d": None, "e": "2j"}
    assert json.dumps(jsonable(data), allow_nan=False)
    assert one_line("  two\n\tlines  ") == "two lines"
    with capture_warnings() as caught:
        warnings.warn("first\nline")
        warnings.warn("second")
    assert caught == ["first line", "second"]
