"""``nhham reduce`` and ``nhham hamiltonize`` on the gallery's Chaplygin scenes: the
schema, the hand values (tests/lagrangian/test_chaplygin.py and
tests/hamiltonian/test_hamiltonization.py derive them), and one-line refusals."""

import json
from pathlib import Path

import jsonschema
import sympy as sp

import nhham
from nhham.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_hamiltonize_the_nonholonomic_particle(capsys):
    status, out, err = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml",
                           "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    result = envelope["result"]
    f = nhham.parse_expression(result["conformal_factor"], envelope["scene"]["names"])
    y = next(s for s in f.free_symbols if s.name == "y")
    assert result["hamiltonizable"] and sp.simplify(f - 1 / sp.sqrt(1 + y**2)) == 0
    assert result["jacobiator_after"] == [] and result["reduction_check"]["agrees"]
    status, text, _ = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml")
    assert status == 0 and "conformal factor f  1/sqrt(y**2 + 1)" in text


def test_reduce_the_sleigh_with_its_symmetry_and_without_a_factor(capsys):
    status, out, err = run(capsys, "reduce", EXAMPLES / "chaplygin_sleigh.toml",
                           "--symmetry", "y", "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    assert envelope["result"]["symmetry_coordinates"] == ["y"]
    assert envelope["result"]["check"]["agrees"]
    status, out, _ = run(capsys, "hamiltonize", EXAMPLES / "chaplygin_sleigh.toml",
                         "--symmetry", "y", "--json")
    result = json.loads(out)["result"]
    assert status == 0 and result["hamiltonizable"] is False
    assert result["obstruction"].startswith("theta is not closed")


def test_a_scene_that_is_not_chaplygin_is_refused_in_one_line(capsys):
    status, out, err = run(capsys, "reduce", EXAMPLES / "pendulum_cartesian.toml")
    assert status == 2 and "not of Chaplygin type" in err
    assert len(err.strip().splitlines()) == 1


def test_latex_of_the_particle_s_reduction_and_factor(capsys):
    status, out, _ = run(capsys, "reduce", EXAMPLES / "nonholonomic_particle.toml", "--latex")
    assert status == 0 and r"\ddot{x} &= - \frac{\dot{x} y \dot{y}}{y^{2} + 1}" in out
    status, out, _ = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml",
                         "--latex")
    assert status == 0 and r"f &= \frac{1}{\sqrt{y^{2} + 1}}" in out


TWO_CONSTRAINTS = """\
name = "particle with a second constraint"
coordinates = ["x", "y", "z"]
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
constraints = ["z_dot - y*x_dot", "x_dot - y_dot"]
"""


def test_a_second_step_by_the_constraint_left_on_the_shape_space(capsys, tmp_path):
    """z' = y x' and x' = y': --symmetry z leaves x' - y' = 0 on (x, y); --then x reduces
    by it: L_c2 = (2 + y^2) y'^2/2, so y'' = -y y'^2/(2 + y^2) (by hand: d/dt((2 + y^2) y')
    = y y'^2). hamiltonize refuses the first step alone (a constraint is left)."""
    scene = tmp_path / "two.toml"
    scene.write_text(TWO_CONSTRAINTS)
    status, out, err = run(capsys, "reduce", scene, "--symmetry", "z", "--then", "x", "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    result = envelope["result"]
    assert result["shape_coordinates"] == ["y"] and result["symmetry_coordinates"] == ["z", "x"]
    assert [s["by"] for s in result["stages"]] == ["symmetry", "constraint"]
    assert result["stages"][0]["reduced_coordinates"] == ["z"] and result["level"] == {}
    acc = nhham.parse_expression(result["accelerations"][0], envelope["scene"]["names"])
    y, yd = sorted(acc.free_symbols, key=str)
    assert sp.simplify(acc + y * yd**2 / (2 + y**2)) == 0 and result["check"]["agrees"]
    status, text, _ = run(capsys, "reduce", scene, "--symmetry", "z", "--then", "x")
    assert "step 2" in text and "reduce x by constraint; shape y" in text
    status, _, err = run(capsys, "hamiltonize", scene, "--symmetry", "z")
    assert status == 2 and "constraints are left on the shape space" in err
    status, out, err = run(capsys, "hamiltonize", scene, "--symmetry", "z", "--then", "x",
                           "--json")
    assert status == 0, err
    result = json.loads(out)["result"]
    assert result["hamiltonizable"] and len(result["stages"]) == 2   # k = 1: f = 1


def test_bad_stage_options_exit_2_naming_the_option(capsys):
    particle = EXAMPLES / "nonholonomic_particle.toml"
    for argv, why in [(["--then", "w"], "then: w not a shape coordinate"),
                      (["--level", "x"], "--level: expected C=VALUE"),
                      (["--level", "x=0"], "level: p_x is not conserved"),
                      (["--level", "y=0"], "then: y is not cyclic"),
                      (["--then", "x"], "then: no constraint is left")]:
        status, _, err = run(capsys, "reduce", particle, *argv)
        assert status == 2 and why in err and len(err.strip().splitlines()) == 1, err


def test_the_rubber_ball_reduces_in_two_steps_and_the_command_finds_its_factor(capsys):
    """x, y by the rolling constraints, then yaw by the no-twist constraint
    (yaw' = -sin(pitch) roll', the second stage's connection (0, sin(pitch))); hamiltonize
    reaches EKMR's verdict, f^-2 proportional to (gamma, A gamma) (hand values and the
    exact identity: tests/lagrangian/test_chaplygin_stages.py; here at two points)."""
    status, out, err = run(capsys, "hamiltonize", EXAMPLES / "rubber_ball.toml", "--symmetry",
                           "x,y", "--then", "yaw", "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    result = envelope["result"]
    assert result["shape_coordinates"] == ["pitch", "roll"]
    assert result["stages"][0]["shape_coordinates"] == ["yaw", "pitch", "roll"]
    assert result["stages"][1]["connection"] == [["0", "sin(pitch)"]]
    assert result["reduction_check"]["agrees"]
    assert result["hamiltonizable"] is True and result["jacobiator_after"] == []
    # f^-2 / (gamma, A gamma) is one constant: gamma = (-sin r cos p, sin p, cos p cos r)
    f = sp.sympify(result["conformal_factor"])
    m, r, I1, I2, I3 = 1.0, 0.5, 0.08, 0.1, 0.12
    D = m * r ** 2
    ratios = []
    for pitch, roll in ((0.3, -0.7), (1.1, 0.4)):
        gamma = (-sp.sin(roll) * sp.cos(pitch), sp.sin(pitch), sp.cos(pitch) * sp.cos(roll))
        gAg = sum(g ** 2 / (I + D) for g, I in zip(gamma, (I1, I2, I3)))
        at = {sp.Symbol(k): v for k, v in dict(m=m, r=r, I1=I1, I2=I2, I3=I3, pitch=pitch,
                                               roll=roll).items()}
        ratios.append(float((f ** -2).xreplace(at) / gAg))
    assert abs(ratios[0] / ratios[1] - 1) < 1e-12


def test_a_connection_singular_on_the_scenes_motion_is_warned_about(tmp_path, capsys):
    """sin(x) z' = y': with z as the symmetry, A = (0, -1/sin(x)) is singular at x = 0,
    where the [initial] state is (by hand: z' = y'/sin(x) is not defined there); the
    warning names the factor and y, which the constraint also solves for (y' = sin(x) z',
    regular everywhere: no warning)."""
    scene = tmp_path / "s.toml"
    scene.write_text('''coordinates = ["x", "y", "z"]
lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
constraints = ["sin(x)*z_dot - y_dot"]
[initial]
x = 0.0
y = 0.0
z = 0.0
x_dot = 1.0
y_dot = 0.0
z_dot = 0.0
''')
    assert main(["reduce", str(scene), "--symmetry", "z"]) == 0
    err = capsys.readouterr().err
    assert "the connection is singular at the [initial] state: sin(x) = 0" in err
    assert "the constraints also solve for: y" in err
    assert main(["reduce", str(scene), "--symmetry", "y"]) == 0
    assert "singular" not in capsys.readouterr().err
