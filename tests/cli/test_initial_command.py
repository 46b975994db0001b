"""[initial] in the commands: checked only where it is used (simulate, bench), with a short
message; the values left out solved and named (issue 34, items 3 and 4).

The rolling disk of examples/rolling_disk.toml (R = 1): theta' = 1 and phi' = 2 stay
constant, x' = R cos(theta) phi', y' = R sin(theta) phi', so from the origin with
theta = 0: x(t) = 2 sin t, y(t) = 2 (1 - cos t) (by hand).
"""

from __future__ import annotations

import json
import math

import pytest

from tests.cli.conftest import EXAMPLES, run_inprocess

DISK = (EXAMPLES / "rolling_disk.toml").read_text()


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    d = tmp_path_factory.mktemp("initial")
    off = d / "off.toml"  # x_dot = 2.5: constraints[0] = 2.5 - cos(0) 2 = 0.5
    off.write_text(DISK.replace("x_dot = 2.0", "x_dot = 2.5"))
    partial = d / "partial.toml"  # x_dot, y_dot left out
    partial.write_text(DISK.replace("x_dot = 2.0\n", "").replace("y_dot = 0.0\n", ""))
    return {"off": str(off), "partial": str(partial)}


@pytest.mark.parametrize("command", ["classify", "derive", "compare"])
def test_commands_that_do_not_integrate_ignore_initial(scenes, command):
    rc, out, err = run_inprocess(command, scenes["off"], "--json")
    assert rc == 0, err
    assert json.loads(out)["error"] is None


@pytest.mark.parametrize("command", ["simulate", "bench"])
def test_commands_that_integrate_refuse_it_in_one_short_line(scenes, command):
    rc, out, err = run_inprocess(command, scenes["off"], "--t-end", "0.1")
    assert rc == 2 and out == ""
    assert err.count("\n") == 1 and len(err) < 400
    assert "[initial] violates constraints[0] = 0.5 (tolerance" in err
    assert "--project-initial" in err and "leave the dependent velocities" in err
    assert "cos(theta)" not in err  # the constraint by its key, not its expression


def test_project_initial_still_projects(scenes):
    rc, out, err = run_inprocess("simulate", scenes["off"], "--project-initial", "--t-end",
                                 "0.1", "--json")
    assert rc == 0, err


def test_simulate_solves_the_velocities_left_out_and_names_them(scenes):
    rc, out, err = run_inprocess("simulate", scenes["partial"], "--json")
    assert rc == 0, err
    env = json.loads(out)
    assert "initial: solved from the constraints: x_dot = 2, y_dot = 0" in env["warnings"]
    state = env["result"]["state"]
    y = dict(zip(state, env["result"]["y_final"]))
    t = env["result"]["t_final"]
    assert t == 10.0
    assert y["x"] == pytest.approx(2 * math.sin(t), abs=1e-8)
    assert y["y"] == pytest.approx(2 * (1 - math.cos(t)), abs=1e-8)


def test_bench_names_the_values_solved(scenes):
    rc, out, err = run_inprocess("bench", scenes["partial"], "--quick", "--t-end", "0.5")
    assert rc == 0, err
    assert "nhham: warning: initial: solved from the constraints: x_dot = 2, y_dot = 0" in err


def test_the_library_check_is_short_too():
    from nhham.errors import InconsistentInitialDataError
    from nhham.system.scene import loads_scene

    with pytest.raises(InconsistentInitialDataError) as info:
        loads_scene(DISK.replace("x_dot = 2.0", "x_dot = 2.5"), source="disk.toml")
    assert str(info.value).startswith("disk.toml: [initial] violates constraints[0] = 0.5 ")
    assert info.value.key == "constraints[0]"
