"""A point of a study is what the single command answers there.

Each kind of study is evaluated at a few points, and at each point the command is run
(in this process, through :func:`nhham.cli.main.main`) with ``--set`` giving the point's
values: every variable of the study against the command's JSON at that point, and against
a closed form where there is one.
"""

import json
import math

import numpy as np
import pytest

from nhham.cli.main import main
from nhham.study.classes import row_of
from nhham.study.sweep import sweep

HELD = "tests/study/scenes/held_pendulum.toml"
CLASSES = "examples/parametric_null_constraint.toml"


def command(capsys, *argv):
    """(exit status, JSON envelope) of ``nhham ARGV --json``."""
    capsys.readouterr()
    status = main([*map(str, argv), "--json"])
    return status, json.loads(capsys.readouterr().out)


def settings(**values):
    return [item for k, v in values.items() for item in ("--set", f"{k}={v!r}")]


@pytest.fixture(scope="module")
def held_map():
    return sweep(HELD, "linearize", ["k=0.5,2.0", "s=0.0,0.1"], workers=1).dataset


@pytest.mark.parametrize("i, k", [(0, 0.5), (1, 2.0)])
def test_a_linearize_point_is_the_command_s_answer(capsys, held_map, i, k):
    ds = held_map
    status, env = command(capsys, "linearize", HELD, "--numeric", *settings(k=k))
    assert status == 0
    lin = env["result"]
    point = ds.isel(k=i, s=0)
    assert int(point["status"]) == 0 and lin["loop"] == "closed"
    assert list(ds["row"].values) == lin["coordinates"] == ["x", "x_dot"]
    np.testing.assert_allclose(point["state_matrix"].values, lin["matrix"], rtol=0,
                               atol=1e-12)
    got = np.sort_complex(point["eigenvalue_real"].values + 1j * point["eigenvalue_imag"].values)
    want = np.sort_complex(np.array([complex(re, im) for re, im in lin["eigenvalues"]]))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert bool(point["stable"]) == lin["stable"] and int(point["verdict"]) == 1
    # and the closed form: l^2 + c l + cos(x0) + k = 0 (c = 0.1, x0 = asin(0.5))
    roots = np.sort_complex(np.roots([1.0, 0.1, math.cos(math.asin(0.5)) + k]))
    np.testing.assert_allclose(got, roots, rtol=0, atol=1e-12)
    # the command's default (the exact Jacobian for n <= 4) to its rounding
    status, env = command(capsys, "linearize", HELD, *settings(k=k))
    exact = np.sort_complex(np.array([complex(re, im) for re, im in env["result"]["eigenvalues"]]))
    assert env["result"]["method"] == "exact"
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-12)


@pytest.mark.parametrize("i, k", [(0, 0.5), (1, 2.0)])
def test_where_the_law_misses_the_steady_input_neither_linearises(capsys, held_map, i, k):
    """s = 0.1: the law gives u0 + s where [steady] says u0: the command refuses, and the
    study has no linearisation there (status 2, verdict -1), as it says of such points."""
    point = held_map.isel(k=i, s=1)
    assert int(point["status"]) == 2 and int(point["verdict"]) == -1
    assert not bool(point["stable"]) and np.isnan(point["eigenvalue_real"].values).all()
    status, env = command(capsys, "linearize", HELD, *settings(k=k, s=0.1))
    assert status == 2 and env["error"]["key"] == "control"
    assert "not a steady motion of the closed loop" in env["error"]["message"]


@pytest.fixture(scope="module")
def classes_map():
    return sweep(CLASSES, "classify", ["b=-1.0,0.5,1.0", "a=0.0,2.0"], workers=1).dataset


@pytest.mark.parametrize("b", [-1.0, 0.5, 1.0])
@pytest.mark.parametrize("a", [0.0, 2.0])
def test_a_classify_point_is_the_command_s_answer(capsys, classes_map, a, b):
    point = classes_map.sel(a=a, b=b)
    status, env = command(capsys, "classify", CLASSES, *settings(a=a, b=b))
    fields = ("status", "regular", "integrable", "rank_C", "stages", "free_multipliers",
              "first_class", "second_class")
    got = {f: int(point[f]) for f in fields}
    if status == 2:   # the command refuses the system there (a = 0: W singular)
        assert a == 0.0 and got["status"] == 3
        return
    assert status == 0
    assert got == row_of(env["result"])


START = "tests/study/scenes/disk_start.toml"


@pytest.fixture(scope="module")
def start_runs():
    return sweep(START, "simulate", ["w=1.0,3.0", "R=0.5,1.0"], workers=1).dataset


@pytest.mark.parametrize("w", [1.0, 3.0])
@pytest.mark.parametrize("R", [0.5, 1.0])
def test_a_simulate_point_is_the_command_s_run(capsys, start_runs, w, R):
    """[initial] completed at the point as the command completes it (x_dot = R w, not the
    scene's value projected), the same run, the same end."""
    point = start_runs.sel(w=w, R=R)
    assert int(point["status"]) == 0 and float(point["projection_distance"]) == 0.0
    status, env = command(capsys, "simulate", START, *settings(w=w, R=R))
    assert status == 0
    names = list(start_runs["state"].values)
    start = dict(zip(names, point["initial_state"].values))
    assert start["x_dot"] == pytest.approx(R * w, abs=1e-14)
    np.testing.assert_allclose(point["final_state"].values, env["result"]["y_final"],
                               rtol=1e-12, atol=1e-12)
    assert float(point["t_final"]) == env["result"]["t_final"] == 1.0
    end = dict(zip(names, point["final_state"].values))
    assert end["x"] == pytest.approx(R * w * math.sin(1.0), abs=1e-9)
    assert end["y"] == pytest.approx(R * w * (1 - math.cos(1.0)), abs=1e-9)
