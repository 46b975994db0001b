"""Exit codes and messages as a user meets them (the command in a subprocess, or in
process where a failure has to be planted).

0 success, 1 internal failure, 2 bad input or usage, 3 the computation did not
succeed; every message is one line in the command's own vocabulary, and with
``--json`` every exit prints exactly one envelope that the shipped schema accepts,
its ``error`` naming the kind of failure and the option or key at fault.
"""

import contextlib
import importlib
import io
import json
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest

import nhham

cli_main = importlib.import_module("nhham.cli.main")  # the module (nhham.cli.main is also a function)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
HOSTILE = Path(__file__).resolve().parent / "scenes_hostile"
BAD = ROOT / "tests" / "system" / "scenes_bad"
DISK = EXAMPLES / "rolling_disk.toml"


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


# ------------------------------------------------------ the envelope on failure
def in_process(*argv):
    """(exit status, stdout, stderr) of ``nhham ARGV`` run by ``main`` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli_main.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def one_envelope(stdout, schema):
    """stdout is exactly one JSON document, an envelope the schema accepts."""
    env = json.loads(stdout)  # two documents, or text around one, would not parse
    jsonschema.validate(env, schema)
    return env


def assert_failure(rc, out, err, schema, status, kind, key):
    assert rc == status, err
    assert len(err.strip().splitlines()) == 1, err
    assert_clean_lines(err)
    env = one_envelope(out, schema)
    assert env["error"]["kind"] == kind and env["error"]["key"] == key, env["error"]
    assert env["error"]["message"] in err  # the same words on stderr
    return env


# The values of issue 21 that failed with an internal error after the work or were
# silently used, with the option the refusal must name. The scene does not exist:
# the option is refused before anything is loaded.
REFUSED = [
    ("simulate", "--atol", "-1"), ("simulate", "--atol", "nan"),
    ("simulate", "--max-step", "0"), ("simulate", "--max-step", "-1"),
    ("simulate", "--budget", "nan"), ("simulate", "--budget", "inf"),
    ("simulate", "--budget", "1e20"), ("classify", "--budget", "0"),
    ("compare", "--samples", "0"), ("compare", "--samples", "-1"),
    ("bench", "--reference-digits", "0"), ("bench", "--reference-digits", "-3"),
    ("simulate", "--output", "/nonexistent/dir/x.csv"),
    ("simulate", "--rtol", "0"), ("simulate", "--rtol", "-1"), ("simulate", "--rtol", "1e-16"),
    ("simulate", "--t-end", "-1"), ("bench", "--t-end", "inf"),
    ("classify", "--precision", "0"), ("derive", "--precision", "-5"),
    ("simulate", "--plot", "trajectory.nosuchformat"),
    ("classify", "--depth", "2"), ("classify", "--positive", "m"),
    ("linearize", "--sweep", "v=10:0:5"), ("linearize", "--plot", "locus.png"),
]


@pytest.mark.parametrize("command,option,value", REFUSED)
def test_option_values_are_refused_before_any_work(command, option, value, schema):
    rc, out, err = in_process(command, "no_such_scene.toml", option, value, "--json")
    env = assert_failure(rc, out, err, schema, 2, "usage", option)
    assert "no_such_scene" not in err  # refused before the scene was read
    assert env["result"] is None and env["scene"] is None and env["command"] == command
    rc, out, err = in_process(command, "no_such_scene.toml", option, value)
    assert rc == 2 and out == "" and err.startswith(f"nhham {command}: error: {option}")


def test_the_fixed_step_may_not_exceed_the_time_span(schema):
    """rattle with --step 1e300 took one step of 10 (x = 10.86 where the motion gives
    -1.088): refused against the command line's --t-end and the scene's t_end alike."""
    rc, out, err = in_process("simulate", "no_such_scene.toml", "--method", "rattle",
                              "--step", "1e300", "--t-end", "10", "--json")
    assert_failure(rc, out, err, schema, 2, "usage", "--step")
    rc, out, err = in_process("simulate", DISK, "--method", "rattle", "--step", "1e300",
                              "--json")  # t_end = 10 from the scene's [simulate]
    env = assert_failure(rc, out, err, schema, 2, "usage", "--step")
    assert "must not exceed the time span t_end = 10" in env["error"]["message"]
    assert env["scene"]["name"] == "vertical rolling disk"


def test_options_that_would_be_ignored_are_refused(schema):
    rc, out, err = in_process("classify", DISK, "--latex", "--json")
    assert_failure(rc, out, err, schema, 2, "usage", "--latex")
    rc, out, err = in_process("simulate", DISK, "--method", "reference", "--rtol", "1e-6",
                              "--json")
    env = assert_failure(rc, out, err, schema, 2, "usage", "--rtol")
    assert "not to reference" in env["error"]["message"]


def test_usage_errors_print_the_envelope(schema):
    rc, out, err = in_process("bogus", "x.toml", "--json")
    env = assert_failure(rc, out, err, schema, 2, "usage", "command")
    assert env["command"] is None
    rc, out, err = in_process("classify", "--json")
    assert_failure(rc, out, err, schema, 2, "usage", "scene")
    rc, out, err = in_process("simulate", DISK, "--method", "euler", "--json")
    assert_failure(rc, out, err, schema, 2, "usage", "--method")
    rc, out, err = in_process("simulate", DISK, "--frobnicate", "--json")
    assert_failure(rc, out, err, schema, 2, "usage", "--frobnicate")


@pytest.mark.parametrize("scene,key", [
    ("imaginary_log.toml", "lagrangian"), ("fullwidth_name.toml", "lagrangian"),
    ("sign_in_lagrangian.toml", "lagrangian"), ("huge_expansion.toml", "lagrangian"),
    ("unknown_name.toml", "lagrangian"),
])
def test_bad_scenes_print_the_envelope(scene, key, schema):
    rc, out, err = in_process("derive", BAD / scene, "--json")
    env = assert_failure(rc, out, err, schema, 2, "input", key)
    assert env["result"] is None and env["scene"] is None


def test_a_bad_table_stops_only_the_commands_that_read_it(schema):
    """[simulate] is read by simulate (exit 2 naming simulate.rtol), not by derive."""
    scene = BAD / "simulate_rtol_below_epsilon.toml"
    rc, out, err = in_process("derive", scene, "--json")
    assert rc == 0 and one_envelope(out, schema)["error"] is None
    rc, out, err = in_process("simulate", scene, "--json")
    env = assert_failure(rc, out, err, schema, 2, "input", "simulate.rtol")
    assert env["result"] is None


def test_holonomic_constraint_without_real_solution_is_bad_input(schema):
    """derive and compare find no point of M_1 (x^2 + y^2 + 1 = 0): exit 2, not an
    internal failure; classify reports the constraint set inconsistent."""
    scene = HOSTILE / "holonomic_no_real_solution.toml"
    for command in ("derive", "compare"):
        rc, out, err = in_process(command, scene, "--json")
        env = assert_failure(rc, out, err, schema, 2, "input", None)
        assert "x**2 + y**2 + 1" in env["error"]["message"]
        assert env["scene"]["coordinates"] == ["x", "y", "z"]
    rc, out, err = in_process("classify", scene, "--json")
    assert rc == 0 and one_envelope(out, schema)["result"]["status"] == "inconsistent"


def test_redundant_constraint_advice_is_the_commands_option(schema):
    rc, out, err = in_process("derive", BAD / "dependent_constraints.toml", "--json")
    assert_failure(rc, out, err, schema, 2, "input", "constraints[1]")
    assert "run with --drop-redundant" in err and "drop_redundant=True" not in err
    rc, out, err = in_process("derive", BAD / "dependent_constraints.toml", "--drop-redundant",
                              "--json")
    assert rc == 0, err
    assert one_envelope(out, schema)["error"] is None


def test_internal_failure_prints_the_envelope(monkeypatch, schema):
    def boom(args, steps):
        cli_main._load(args, steps)
        raise RuntimeError("planted\nfailure")

    monkeypatch.setitem(cli_main.COMMANDS, "classify", boom)
    rc, out, err = in_process("classify", DISK, "--json")
    env = assert_failure(rc, out, err, schema, 1, "internal", None)
    assert env["error"]["message"].startswith("RuntimeError: planted failure")
    assert env["scene"]["name"] == "vertical rolling disk" and env["result"] is None

    def interrupted(args, steps):
        raise KeyboardInterrupt

    monkeypatch.setitem(cli_main.COMMANDS, "classify", interrupted)
    rc, out, err = in_process("classify", DISK, "--json")
    assert_failure(rc, out, err, schema, 130, "interrupted", None)


def test_budget_and_failed_runs_print_the_envelope(schema):
    rc, out, err = in_process("classify", EXAMPLES / "snakeboard.toml", "--budget", "0.05",
                              "--json")
    env = assert_failure(rc, out, err, schema, 3, "budget", None)
    assert "ran out during" in env["error"]["message"] and env["result"] is None
    rc, out, err = in_process("simulate", EXAMPLES / "paper_3_1.toml", "--json")
    env = assert_failure(rc, out, err, schema, 3, "failed", None)
    assert env["result"]["success"] is False  # the run's result says how it stopped


QUARTIC = """name = "not quadratic in v"
coordinates = ["x", "y"]
lagrangian = "x_dot**4/12 + x_dot**2/2 + y_dot**2/2 + x_dot*y_dot/4"
constraints = ["y_dot - x*x_dot"]
"""


def test_a_computation_that_cannot_be_carried_out_exits_3_saying_what_to_do(tmp_path, schema):
    """p_x = x'^3/3 + x' + y'/4 couples x' and y' through a cubic: no closed-form v(q, p),
    so the Hamiltonian side cannot be formed. A ComputationError, not the user's fault
    and not a bug: exit 3 (it was exit 1, "nhham: failed: NoClosedFormInverseError"),
    kind "computation", the one line naming the Lagrangian side as what works."""
    scene = tmp_path / "quartic.toml"
    scene.write_text(QUARTIC, encoding="utf-8")
    rc, out, err = in_process("derive", scene, "--side", "hamiltonian", "--json")
    env = assert_failure(rc, out, err, schema, 3, "computation", "lagrangian")
    assert env["result"] is None
    assert err.startswith("nhham: p = dL/dv could not be solved for v in closed form")
    assert "derive --side lagrangian" in err and "Traceback" not in err
    rc, out, err = in_process("derive", scene)   # the Lagrangian side needs no inverse
    assert rc == 0, err
