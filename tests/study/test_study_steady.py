"""A swept parameter that moves the steady configuration: the chart's dependent
coordinates are solved at every point (the study, ``linearize --sweep`` and the single
command alike), against the closed forms of a pendulum of squared length L2 and of the
bicycle's upright pitch as a function of its fork offset."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from nhham.cli.main import main
from nhham.study.sweep import sweep

SCENES = Path(__file__).resolve().parent / "scenes"
BICYCLE = Path(__file__).resolve().parents[2] / "examples" / "whipple_bicycle.toml"


def test_the_pendulum_hangs_at_minus_sqrt_L2_at_every_point(capsys):
    """Eigenvalues +- i sqrt(g / sqrt(L2)); no hanging state for L2 <= 0 (status 1)."""
    ds = sweep(SCENES / "pendulum_steady.toml", "linearize", ["L2=-1:3:5"],
               workers=1).dataset
    assert ds["status"].values.tolist() == [1, 1, 0, 0, 0]
    for L2, im in zip(ds["L2"].values[2:], ds["eigenvalue_imag"].values[2:]):
        assert sorted(im) == pytest.approx([-math.sqrt(9.81 / math.sqrt(L2)),
                                            math.sqrt(9.81 / math.sqrt(L2))], rel=1e-9)
    assert np.isnan(ds["eigenvalue_imag"].values[:2]).all()
    status = main(["linearize", str(SCENES / "pendulum_steady.toml"), "--sweep",
                   "L2=0.5:3:3", "--json"])
    result = json.loads(capsys.readouterr().out)["result"]
    assert status == 0
    for L2, ev in zip(result["sweep"]["values"], result["sweep"]["eigenvalues"]):
        assert sorted(im for _, im in ev) == pytest.approx(
            [-math.sqrt(9.81 / math.sqrt(L2)), math.sqrt(9.81 / math.sqrt(L2))], rel=1e-9)


def test_no_hanging_state_is_said_by_the_single_command(tmp_path, capsys):
    scene = tmp_path / "p.toml"
    scene.write_text((SCENES / "pendulum_steady.toml").read_text()
                     .replace("L2 = 1.0", "L2 = -1.0"))
    assert main(["linearize", str(scene)]) == 2
    assert "no state of M_1 near the table's" in capsys.readouterr().err


def upright_pitch(text: str, forkoffset: float) -> float:
    """With lean = steer = 0 the front contact reads
    (d1 + d3) cos(h + p) - d2 sin(h + p) = rF - rR (d1 framelength, d2 forklength,
    d3 forkoffset, h the head tube angle): p from the closed form."""
    params = dict(re.findall(r"(\w+) = ([-\d.e]+)", text.split("lagrangian")[0]))
    d1, d2, h = (float(params[k]) for k in ("framelength", "forklength", "htangle"))
    rF, rR = float(params["rF"]), float(params["rR"])
    A, B = d1 + forkoffset, d2
    return math.acos((rF - rR) / math.hypot(A, B)) - math.atan2(B, A) - h


def bicycle_with(tmp_path, forkoffset, pitch):
    text = BICYCLE.read_text()
    text = re.sub(r"forkoffset = [\d.e-]+", f"forkoffset = {forkoffset!r}", text, count=1)
    text = text.replace("[steady]\nx = 0.0\ny = 0.0\npsi = 0.0\nphi = 0.0\npitch = 0.0",
                        f"[steady]\nx = 0.0\ny = 0.0\npsi = 0.0\nphi = 0.0\npitch = {pitch!r}")
    text = re.sub(r"\n\[initial\]\n[^\[]*", "\n", text)   # a run's start: not used here
    path = tmp_path / f"bicycle_{forkoffset}_{pitch}.toml"
    path.write_text(text)
    return path


def test_sweeping_the_bicycle_s_fork_offset(tmp_path, capsys):
    text = BICYCLE.read_text()
    # the closed form at the scene's own fork offset is its upright pitch, 0
    assert abs(upright_pitch(text, 0.032071426727619305)) < 1e-12
    ds = sweep(BICYCLE, "linearize", ["v=2,5", "forkoffset=0,0.06"], workers=1).dataset
    assert (ds["status"].values == 0).all()
    for j, d3 in enumerate([0.0, 0.06]):
        pitch = upright_pitch(text, d3)
        assert abs(pitch) > 1e-3                      # the pitch really moves
        # solved by hand at one offset, left for nhham to solve at the other
        for given in ((pitch,) if j == 0 else (0.0,)):
            path = bicycle_with(tmp_path, d3, given)
            assert main(["linearize", str(path), "--sweep", "v=2:5:2", "--json"]) == 0
            env = json.loads(capsys.readouterr().out)
            for i, ev in enumerate(env["result"]["sweep"]["eigenvalues"]):   # v = 2, 5
                study = np.sort_complex(ds["eigenvalue_real"].values[i, j]
                                        + 1j * ds["eigenvalue_imag"].values[i, j])
                single = np.sort_complex(np.array([complex(*z) for z in ev]))
                assert np.allclose(single, study, atol=1e-8)
            said = " ".join(env["warnings"])
            assert ("pitch = " in said) == (given == 0.0)


def test_a_sweep_through_values_with_no_steady_state_names_the_value(capsys):
    assert main(["linearize", str(SCENES / "pendulum_steady.toml"), "--sweep",
                 "L2=-1:3:5"]) == 2
    err = capsys.readouterr().err
    assert "no state of M_1 near the table's" in err and "(L2 = -1)" in err
