"""Exit codes and messages as a user meets them (the command in a subprocess).

0 success, 1 internal failure, 2 bad input or usage, 3 the computation did not
succeed; every message is one line in the command's own vocabulary.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import nhham

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def run(*args):
    return subprocess.run([sys.executable, "-m", "nhham", *map(str, args)], capture_output=True,
                          text=True, timeout=300, cwd=ROOT)


def assert_clean_lines(stderr):
    """Each stderr line is one of nhham's own: no Python warning text, no file paths."""
    for line in stderr.splitlines():
        assert line.startswith("nhham"), line
    for raw in ("Traceback", "Warning:", ".py:", "warnings.warn"):
        assert raw not in stderr, stderr


def test_failed_simulation_exits_3_with_one_line_saying_what_to_do():
    """Paper Example 3.1: C = 0 on M_1, the multiplier is free, so the projected
    field is not defined: the run stops at t = 0 and must not pass for a success."""
    proc = run("simulate", EXAMPLES / "paper_3_1.toml")
    assert proc.returncode == 3
    assert_clean_lines(proc.stderr)
    last = proc.stderr.splitlines()[-1]
    assert "lambda_1" in last and "nhham classify" in last and "t = 0" in last
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("nhham: warning:")]
    assert len(warnings) >= 1  # cond(C) = inf, one line


def test_failed_simulation_json_still_has_the_envelope():
    proc = run("simulate", EXAMPLES / "paper_3_1.toml", "--json")
    assert proc.returncode == 3
    env = json.loads(proc.stdout)
    r = env["result"]
    assert r["success"] is False and r["status"] == "singular"
    assert r["status_code"] == -3 and r["t_final"] == 0.0
    assert env["warnings"] and all("\n" not in w for w in env["warnings"])
    assert len(proc.stderr.strip().splitlines()) == 1  # the reason; warnings are in the JSON


DEGENERATE = """name = "degenerate at x = 0"
coordinates = ["x", "y"]
lagrangian = "x**2*x_dot**2/2 + y_dot**2/2"
constraints = ["y_dot - 1"]
[initial]
x = 0.0
y = 0.5
x_dot = 1.0
y_dot = 1.0
"""


def _snakeboard_at_the_singular_steering(tmp_path):
    """The bundled snakeboard started at phi = pi/2 (both axles parallel: the two rows of
    mu are opposite), with (x', y') = (0, 0.5) on both constraints there."""
    text = (EXAMPLES / "snakeboard.toml").read_text()
    for old, new in (("phi = 0.0", "phi = 1.5707963267948966"), ("x_dot = 1.0", "x_dot = 0.0"),
                     ("y_dot = 0.0", "y_dot = 0.5")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "snakeboard_pi_2.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("scene, words", [
    ("degenerate", ["at t = 0: W = d2L/dv2 is singular", "not regular at x = 0, y = 0.5",
                    "start from other [initial] data"]),
    ("snakeboard", ["one-forms are dependent (rank of mu 1 of 2)", "phi = 1.5708",
                    "start from other [initial] data"]),
])
def test_a_run_stopped_by_a_singularity_says_what_is_singular_and_where(tmp_path, scene,
                                                                         words):
    """W singular at the initial state (not C, not free multipliers), or the constraints
    dependent at a configuration: the one line names it, with the coordinates."""
    if scene == "degenerate":
        path = tmp_path / "degenerate.toml"
        path.write_text(DEGENERATE)
    else:
        path = _snakeboard_at_the_singular_steering(tmp_path)
    proc = run("simulate", path)
    assert proc.returncode == 3, proc.stderr
    assert_clean_lines(proc.stderr)
    last = proc.stderr.splitlines()[-1]
    for w in words:
        assert w in last, (w, last)
    assert "free multiplier" not in last and "Radau" not in last


@pytest.mark.parametrize("args,words", [
    (["simulate", "rolling_disk.toml", "--precision", "30"],
     ["simulate has no option --precision", "classify, derive, compare"]),
    (["bench", "rolling_disk.toml", "--precision", "30"], ["bench has no option --precision"]),
    (["simulate", "rolling_disk.toml", "--method", "rattle"], ["--step DT"]),
    (["simulate", "rolling_disk.toml", "--step", "0.1"], ["--step applies to the fixed-step"]),
    (["simulate", "rolling_disk.toml", "--method", "rattle", "--step", "0.1", "--rtol", "1e-6"],
     ["--rtol applies to the adaptive"]),
    (["simulate", "rolling_disk.toml", "--method", "rattle", "--step", "0.1", "--projection"],
     ["keeps the constraints itself"]),
    (["simulate", "rolling_disk.toml", "--method", "euler"], ["invalid choice", "DOP853"]),
    (["derive", "rolling_disk.toml", "--side", "both"], ["invalid choice"]),
    (["classify", "no_such_scene.toml"], ["no_such_scene.toml"]),
])
def test_refused_options_exit_2_with_one_line(args, words):
    if not args[1].startswith("no_such"):
        args = [args[0], EXAMPLES / args[1], *args[2:]]
    proc = run(*args)
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert_clean_lines(proc.stderr)
    for w in words:
        assert w in proc.stderr, (w, proc.stderr)
    assert "step=" not in proc.stderr  # no Python keyword arguments in messages


def test_version():
    proc = run("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"nhham {nhham.__version__}"


@pytest.mark.parametrize("command", ["classify", "derive", "compare", "simulate", "bench"])
def test_help_has_an_example_and_defaults(command):
    proc = run(command, "--help")
    assert proc.returncode == 0
    out = proc.stdout
    assert f"example: nhham {command} examples/" in out and "exit status" in out
    if command == "simulate":
        assert "DOP853, RK45" in out and "default" in out and "--project-initial" in out
        assert "M_1" in out and "M_f" not in out  # what --project-initial really does
    if command in ("classify", "derive", "compare"):
        assert "--precision" in out and "--latex" in out
    else:
        assert "--precision" not in out


def test_precision_reaches_the_hamiltonian_side():
    """derive --side hamiltonian --precision 30 runs (the option is passed on, not ignored)."""
    proc = run("derive", EXAMPLES / "rolling_disk.toml", "--side", "hamiltonian",
               "--precision", "30", "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["result"]["side"] == "hamiltonian"


@pytest.mark.parametrize("method", ["rattle", "Radau"])
def test_free_multiplier_named_whatever_the_method(method):
    """Paper Example 3.1 with RATTLE (the multiplier guess at the initial state fails) and
    Radau (its batched Jacobian reports the failure as non-finite): exit 3, one line
    naming lambda_1, never exit 1."""
    args = ["--step", "0.1"] if method == "rattle" else []
    proc = run("simulate", EXAMPLES / "paper_3_1.toml", "--method", method, *args)
    assert proc.returncode == 3, proc.stderr
    assert_clean_lines(proc.stderr)
    assert "free multiplier lambda_1" in proc.stderr.splitlines()[-1]
