"""``--set NAME=VALUE``: a parameter's value for one run, on every command (issue 34,
item 5; on sweep every point has it, and a name cannot be both set and swept). Checked as a scene's value is: an unknown name exits 2 with the closest
one, the value is a number as a scene writes one, ``1e-400`` is refused.

Expected values by hand: issue 11's scene (C = -(1 - b^2), singular at b = +-1; see
test_classify_parametric.py) and the rolling disk (x' = R cos(theta) phi', ...: from the
origin with theta' = 1, phi' = 2 the centre runs on a circle of radius R phi' / theta').
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from nhham.errors import InputError, SceneError
from nhham.system.scene import loads_scene
from tests.cli.conftest import EXAMPLES, run_inprocess

ISSUE_11 = EXAMPLES / "parametric_null_constraint.toml"  # a = b = 1
DISK = (EXAMPLES / "rolling_disk.toml").read_text()


def run(*argv):
    rc, out, err = run_inprocess(*map(str, argv))
    return rc, (json.loads(out) if out.strip().startswith("{") else out), err


def test_set_moves_the_values_out_of_the_exceptional_case():
    rc, env, _ = run("classify", ISSUE_11, "--json")
    assert rc == 0 and env["result"]["parameter_case"]["conditions"] == ["b - 1"]
    rc, env, _ = run("classify", ISSUE_11, "--set", "b=0.5", "--json")
    assert rc == 0
    r = env["result"]
    assert (r["regular"], r["rank_c"], r["parameter_case"]) == (True, 1, None)
    assert {p["name"]: p["value"] for p in env["scene"]["parameters"]} == {"a": 1.0, "b": 0.5}
    assert env["scene"]["set"] == {"b": 0.5}
    assert env["warnings"][0] == "--set: b = 0.5 for this run (instead of the scene's values)"


def test_set_on_derive_changes_c():
    """b = 1/2: C = -(1 - 1/4) = -3/4 at the values (a = 1)."""
    rc, env, _ = run("derive", ISSUE_11, "--set", "b=0.5", "--set", "a=2", "--json")
    assert rc == 0
    assert env["scene"]["set"] == {"b": 0.5, "a": 2.0}
    assert env["result"]["parameter_case"] is None


def test_set_radius_of_the_disk_in_simulate(tmp_path):
    """R = 1/2, x' and y' left out of [initial] (solved: x' = R phi' = 1): the centre runs
    on the circle x = sin t, y = 1 - cos t."""
    scene = tmp_path / "disk.toml"
    scene.write_text(DISK.replace("x_dot = 2.0\n", "").replace("y_dot = 0.0\n", ""))
    rc, env, err = run("simulate", scene, "--set", "R=0.5", "--t-end", "3", "--json")
    assert rc == 0, err
    assert "initial: solved from the constraints: x_dot = 1, y_dot = 0" in env["warnings"]
    y = dict(zip(env["result"]["state"], env["result"]["y_final"]))
    assert y["x"] == pytest.approx(math.sin(3.0), abs=1e-8)
    assert y["y"] == pytest.approx(1 - math.cos(3.0), abs=1e-8)


@pytest.mark.parametrize("command", ["classify", "derive", "compare", "simulate", "bench",
                                     "linearize"])
def test_an_unknown_name_exits_2_with_the_closest(command):
    rc, _, err = run(command, EXAMPLES / "rolling_disk.toml", "--set", "RR=2")
    assert rc == 2
    assert err.endswith("--set: 'RR' is not a parameter of the scene; did you mean 'R'?\n")
    assert err.count("\n") == 1


@pytest.mark.parametrize("item, message", [
    ("m=1e-400", "--set m: the number 1e-400 is outside the range of double precision"),
    ("m=abc", "--set m: expected a number as a scene writes one (2, 0.5, 1e-3), got 'abc'"),
    ("m=inf", "--set m: expected a finite number, got inf"),
    ("m=true", "--set m: expected a number, got a boolean"),
    ("m", "--set: expected NAME=VALUE (e.g. --set m=2.5), got 'm'"),
])
def test_values_are_checked_as_a_scene_checks_them(item, message):
    rc, _, err = run("classify", EXAMPLES / "rolling_disk.toml", "--set", item)
    assert rc == 2 and message in err, err


def test_a_name_set_twice_is_refused():
    rc, _, err = run("classify", EXAMPLES / "rolling_disk.toml", "--set", "m=1", "--set",
                     "m=2")
    assert rc == 2 and "--set: 'm' given twice" in err


def test_a_scene_value_written_as_1e_400_is_refused_too():
    """tomllib reads 1e-400 as 0.0 without a word: the scene refuses it instead."""
    with pytest.raises(SceneError, match="the number 1e-400 is outside the range"):
        loads_scene(DISK.replace("m = 1.0", "m = 1e-400"))


def test_a_symbolic_parameter_gets_a_value():
    text = ISSUE_11.read_text().replace("parameters = { a = 1.0, b = 1.0 }",
                                        'parameters = { a = 1.0 }\nsymbolic_parameters = ["b"]')
    scene = loads_scene(text)
    assert {p.name for p in scene.system.parameter_values} == {"a"}
    scene = loads_scene(text, values={"b": 0.25})
    assert {p.name: v for p, v in scene.system.parameter_values.items()} == \
        {"a": 1.0, "b": 0.25}


def test_the_library_names_an_unknown_value():
    with pytest.raises(InputError) as info:
        loads_scene(DISK, values={"mass": 1.0})
    assert info.value.key == "values" and "'mass' is not a parameter" in str(info.value)


SLEIGH = Path(__file__).resolve().parents[1] / "study" / "scenes" / "sleigh_drag.toml"


def test_set_on_sweep_moves_the_boundary(tmp_path):
    """c = 0.3, m = 2 (a = -0.5): the yaw eigenvalue crosses 0 at U* = -c / (m a) = 0.3,
    not at the scene's 0.8; the values are stored with the study."""
    out = tmp_path / "s.zarr"
    rc, env, err = run("sweep", SLEIGH, "--what", "linearize", "--over", "U=-1:3:9",
                       "--set", "c=0.3", "--set", "m=2", "--out", out, "--workers", "1",
                       "--json")
    assert rc == 0, err
    s = env["result"]["summary"]
    assert s["real_crossings"] == 1
    assert s["real_crossing_range"] == pytest.approx([0.3, 0.3], abs=1e-10)
    assert env["scene"]["set"] == {"c": 0.3, "m": 2.0}
    assert env["warnings"][0] == ("--set: c = 0.3, m = 2 for this run (instead of the "
                                  "scene's values)")
    import xarray as xr

    with xr.open_zarr(out) as ds:
        assert json.loads(ds.attrs["options"])["values"] == {"c": 0.3, "m": 2.0}


def test_set_and_over_on_one_name_is_a_usage_error(tmp_path):
    out = tmp_path / "s.zarr"
    rc, env, err = run("sweep", SLEIGH, "--what", "linearize", "--over", "U=-1:3:9",
                       "--over", "c=0.1,0.2", "--set", "c=0.3", "--out", out, "--json")
    assert rc == 2 and err.count("\n") == 1
    assert err == ("nhham: error: --set c: 'c' is also swept (--over c=...); give it either "
                   "a value (--set) or a range (--over), not both\n")
    assert env["error"]["key"] == "--set" and not out.exists()


def test_sweep_names_an_unknown_set_name(tmp_path):
    rc, _, err = run("sweep", SLEIGH, "--what", "linearize", "--over", "U=-1:3:9",
                     "--set", "cc=0.3", "--out", tmp_path / "s.zarr", "--workers", "1")
    assert rc == 2 and err.endswith("--set: 'cc' is not a parameter of the scene; did you "
                                    "mean 'c'?\n")


def test_a_worker_loads_the_study_s_scene_with_its_values():
    """What a worker of another process does with a study (tasks.context): the scene
    parsed with the set values; the same text with other values is another context."""
    from nhham.study.points import grid, parse_over
    from nhham.study.tasks import Study, context

    text = SLEIGH.read_text()
    design = grid([parse_over("U=0:1:2")])
    contexts = [context(Study("classify", text, "sleigh", "", design, options))
                for options in ({"values": {"c": 0.3, "m": 2.0}}, {"values": {"c": 0.5}}, {})]
    got = [{p.name: v for p, v in ctx.scene.system.parameter_values.items()}
           for ctx in contexts]
    assert (got[0]["c"], got[0]["m"]) == (0.3, 2.0)
    assert (got[1]["c"], got[1]["m"]) == (0.5, 1.0)
    assert (got[2]["c"], got[2]["m"]) == (0.4, 1.0)
