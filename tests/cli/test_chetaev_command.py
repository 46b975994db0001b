"""The command on the scenes with nonlinear (Chetaev) constraints, end to end in-process:
each constraint's kind, integrability not applicable, the multipliers and the motion
against the closed forms of the scenes' headers (worked out by hand), and the refusals."""

import json
import math
from pathlib import Path

import pytest

from nhham.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
G = 9.81


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def result(capsys, *argv):
    status, out, err = run(capsys, *argv, "--json")
    assert status == 0, err
    return json.loads(out)["result"]


@pytest.mark.parametrize("scene", ["appell_hamel", "isokinetic_particle",
                                   "perpendicular_velocities"])
def test_classify_labels_each_constraint_and_frobenius_does_not_apply(capsys, scene):
    r = result(capsys, "classify", EXAMPLES / f"{scene}.toml")
    assert r["constraint_kinds"] == [{"label": "constraints[0]", "kind": "nonlinear (Chetaev)",
                                      "time_dependent": False}]
    assert r["integrable"] is None
    assert r["integrability"] == "not applicable for nonlinear constraints"
    assert r["status"] == "determined" and r["regular"] and r["rank_c"] == 1
    status, out, _ = run(capsys, "classify", EXAMPLES / f"{scene}.toml")
    assert status == 0 and "not applicable for nonlinear constraints" in out
    assert "nonlinear (Chetaev)" in out


def test_appell_hamel_derive_and_simulate_against_the_closed_form(capsys):
    # lambda = m g/(1 + a^2); s(t) = s0 - a g t/(1 + a^2) along the fixed direction (3, 4)/5
    scene = EXAMPLES / "appell_hamel.toml"
    r = result(capsys, "derive", scene)
    assert r["multipliers"] == ["g*m/(a**2 + 1)"]
    r = result(capsys, "simulate", scene)
    y = dict(zip(r["state"], r["y_final"]))
    s = 5.0 - 0.5 * G * 1.0 / 1.25
    assert abs(y["x_dot"] - 0.6 * s) < 1e-9 and abs(y["y_dot"] - 0.8 * s) < 1e-9
    assert abs(y["z_dot"] - 0.5 * s) < 1e-9
    assert r["energy_drift"] < 1e-10


def test_isokinetic_simulate_against_the_closed_form(capsys):
    # x = (c^2/g) gd(u), y = -(c^2/g) ln cosh(u), u = g t/c; E changes by m g y
    r = result(capsys, "simulate", EXAMPLES / "isokinetic_particle.toml")
    y = dict(zip(r["state"], r["y_final"]))
    c, u = 2.0, G / 2.0
    assert abs(y["x"] - c**2 / G * 2 * math.atan(math.tanh(u / 2))) < 1e-8
    assert abs(y["y"] + c**2 / G * math.log(math.cosh(u))) < 1e-8
    assert abs(r["energy_drift"] - c**2 * math.log(math.cosh(u))) < 1e-7
    assert r["energy_balance_residual"] < 1e-9


def test_perpendicular_velocities_compare_agrees_and_energy_is_conserved(capsys):
    scene = EXAMPLES / "perpendicular_velocities.toml"
    r = result(capsys, "derive", scene)
    # lambda = (F1.v2/m1 + F2.v1/m2)/(|v2|^2/m1 + |v1|^2/m2), F1 = (0, -m1 g), F2 = -k q2
    assert r["constraint_matrix"] == [
        ["-(m1*x1_dot**2 + m1*y1_dot**2 + m2*x2_dot**2 + m2*y2_dot**2)/(m1*m2)"]]
    status, out, err = run(capsys, "compare", scene)
    assert status == 0 and "AGREE" in out, err
    r = result(capsys, "simulate", scene)
    assert r["energy_drift"] < 1e-9 and r["constraint_residual_max"] < 1e-9


def test_rattle_runs_and_a_degenerate_constraint_is_refused_in_one_line(capsys, tmp_path):
    r = result(capsys, "simulate", EXAMPLES / "isokinetic_particle.toml", "--method", "rattle",
               "--step", "0.01")
    assert r["constraint_residual_max"] < 1e-12   # |v| = c at every grid point
    scene = tmp_path / "degenerate.toml"
    scene.write_text('name = "d"\ncoordinates = ["x", "y"]\n'
                     'lagrangian = "(x_dot**2 + y_dot**2)/2"\n'
                     'constraints = ["(x_dot - y_dot)**2"]\n')
    status, out, err = run(capsys, "classify", scene, "--json")
    assert status == 2 and "constraints[0]" in err and "vanishes on M_1" in err
    assert json.loads(out)["error"]["key"] == "constraints[0]"


def test_linearize_a_uniform_motion_under_a_nonlinear_constraint(capsys, tmp_path):
    """|v| = c without forces: lambda = 0 and a = 0 at every state of M_1 (the reaction
    lambda v does no work only at lambda = 0, and mu . a = 0 with W a = -lambda mu), so
    the chart's field is zero near the uniform motion: A = 0 in (x, y, y_dot), x_dot
    solved by Newton's method from c (its branch)."""
    scene = tmp_path / "free.toml"
    scene.write_text('name = "f"\ncoordinates = ["x", "y"]\nparameters = { c = 2.0 }\n'
                     'lagrangian = "(x_dot**2 + y_dot**2)/2"\n'
                     'constraints = ["(x_dot**2 + y_dot**2 - c**2)/2"]\n'
                     '[steady]\nx = 0.0\ny = 0.0\nx_dot = "c"\ny_dot = 0.0\n')
    status, out, err = run(capsys, "linearize", scene, "--json")
    assert status == 0, err
    result = json.loads(out)["result"]
    assert result["dependent"] == ["x_dot"]
    assert all(abs(e) < 1e-12 for row in result["matrix"] for e in row)
