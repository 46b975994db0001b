"""The command on forced scenes: simulate's control laws, linearize's B, derive's Q, and
the refusals (one line, exit 2, the key named)."""

import json
import re
from pathlib import Path

import numpy as np

from nhham.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
DRIVE = EXAMPLES / "differential_drive_motors.toml"


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def final_speed(out):
    result = json.loads(out)["result"]
    return result["y_final"][result["state"].index("x_dot")]


def test_simulate_uses_the_scene_s_control_laws_or_the_command_line_s(capsys):
    status, out, _ = run(capsys, "simulate", DRIVE, "--t-end", "40", "--json")
    assert status == 0 and abs(final_speed(out) - 0.1) < 1e-9          # r tau / c
    status, out, _ = run(capsys, "simulate", DRIVE, "--t-end", "40", "--json",
                         "--control", "tauL=2*tau", "--control", "tauR=2*tau")
    assert status == 0 and abs(final_speed(out) - 0.2) < 1e-9


def test_bad_control_laws_exit_2_naming_them(capsys):
    for law, fragment in (("tauL", "expected U=EXPR"), ("speed=1", "not an input"),
                          ("tauL=tauR", "unknown name 'tauR'")):
        status, out, err = run(capsys, "simulate", DRIVE, "--control", law, "--json")
        envelope = json.loads(out)
        assert status == 2 and fragment in envelope["error"]["message"], envelope["error"]
        assert envelope["error"]["key"] in ("--control", "control")


def test_linearize_gives_B_with_the_inputs_named(capsys):
    """The drive's [control] holds both torques at tau: the closed loop is the open loop
    with the inputs at their steady values (K = 0), and the open loop carries B."""
    status, out, _ = run(capsys, "linearize", DRIVE, "--json")
    result = json.loads(out)["result"]
    assert status == 0 and result["loop"] == "closed" and "inputs" not in result
    assert result["control"] == {"tauL": "tau", "tauR": "tau"}
    opened = result["open_loop"]
    assert opened["inputs"] == ["tauL", "tauR"] and opened["coordinates"] == result["coordinates"]
    B = np.array(opened["input_matrix"])
    assert B.shape == (2, 2) and np.allclose(B, B.T) and B[0, 0] > B[0, 1] > 0
    np.testing.assert_allclose(result["matrix"], opened["matrix"], rtol=1e-12, atol=1e-14)
    status, out, _ = run(capsys, "linearize", DRIVE)
    assert "input matrix B" in out and "tauL" in out and "open loop" in out


def test_linearize_closes_the_bicycle_s_steer_controller(capsys):
    """The headline is the scene's closed loop: the poles the controller was placed at
    (-2, -3, -4, -5: examples/make_bicycle_steer_control.py), and its matrix the closed
    form's A + B K (Meijaard et al. 2007 at v = 3, B = [0; M^-1], K read off the law);
    the open loop under it weaves unstably, as the benchmark does below 4.29 m/s."""
    import sympy as sp

    from bicycle_benchmark import BENCHMARK, benchmark_matrices, benchmark_state_matrix

    import nhham

    scene = EXAMPLES / "bicycle_steer_control.toml"
    # the command's answer (its JSON result and its text are the journey's data and text:
    # tests/journeys), computed once
    answer = nhham.linearize(scene)
    result = answer.to_dict()
    assert answer.failure is None and result["loop"] == "closed" and result["stable"] is True
    assert result["coordinates"] == ["phi", "delta", "phi_dot", "delta_dot"]
    poles = sorted(re for re, im in result["eigenvalues"])
    np.testing.assert_allclose(poles, [-5, -4, -3, -2], atol=1e-7)
    assert result["open_loop"]["stable"] is False
    law = sp.sympify(result["control"]["T_delta"])
    K = np.array([[0.0] * 4, [float(law.diff(sp.Symbol(s))) for s in result["coordinates"]]])
    M = benchmark_matrices(BENCHMARK)[0]
    B = np.vstack([np.zeros((2, 2)), np.linalg.inv(M)])
    expected = benchmark_state_matrix(3.0) + B @ K
    np.testing.assert_allclose(result["matrix"], expected, rtol=1e-6, atol=1e-6)
    out = answer.text()
    assert "(closed loop)" in out and "open loop            unstable" in out


def test_linearize_refuses_a_closed_loop_without_that_steady_motion(capsys, tmp_path):
    """A law in t (no steady motion of the closed loop) or one that does not give its
    input's [steady] value there: exit 2, the law named."""
    text = DRIVE.read_text()
    for law, fragment in (('tauL = "tau*cos(t)"', "uses t"),
                          ('tauL = "2*tau"', "not a steady motion of the closed loop")):
        scene = tmp_path / "drive.toml"
        scene.write_text(text.replace('[control]\ntauL = "tau"', f"[control]\n{law}"))
        status, out, _ = run(capsys, "linearize", scene, "--json")
        error = json.loads(out)["error"]
        assert status == 2 and error["key"] == "control" and fragment in error["message"], error
        assert "control.tauL" in error["message"]


def test_derive_shows_the_generalized_forces(capsys):
    status, out, _ = run(capsys, "derive", DRIVE, "--json")
    result = json.loads(out)["result"]
    assert result["inputs"] == ["tauL", "tauR"]
    assert result["generalized_forces"][3:] == ["-c*phiL_dot + tauL", "-c*phiR_dot + tauR"]
    status, out, _ = run(capsys, "derive", EXAMPLES / "rolling_disk.toml", "--json")
    assert json.loads(out)["result"]["generalized_forces"] is None


def test_a_secondary_constraint_on_an_input_exits_2(capsys, tmp_path):
    scene = tmp_path / "pushed.toml"
    scene.write_text('coordinates = ["q1", "q2", "q3"]\ninputs = ["u"]\n'
                     'lagrangian = "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2 + q1**2/2"\n'
                     'constraints = ["q1_dot + q3_dot"]\nforces = { q1 = "u" }\n')
    status, _, err = run(capsys, "classify", scene)
    assert status == 2 and "secondary[0]" in err and "depends on u" in err
    assert len(err.strip().splitlines()) == 1


def test_a_control_given_twice_exits_2(capsys):
    status, out, _ = run(capsys, "simulate", DRIVE, "--control", "tauL=1", "--control",
                         "tauL=2", "--json")
    error = json.loads(out)["error"]
    assert status == 2 and "tauL is given twice" in error["message"]


PENDULUM = """
name = "torqued pendulum"
coordinates = ["x"]
parameters = { u0 = 0.5, c = 0.1 }
lagrangian = "x_dot**2/2 + cos(x)"
inputs = ["u"]
forces = { x = "u" }
dissipation = "c*x_dot**2/2"
[initial]
x = 0.0
x_dot = 0.0
[steady]
u = "u0"
x = "asin(u0)"
x_dot = 0.0
"""


def test_bench_refuses_an_input_without_a_value(capsys, tmp_path):
    scene = tmp_path / "pendulum.toml"
    scene.write_text(PENDULUM)
    status, out, err = run(capsys, "bench", scene, "--quick", "--json")
    envelope = json.loads(out)
    assert status == 2 and envelope["error"]["key"] == "inputs", envelope["error"]
    assert "no value for u" in envelope["error"]["message"]


def test_a_sweep_over_an_input_is_refused_and_over_its_parameter_is_not(capsys, tmp_path):
    scene = tmp_path / "pendulum.toml"
    scene.write_text(PENDULUM)
    status, out, err = run(capsys, "linearize", scene, "--sweep", "u=0.1:0.9:3", "--json")
    envelope = json.loads(out)
    assert status == 2 and "'u' is an input" in envelope["error"]["message"]
    status, out, err = run(capsys, "linearize", scene, "--sweep", "u0=0.1:0.9:3", "--json")
    sweep = json.loads(out)["result"]["sweep"]
    # x = asin(u0): A = [[0, 1], [-cos x, -c]], eigenvalues -c/2 +- i sqrt(cos x - c^2/4)
    for u0, ev in zip(sweep["values"], sweep["eigenvalues"]):
        omega = np.sqrt(np.sqrt(1 - u0 ** 2) - 0.1 ** 2 / 4)
        assert abs(ev[0][0] + 0.05) < 1e-12 and abs(abs(ev[0][1]) - omega) < 1e-12


LONG_FORCES = """
name = "a cart with a long name for its implicit form and long forces on every coordinate"
coordinates = ["x", "y", "theta", "phiL", "phiR"]
parameters = { c = 0.5, k = 2.0 }
lagrangian = "(x_dot**2 + y_dot**2 + theta_dot**2 + phiL_dot**2 + phiR_dot**2)/2"
constraints = ["x_dot - cos(theta)*phiL_dot", "y_dot - sin(theta)*phiR_dot"]
forces = { x = "-k*x*cos(theta)*sin(theta)*cos(phiL)*sin(phiR)*x_dot*y_dot*theta_dot*phiL_dot", y = "-c*y_dot", phiR = "-k*phiR*cos(phiL)*cos(theta)*sin(theta)*cos(phiR)*sin(phiL)*x_dot*y_dot*phiR_dot" }
"""


def test_derive_wraps_and_aligns_the_forces_and_the_implicit_header(capsys, tmp_path,
                                                                     monkeypatch):
    """At COLUMNS=80 every line of derive's text fits, the Q rows have their '=' in one
    column (as the F rows), and a wrapped line never ends inside a name."""
    monkeypatch.setenv("COLUMNS", "80")
    path = tmp_path / "long.toml"
    path.write_text(LONG_FORCES)
    status, out, _ = run(capsys, "derive", path)
    assert status == 0
    lines = out.splitlines()
    assert all(len(line) <= 80 for line in lines), [x for x in lines if len(x) > 80]
    assert lines[0].startswith("a cart with a long name") and lines[1].startswith("  ")
    block = lines[lines.index("generalized forces Q (in F; d/dt dL/dv - dL/dq = Q - mu^T "
                              "lambda):") + 1:]
    rows = [x for x in block if x.startswith("  Q[")]
    assert [x.split("=")[0].strip() for x in rows] == ["Q[x]", "Q[y]", "Q[theta]", "Q[phiL]",
                                                       "Q[phiR]"]
    assert len({x.index(" = ") for x in rows}) == 1
    # the long Q[x] continues on lines aligned under its first character, and every
    # name on every line of the report is whole
    i = block.index(rows[0])
    start = rows[0].index("-k*")
    assert block[i + 1].startswith(" " * start) and block[i + 1][start] != " "
    names = {"x", "y", "k", "c", "theta", "phiL", "phiR", "cos", "sin", "x_dot", "y_dot",
             "theta_dot", "phiL_dot", "phiR_dot", "lambda_1", "lambda_2"}
    for x in lines[3:]:
        for word in re.findall(r"[A-Za-z_]\w*", x.split(" =  ", 1)[-1]):
            assert word in names or not x.startswith(" "), (word, x)
    # the implicit form of the drive (W not inverted): its header wraps too
    status, out, _ = run(capsys, "derive", DRIVE)
    lines = out.splitlines()
    assert status == 0 and all(len(line) <= 80 for line in lines)
    assert "dynamics in implicit form" in lines[0] and lines[1].startswith("  ")
    assert "phiR_ddot)" in lines[1] + lines[2]
