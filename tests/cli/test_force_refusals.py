"""A force not defined where the command starts, and a dissipation that does not
dissipate: exit 2 with one line naming the key and the state, the same with a cold and a
warm compile cache, and the envelope names the scene once it is loaded."""

import contextlib
import io
import json

import pytest

from nhham.cli.main import main

SCENE = """
name = "singular force"
coordinates = ["x", "y"]
parameters = { k = 1.0 }
lagrangian = "(x_dot**2 + y_dot**2)/2"
constraints = ["x_dot - y_dot"]
forces = { x = "k/x" }

[initial]
x = 0.0
y = 0.0
x_dot = 1.0
y_dot = 1.0

[steady]
x = 0.0
y = 0.0
x_dot = 1.0
y_dot = 1.0
"""


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def warm_cache(tmp_path_factory):
    """A compile cache holding the scene's compiled library (built before the command)."""
    from nhham.numerics.codegen import numeric_model
    from nhham.system.scene import loads_scene

    where = tmp_path_factory.mktemp("warm")
    where.chmod(0o700)
    model = numeric_model(loads_scene(SCENE, check_initial=False).system, backend="c",
                          cache_dir=str(where))
    assert model.backend == "c"
    return where


@pytest.mark.parametrize("command", ["simulate", "linearize"])
@pytest.mark.parametrize("cache", ["cold", "warm"])
def test_a_force_singular_at_the_start_exits_2_naming_force_and_state(
        tmp_path, monkeypatch, warm_cache, command, cache):
    where = warm_cache if cache == "warm" else tmp_path / "cold"
    if cache == "cold":
        where.mkdir(mode=0o700)
    monkeypatch.setenv("NHHAM_CACHE", str(where))
    path = tmp_path / "singular.toml"
    path.write_text(SCENE)
    rc, out, err = run(command, path, "--json")
    assert rc == 2, err
    assert err.count("\n") == 1
    state = "initial state" if command == "simulate" else "[steady] motion"
    assert (f"forces.x: the force k/x on x is not defined at the {state} (x = 0, y = 0, "
            f"x_dot = 1, y_dot = 1)") in err
    env = json.loads(out)
    assert env["error"]["key"] == "forces.x" and env["error"]["kind"] == "input"
    assert env["scene"]["name"] == "singular force"   # loaded: the envelope names it


def test_a_negative_dissipation_exits_2_naming_it(tmp_path):
    path = tmp_path / "pump.toml"
    path.write_text('coordinates = ["x"]\nparameters = { c = 2.0 }\n'
                    'lagrangian = "x_dot**2/2"\ndissipation = "-c*x_dot**2/2"\n')
    rc, out, err = run("classify", path, "--json")
    assert rc == 2 and err.startswith("nhham: error: dissipation: ")
    assert json.loads(out)["error"]["key"] == "dissipation"

