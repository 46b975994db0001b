"""Stability boundaries where the tracked-eigenvalue search went wrong, by both routes
(``nhham sweep --what linearize`` and ``nhham linearize --sweep``), against closed forms
derived by hand in the scenes' headers:

- a sleigh whose drag eigenvalue -3 k U^2 / m touches 0 at U = 0 (a grid value) while
  its yaw eigenvalue -(m a U + c) / J crosses at U* = -c / (m a);
- a wheel on a spring whose complex pair meets on the real axis (p = 0.4) inside the
  grid interval where a real root then crosses 0 (p = 0.5).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from nhham.cli.main import main
from nhham.study.sweep import sweep

SCENES = Path(__file__).resolve().parent / "scenes"


def command_crossings(capsys, scene, over):
    status = main(["linearize", str(scene), "--sweep", over, "--json"])
    out = capsys.readouterr().out
    assert status == 0
    return json.loads(out)["result"]["sweep"]["crossings"]


def test_the_sleigh_s_boundary_is_the_yaw_crossing_not_the_drag_touch():
    m, a = 1.0, -0.5
    ds = sweep(SCENES / "sleigh_drag.toml", "linearize", ["U=-1:3:9", "c=0.2,0.4"],
               workers=1).dataset
    for j, c in enumerate([0.2, 0.4]):
        b = ds["boundary"].values[j]
        # -c / (m a): 0.4 (a grid value) and 0.8; nothing at the touch U = 0
        assert b[np.isfinite(b)].tolist() == pytest.approx([-c / (m * a)], abs=1e-10)
        assert ds["boundary_kind"].values[j, 0] == 0
    assert int(ds["boundary_unlocated"].values.sum()) == 0


def test_the_sleigh_by_the_single_command_agrees(capsys):
    (c,) = command_crossings(capsys, SCENES / "sleigh_drag.toml", "U=-1:3:9")
    assert c["value"] == pytest.approx(0.8, abs=1e-10) and c["kind"] == "real"
    assert abs(c["eigenvalue"][0]) < 1e-9 and c["direction"] == 1


def test_a_pair_meeting_on_the_axis_then_a_real_root_crossing_by_both_routes(capsys):
    (c,) = command_crossings(capsys, SCENES / "wheel_spring.toml", "p=0:1.4:3")
    assert c["value"] == pytest.approx(0.5, abs=1e-10) and c["kind"] == "real"
    assert abs(c["eigenvalue"][0]) < 1e-9 and abs(c["eigenvalue"][1]) < 1e-9
    ds = sweep(SCENES / "wheel_spring.toml", "linearize", ["p=0,0.7,1.4", "m=0.5,0.25"],
               workers=1).dataset
    b = ds["boundary"].values
    assert b[:, 0].tolist() == pytest.approx([0.5, 0.5], abs=1e-10)
    assert np.isnan(b[:, 1:]).all()
    # the eigenvalue at the reported boundary is on the axis (det A = 5 - 10 p = 0)
    at = sweep(SCENES / "wheel_spring.toml", "linearize", [f"p={float(b[0, 0])!r},1.4"],
               workers=1).dataset
    ev = at["eigenvalue_real"].values[0] + 1j * at["eigenvalue_imag"].values[0]
    assert np.min(np.abs(ev)) < 1e-9


def test_a_grid_that_starts_where_the_family_tangent_is_in_the_kernel():
    """At U = 0 the speed's tangent of the steady family is in A's kernel (the drag
    eigenvalue -3 k U^2 / m is 0 there), at no other U: it is not divided out, and every
    point is linearised in one chart (the first probe used to impose its division)."""
    ds = sweep(SCENES / "sleigh_drag.toml", "linearize", ["U=0:2:41"], workers=1).dataset
    assert (ds["status"].values == 0).all()
    assert ds["verdict"].values[0] == -1            # a zero eigenvalue at U = 0
    b = ds["boundary"].values
    assert b[np.isfinite(b)].tolist() == pytest.approx([0.8], abs=1e-10)
