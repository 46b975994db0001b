"""End-to-end tests of the ``nhham`` command on the bundled examples.

Each expected value is derived by hand in the docstring of its test (or comes
from tests/paper_reference.py); the command runs in a subprocess exactly as a
user runs it.
"""

import json
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def run(*args, check_status=0, cwd=None):
    proc = subprocess.run([sys.executable, "-m", "nhham", *map(str, args)], capture_output=True,
                          text=True, timeout=300, cwd=cwd or ROOT)
    assert proc.returncode == check_status, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    return proc


def run_json(*args, check_status=0):
    """The ``result`` of the command's JSON envelope (exactly one JSON object).

    In-process and cached (conftest.run_inprocess): the contract tests run the same
    commands; the subprocess path is covered by ``run`` below.
    """
    from conftest import run_inprocess

    rc, out, err = run_inprocess(*map(str, args), "--json")
    assert rc == check_status, (rc, out, err)
    assert "Traceback" not in err
    env = json.loads(out)
    assert env["command"] == args[0]
    return env["result"]


def parse(text):
    """Scene names are plain symbols here (no parameter named I, E, S or N)."""
    return sp.sympify(text)


# ---------------------------------------------------------------- classify
def test_classify_rolling_disk():
    """C regular (det = (I2 + m R^2)/(I2 m^2) != 0), one stage, M_f = M_1.
    On T*Q: phi_1 = p_x/m - R cos(th) p_phi/I2, phi_2 = p_y/m - R sin(th) p_phi/I2
    depend on theta but not on p_theta, so {phi_1, phi_2} = 0: both first class.
    The distribution is not involutive (the disk can reach any x, y, theta, phi)."""
    d = run_json("classify", EXAMPLES / "rolling_disk.toml")
    assert (d["n"], d["m"], d["regular"], d["rank_c"]) == (4, 2, True, 2)
    assert d["status"] == "determined" and d["free_multipliers"] == 0
    assert len(d["stages"]) == 1 and len(d["final_constraints"]) == 2
    assert d["integrable"] is False and d["redundant"] == []
    assert (d["first_class"], d["second_class"]) == (2, 0)


def test_classify_paper_3_1():
    """Z(phi) = 0 and xi_L(phi) = 0: C = 0, the multiplier stays free, one stage;
    phi = v2 + v3 = d(q2 + q3)/dt is integrable; alone, phi is first class."""
    d = run_json("classify", EXAMPLES / "paper_3_1.toml")
    assert (d["regular"], d["rank_c"], d["status"], d["free_multipliers"]) == \
        (False, 0, "underdetermined", 1)
    assert d["integrable"] is True
    assert (d["first_class"], d["second_class"]) == (1, 0)


def test_classify_paper_3_2():
    """Stages v1 + v3 -> q1 -> v1; M_3 = {q1 = v1 = v3 = 0}; lambda determined.
    On T*Q (p1 = v1, p2 = v2, p3 = -v3): chi = (p1 - p3, q1, p1),
    B = [[0, -1, 0], [1, 0, 1], [0, -1, 0]] of rank 2: two second class, and
    chi_1 - chi_3 = -p3 is first class although chi_1, chi_3 are each second class."""
    d = run_json("classify", EXAMPLES / "paper_3_2.toml")
    assert d["status"] == "determined" and len(d["stages"]) == 3
    q1, v1, v2, v3 = sp.symbols("q1 q1_dot q2_dot q3_dot")
    final = [parse(c) for c in d["final_constraints"]]
    assert len(final) == 3
    on_M3 = {q1: 0, v1: 0, v3: 0}
    assert all(sp.simplify(c.subs(on_M3)) == 0 for c in final)
    # ... and they cut out exactly M_3: their Jacobian in (q1, v1, v3) has rank 3.
    assert sp.Matrix(final).jacobian([q1, v1, v3]).rank() == 3
    assert (d["first_class"], d["second_class"]) == (1, 2)
    (combo,) = [parse(c) for c in d["first_class_combinations"]]
    p1, p3 = sp.symbols("p_q1 p_q3")
    assert combo.free_symbols <= {p1, p3, sp.Symbol("q1"), sp.Symbol("p_q2"), sp.Symbol("q2"),
                                  sp.Symbol("q3")}
    # the combination is a nonzero multiple of p3 on M_f (q1 = 0, p1 = 0):
    on = combo.subs({sp.Symbol("q1"): 0, p1: 0})
    assert on != 0 and sp.simplify(on / p3).free_symbols == set()


def test_classify_pendulum_pair_is_second_class():
    """g = x^2 + y^2 - l^2 and g^c: {g, g^c_H} = 4 (x^2 + y^2)/m != 0: rank 2."""
    d = run_json("classify", EXAMPLES / "pendulum_cartesian.toml")
    assert d["status"] == "determined"
    assert (d["first_class"], d["second_class"]) == (0, 2)
    assert d["integrable"] is True


def test_classify_paper_4_1():
    """h1, h1^c, phi_2: {h1, h1^c} = 2 l^2, {h1, phi_2} = 0; a 3 x 3 antisymmetric B
    has rank 2 here: two second class, one first-class combination."""
    d = run_json("classify", EXAMPLES / "paper_4_1_two_particle_rod.toml")
    assert d["status"] == "determined" and d["regular"] is True
    assert (d["first_class"], d["second_class"]) == (1, 2)
    assert len(d["first_class_combinations"]) == 1


def test_classify_redundant_disk_reports_and_drops():
    d = run_json("classify", EXAMPLES / "redundant_disk.toml")
    assert d["redundant"] == ["constraints[2]"]
    assert (d["m"], d["rank_c"], d["status"]) == (2, 2, "determined")


def test_classify_nonholonomic_particle():
    """z' = y x': d(dz - y dx) ^ (dz - y dx) = -dy ^ dx ^ dz != 0: not integrable."""
    d = run_json("classify", EXAMPLES / "nonholonomic_particle.toml")
    assert d["integrable"] is False and d["status"] == "determined"
    assert (d["first_class"], d["second_class"]) == (1, 0)


def test_classify_text_output_is_readable():
    out = run("classify", EXAMPLES / "rolling_disk.toml").stdout
    assert "status" in out and "determined" in out and "rank C on M_1" in out
    for raw in ("Matrix(", "Symbol(", "<nhham", "object at 0x", "Decision("):
        assert raw not in out


def test_verbose_lists_derivations_and_decisions():
    proc = run("classify", EXAMPLES / "rolling_disk.toml", "--verbose")
    assert "derived (in order)" in proc.stderr and "ms" in proc.stderr
    assert "stage 1" in proc.stderr


# ------------------------------------------------------------------ derive
def test_derive_rolling_disk_json_matches_hand_values():
    """P(xi_L) = (v, -R th' ph' sin th, R th' ph' cos th, 0, 0) and
    lambda = m R th' ph' (sin th, -cos th) (paper Example 2.1; see test_lagrangian)."""
    d = run_json("derive", EXAMPLES / "rolling_disk.toml")
    assert d["state"] == ["x", "y", "theta", "phi", "x_dot", "y_dot", "theta_dot", "phi_dot"]
    names = {n: sp.Symbol(n) for n in d["state"] + ["m", "R", "I1", "I2"]}
    th, thd, phd = names["theta"], names["theta_dot"], names["phi_dot"]
    params = tomllib.loads((EXAMPLES / "rolling_disk.toml").read_text())["parameters"]
    m, R = params["m"], params["R"]
    rng = np.random.default_rng(0)
    for _ in range(3):
        pt = {names[n]: rng.normal() for n in d["state"]}
        pt.update({names[k]: v for k, v in params.items() if k in names})
        expected = [pt[names[n]] for n in d["state"][4:]] + [
            -R * pt[thd] * pt[phd] * np.sin(pt[th]), R * pt[thd] * pt[phd] * np.cos(pt[th]), 0, 0]
        got = [float(parse(f).subs(pt)) for f in d["field"]]
        assert np.allclose(got, expected, atol=1e-12)
        lam = [float(parse(f).subs(pt)) for f in d["multipliers"]]
        assert np.allclose(lam, [m * R * pt[thd] * pt[phd] * np.sin(pt[th]),
                                 -m * R * pt[thd] * pt[phd] * np.cos(pt[th])], atol=1e-12)
    assert d["free_multiplier_symbols"] == []
    assert len(d["constraint_matrix"]) == 2 and len(d["constraint_matrix"][0]) == 2


def test_derive_paper_3_1_has_free_multiplier():
    """C = 0: the dynamics is xi_L + lambda_1 Z with Z = -d/dv2 + d/dv3."""
    d = run_json("derive", EXAMPLES / "paper_3_1.toml")
    assert d["free_multiplier_symbols"] == ["lambda_1"]
    lam = sp.Symbol("lambda_1")
    field = [parse(f) for f in d["field"]]
    assert [sp.diff(f, lam) for f in field[3:]] == [0, -1, 1]


def test_derive_latex_and_hamiltonian_side():
    out = run("derive", EXAMPLES / "rolling_disk.toml", "--latex").stdout
    assert r"\begin{aligned}" in out and r"\dot" in out
    d = run_json("derive", EXAMPLES / "rolling_disk.toml", "--side", "hamiltonian")
    assert d["state"][4:] == ["p_x", "p_y", "p_theta", "p_phi"]
    assert len(d["field"]) == 8


# ----------------------------------------------------------------- compare
@pytest.mark.parametrize("scene", ["rolling_disk.toml", "paper_4_1_two_particle_rod.toml",
                                   "pendulum_cartesian.toml"])
def test_compare_agrees(scene):
    d = run_json("compare", EXAMPLES / scene)
    assert d["agree"] is True
    assert d["max_abs_difference"] <= d["tolerance"]
    assert d["samples"] >= 1 and isinstance(d["exact"], bool)


# --------------------------------------------------------------- bad input
def test_bad_input_exits_2_with_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('coordinates = ["x"]\nlagrangian = "x_dot**2/2 + __import__(\'os\')"\n')
    proc = run("classify", bad, check_status=2)
    assert proc.stderr.count("\n") == 1 and "lagrangian" in proc.stderr
    assert proc.stdout == ""


def test_missing_file_exits_2(tmp_path):
    proc = run("derive", tmp_path / "nope.toml", check_status=2)
    assert "nope.toml" in proc.stderr


def test_usage_error_exits_2():
    proc = subprocess.run([sys.executable, "-m", "nhham", "frobnicate"], capture_output=True,
                          text=True)
    assert proc.returncode == 2


@pytest.mark.skipif(shutil.which("nhham") is None, reason="console script not installed")
def test_console_script_installed():
    proc = subprocess.run(["nhham", "classify", str(EXAMPLES / "rolling_disk.toml"), "--json"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and json.loads(proc.stdout)["result"]["status"] == "determined"


# ---------------------------------------------------------------- simulate
def _disk_closed_form(t, init, R):
    """theta' and phi' are constant (lambda_1 cos + lambda_2 sin = 0, theta is
    cyclic), so x' = R phi' cos(theta0 + theta' t) integrates to
    x = x0 + (R phi'/theta') (sin(theta) - sin(theta0)), likewise y."""
    th0, w, s = init["theta"], init["theta_dot"], init["phi_dot"]
    th = th0 + w * t
    r = R * s / w
    return [init["x"] + r * (np.sin(th) - np.sin(th0)), init["y"] - r * (np.cos(th) - np.cos(th0)),
            th, init["phi"] + s * t]


@pytest.mark.parametrize("method", [[], ["--method", "rattle", "--step", "0.005"]])
def test_simulate_rolling_disk_against_closed_form(method, tmp_path):
    scene = tomllib.loads((EXAMPLES / "rolling_disk.toml").read_text())
    d = run_json("simulate", EXAMPLES / "rolling_disk.toml", *method, "--output",
                 tmp_path / "traj.csv")
    for key in ("status", "t_final", "y_final", "constraint_residual_max", "energy_drift",
                "nfev", "wall_time_s"):
        assert key in d
    assert d["success"] is True and d["status"] == "success" and d["status_code"] == 0
    assert d["t_final"] == scene["simulate"]["t_end"]
    expected = _disk_closed_form(d["t_final"], scene["initial"], scene["parameters"]["R"])
    tol = 1e-7 if method else 1e-8
    assert np.allclose(d["y_final"][:4], expected, atol=tol)
    assert d["constraint_residual_max"] < (1e-12 if method else 1e-9)
    rows = (tmp_path / "traj.csv").read_text().splitlines()
    assert rows[0].startswith("t,x,y,theta,phi,x_dot")
    assert len(rows) > 10


def test_simulate_refuses_inconsistent_initial_data(tmp_path):
    text = (EXAMPLES / "rolling_disk.toml").read_text().replace("x_dot = 2.0", "x_dot = 2.5")
    scene = tmp_path / "bad_initial.toml"
    scene.write_text(text)
    proc = run("simulate", scene, check_status=2)
    assert "constraints[0] = 0.5" in proc.stderr and "--project-initial" in proc.stderr
    d = run_json("simulate", scene, "--project-initial")
    assert d["success"] and d["constraint_residual_max"] < 1e-9




def test_simulate_reports_the_contact_forces_of_a_scene():
    """examples/disc_on_ground.toml names its contact point: the JSON has the ground's
    force at every stored time, its residual at rounding level (the force itself is
    checked against m g and Newton's law in tests/numerics/test_contact_forces.py); a
    scene without [contacts] has none."""
    d = run_json("simulate", EXAMPLES / "disc_on_ground.toml", "--t-end", "0.5")
    forces = d["contact_forces"]
    assert d["contact_forces"]["t"][-1] == 0.5 and set(forces) == {"t", "ground"}
    ground = forces["ground"]
    assert len(ground["force"]) == len(forces["t"]) and ground["rank"] == 3
    assert ground["max_residual"] < 1e-10
    assert all(abs(f[2]) > 0 for f in ground["force"])
    d = run_json("simulate", EXAMPLES / "rolling_disk.toml")
    assert d["contact_forces"] is None


def test_derive_gives_the_contact_forces_in_implicit_form():
    """derive on a scene with [contacts]: per point the constraints, their multipliers and
    J_P = dv_P/dv, here d(v_P)/d(x_dot, ..., psi_dot) of the disc whose first row starts
    (1, 0, 0) (v_P = v_C + omega x (P - C)); the Hamiltonian side has none."""
    d = run_json("derive", EXAMPLES / "disc_on_ground.toml")
    ground = d["contact_forces"]["ground"]
    assert ground["constraints"] == ["holonomic[0]", "constraints[0]", "constraints[1]"]
    assert ground["multipliers"] == ["lambda_1", "lambda_2", "lambda_3"]
    J = ground["velocity_jacobian"]
    assert len(J) == 3 and all(len(row) == 6 for row in J)
    assert J[0][:3] == ["1", "0", "0"] and J[2][:3] == ["0", "0", "1"]
    assert run_json("derive", EXAMPLES / "disc_on_ground.toml", "--side",
                    "hamiltonian")["contact_forces"] is None
    assert run_json("derive", EXAMPLES / "rolling_disk.toml")["contact_forces"] is None
