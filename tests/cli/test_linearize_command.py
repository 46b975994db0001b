"""``nhham linearize``: JSON keys (and the schema), sweeps, exit statuses (in-process)."""

import json

import jsonschema
from pathlib import Path

import pytest

from nhham.cli.main import main

from handmade import SLEIGH_SCENE

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

SLEIGH = SLEIGH_SCENE + """[steady]
x = 0
y = 0
theta = 0
x_dot = "u"
y_dot = 0
theta_dot = 0
"""


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


@pytest.fixture
def sleigh(tmp_path):
    path = tmp_path / "sleigh.toml"
    path.write_text(SLEIGH)
    return path


def test_json_keys_and_exact_verdict(capsys, sleigh):
    status, out, _ = run(capsys, "linearize", sleigh, "--json")
    assert status == 0
    env = json.loads(out)
    assert env["command"] == "linearize"
    d = env["result"]
    assert d["coordinates"] == ["theta_dot"] and d["method"] == "exact"
    # w' = -m a u w / (I + m a^2) = -2 w
    assert d["eigenvalues"] == [[-2.0, 0.0]] and d["stable"] is True
    assert d["matrix"] == [[-2.0]] and d["matrix_exact"] == [["-2"]]
    assert "x_dot" in d["neutral"]   # the speed: a column nothing depends on


def test_sweep_json_with_crossing(capsys, sleigh):
    from nhham.render.schema import output_schema

    status, out, _ = run(capsys, "linearize", sleigh, "--json", "--numeric",
                         "--sweep", "u=-1:1.5:6")
    assert status == 0
    jsonschema.validate(json.loads(out), output_schema())
    sw = json.loads(out)["result"]["sweep"]
    assert set(sw) >= {"parameter", "values", "eigenvalues", "crossings"}
    assert sw["parameter"] == "u" and len(sw["values"]) == 6 == len(sw["eigenvalues"])
    assert [c["kind"] for c in sw["crossings"]] == ["real"]
    assert abs(sw["crossings"][0]["value"]) < 1e-9


def test_differential_drive_text(capsys):
    status, out, _ = run(capsys, "linearize", EXAMPLES / "differential_drive.toml")
    assert status == 0
    assert "asymptotically stable" in out and "-0.8908685969" in out


@pytest.mark.parametrize("argv, fragment", [
    (["--sweep", "v=0:10"], "--sweep: expected PARAMETER=START:STOP:COUNT"),
    (["--sweep", "w=0:1:5"], "'w' is not a parameter"),
    (["--plot", "x.png"], "--plot draws the root locus of a sweep"),
])
def test_bad_options_exit_2(capsys, sleigh, argv, fragment):
    status, out, err = run(capsys, "linearize", sleigh, *argv)
    assert status == 2 and fragment in err and len(err.strip().splitlines()) == 1


def test_scene_without_steady_exits_2(capsys):
    status, _, err = run(capsys, "linearize", EXAMPLES / "rolling_disk.toml")
    assert status == 2 and "needs a [steady] table" in err


def test_not_steady_exits_2_with_residual(capsys, tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SLEIGH.replace('x_dot = "u"', 'x_dot = "u"\n').replace(
        "theta_dot = 0", "theta_dot = 1").replace("y_dot = 0", "y_dot = 0.5"))
    status, _, err = run(capsys, "linearize", path)
    assert status == 2 and "not steady" in err


def test_plot_needs_the_extra_or_writes_a_file(capsys, sleigh, tmp_path):
    target = tmp_path / "locus.png"
    status, _, err = run(capsys, "linearize", sleigh, "--sweep", "u=0:1:3", "--plot", target)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert status == 2 and "matplotlib" in err
    else:
        assert status == 0 and target.exists()


def test_a_rotating_chart_is_refused(capsys, tmp_path):
    """The Chaplygin sphere spinning in place about its vertical principal axis: every
    acceleration is zero and the yaw column of the Jacobian vanishes, but turning the yaw
    turns the rolling constraints' velocity block, so the state matrix at yaw = 0 does not
    describe the motion (it changes by O(1) over half a radian). Refused, exit 2."""
    text = (EXAMPLES / "chaplygin_sphere.toml").read_text()
    steady = {s: "0.0" for s in ("yaw", "pitch", "roll", "x", "y", "pitch_dot", "roll_dot",
                                 "x_dot", "y_dot")} | {"yaw_dot": '"w"'}
    text = text.replace("I3 = 0.12 }", "I3 = 0.12, w = 2.0 }") + "\n[steady]\n" + "".join(
        f"{k} = {v}\n" for k, v in steady.items())
    path = tmp_path / "spinning_sphere.toml"
    path.write_text(text)
    status, _, err = run(capsys, "linearize", path)
    assert status == 2
    assert "moves yaw" in err and "changes along it" in err


def test_rounding_is_shown_as_zero_and_said(sleigh):
    """-0 and 1e-17 in a complex-step state matrix are rounding: the text shows 0 and says
    which magnitudes it treats so; the JSON keeps the values (with -0.0 written 0.0)."""
    from types import SimpleNamespace

    import numpy as np

    from nhham.render.linearize import linearize_text, rounding_level
    from nhham.numerics.linearization import linearization_result

    A = np.array([[-0.0, 1.0e-17], [2.0, -1.5]])
    lin = linearization_result(A, ("phi", "phi_dot"), "complex-step", "float64", ("phi", "phi_dot"),
                               A, (), (), {}, {}, 0.0)
    text = linearize_text("toy", SimpleNamespace(name="toy", control={}), lin, None)
    matrix = text.split("state matrix:\n", 1)[1].split("eigenvalues:", 1)[0]
    assert "-0 " not in matrix + " " and "e-17" not in matrix
    assert matrix.splitlines()[2].split() == ["0", "0"]
    assert f"values of magnitude <= {rounding_level(lin):.1e} are shown as 0" in text
    # eigenvalues of [[0, 0], [2, -1.5]]: 0 and -1.5 (by hand), no "-0"
    eig = text.split("eigenvalues:\n", 1)[1].splitlines()[:2]
    assert [e.split()[0] for e in eig] == ["0", "-1.5"]


def test_json_has_no_negative_zero(capsys):
    """The 3-D disc's state matrix had -0.0 entries (JSON "-0.0")."""
    import math

    status, out, err = run(capsys, "linearize", EXAMPLES / "rolling_disc_3d.toml", "--json")
    assert status == 0, err
    res = json.loads(out)["result"]
    values = [x for row in res["matrix"] for x in row] + [x for z in res["eigenvalues"]
                                                          for x in z]
    assert all(math.copysign(1.0, x) > 0 for x in values if x == 0)
    assert "-0.0" not in out.split('"matrix"', 1)[1].split("]]", 1)[0]
