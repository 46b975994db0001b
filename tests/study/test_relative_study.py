"""``nhham sweep --what linearize`` over the spin rate of a relative equilibrium (the
rattleback's upright spin along its ``[symmetry]``): a point of the study is the single
command's answer there (co-moving variables, the same state matrix), and the study's
boundary in w is the command's ``--sweep`` crossing (both against the Kane route's root
in tests/numerics/test_relative_equilibria.py: 23.559908405269)."""

import json

import numpy as np
import pytest

from nhham.cli.main import main
from nhham.study.sweep import sweep

SCENE = "examples/rattleback.toml"
W_C = 23.559908405269   # tests/numerics/test_relative_equilibria.py (KanesMethod)


def command(capsys, *argv):
    capsys.readouterr()
    status = main([*map(str, argv), "--json"])
    return status, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def spin_map():
    return sweep(SCENE, "linearize", ["w=-40:40:5"], workers=1).dataset


@pytest.mark.parametrize("i, w", [(0, -40.0), (4, 40.0)])
def test_a_point_is_the_command_s_answer(capsys, spin_map, i, w):
    status, env = command(capsys, "linearize", SCENE, "--set", f"w={w!r}")
    assert status == 0
    lin = env["result"]
    point = spin_map.isel(w=i)
    assert int(point["status"]) == 0 and lin["relative_equilibrium"]["rate"] == w
    assert list(spin_map["row"].values) == lin["coordinates"]
    np.testing.assert_allclose(point["state_matrix"].values, lin["matrix"], rtol=0, atol=1e-9)
    got = np.sort_complex(point["eigenvalue_real"].values + 1j * point["eigenvalue_imag"].values)
    want = np.sort_complex(np.array([complex(re, im) for re, im in lin["eigenvalues"]]))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    assert bool(point["stable"]) == bool(lin["stable"]) and bool(point["stable"]) == (w > 0)


def test_the_study_s_boundary_is_the_command_s_crossing(capsys, spin_map):
    found = spin_map["boundary"].values
    found = np.sort(found[np.isfinite(found)])
    status, env = command(capsys, "linearize", SCENE, "--sweep", "w=-40:40:5")
    assert status == 0
    swept = sorted(c["value"] for c in env["result"]["sweep"]["crossings"])
    np.testing.assert_allclose(found, swept, rtol=0, atol=1e-9)
    # -w_c; at 0 the two directions exchange their unstable pair (a pair turns stable,
    # another unstable); +w_c, where the positive spin turns stable (the negative never is)
    np.testing.assert_allclose(found, [-W_C, 0.0, 0.0, W_C], rtol=1e-9, atol=1e-9)
