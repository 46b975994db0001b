"""Stability boundaries along the second axis of a grid (issue 34, item 9): the crossings
along ``across`` (the first grid dimension other than ``along``) are located on every line
of the grid as well, in the ``boundary_across`` variables, whatever the chunks (pieces of
lines merged as written) and after a resumed interruption.

Expected values by hand (tests/study/scenes/two_parameter_spring.toml): the eigenvalues
are -1 +- sqrt(p1 + p2), so a real root crosses 0 on p1 + p2 = 1, unstable above it: on
the line along p2 at p1 the crossing is at p2 = 1 - p1, on the line along p1 at p2 at
p1 = 1 - p2 (each where it lies inside the grid).
"""

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import xarray as xr

from nhham.render.schema import output_schema
from nhham.study.sweep import sweep

SCENE = Path(__file__).resolve().parent / "scenes" / "two_parameter_spring.toml"
OVER = ["p1=0:1:6", "p2=0.05:0.95:4"]
P1 = np.linspace(0, 1, 6)
P2 = np.linspace(0.05, 0.95, 4)


def _check(ds):
    assert json.loads(ds.attrs["options"])["across"] == "p2"
    across, along = np.asarray(ds["boundary_across"].values), np.asarray(ds["boundary"].values)
    assert ds["boundary_across"].dims == ("p1", "crossing")
    for i, p1 in enumerate(P1):
        want = [1 - p1] if P2[0] < 1 - p1 < P2[-1] else []
        got = across[i][np.isfinite(across[i])].tolist()
        assert got == pytest.approx(want, abs=1e-9), p1
        assert int(ds["boundary_across_count"].values[i]) == len(want)
        if want:   # a real root, unstable as p2 grows
            assert ds["boundary_across_kind"].values[i, 0] == 0
            assert ds["boundary_across_direction"].values[i, 0] == 1
    for j, p2 in enumerate(P2):
        got = along[j][np.isfinite(along[j])].tolist()
        assert got == pytest.approx([1 - p2], abs=1e-9), p2
    assert int(np.asarray(ds["boundary_across_unlocated"].values).sum()) == 0


@pytest.mark.parametrize("chunk", [None, 5, 2])
def test_crossings_along_both_axes_match_the_closed_form(chunk):
    """One chunk; chunks that cut the lines along both axes (5: 3 x 1 points; 2)."""
    _check(sweep(SCENE, "linearize", OVER, workers=1, chunk_points=chunk).dataset)


def test_a_resumed_study_locates_them_as_an_uninterrupted_one(tmp_path):
    out = tmp_path / "map.zarr"

    def stop_after(points):
        def report(done, total, elapsed):
            if done >= points:
                raise KeyboardInterrupt
        return report

    with pytest.raises(KeyboardInterrupt):
        sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=3,
              progress=stop_after(9))
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=3,
                    resume=True)
    assert resumed.complete and 0 < resumed.computed < 24
    _check(xr.open_zarr(out).load())


def test_a_one_dimensional_grid_has_no_second_axis():
    ds = sweep(SCENE, "linearize", ["p1=0:1.5:7"], workers=1).dataset
    assert "boundary_across" not in ds and "across" not in json.loads(ds.attrs["options"])
    b = np.asarray(ds["boundary"].values)
    assert b[np.isfinite(b)].tolist() == pytest.approx([1.0], abs=1e-9)


def test_the_command_summarises_and_draws_them(capsys, tmp_path):
    """The summary's across_... keys (p2* = 1 - p1 on the lines p1 = 0.2 .. 0.8) and the
    map with the crossings located along p2 marked."""
    from nhham.cli.main import main

    plot = tmp_path / "map.png"
    status = main(["sweep", str(SCENE), "--what", "linearize", "--over", OVER[0], "--over",
                   OVER[1], "--out", str(tmp_path / "m.zarr"), "--plot", str(plot),
                   "--workers", "1", "--json"])
    envelope = json.loads(capsys.readouterr().out)
    assert status == 0
    jsonschema.validate(envelope, output_schema())
    assert envelope["result"]["complete"] and envelope["result"]["points"] == 24
    assert envelope["result"]["dims"] == {"p1": 6, "p2": 4}
    assert envelope["result"]["plot"] == str(plot)
    s = envelope["result"]["summary"]
    assert s["across"] == "p2" and s["across_real_crossings"] == 4
    assert s["across_real_crossing_range"] == pytest.approx([0.2, 0.8], abs=1e-9)
    assert s["across_complex_crossings"] == 0 and s["across_unlocated_crossings"] == 0
    assert s["real_crossings"] == 4
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_the_map_marks_the_crossings_located_along_the_second_axis():
    from nhham.study.plots import plot_stability_map

    ds = sweep(SCENE, "linearize", OVER, workers=1).dataset
    ax = plot_stability_map(ds).axes[0]
    marked = [line for line in ax.lines if line.get_marker() == "o"]
    assert [line.get_label() for line in marked] == [
        "real eigenvalue crosses 0 (located along p2)"]
    x, y = marked[0].get_data()
    pick = np.isfinite(np.asarray(y, dtype=float))
    assert np.asarray(y, dtype=float)[pick] == pytest.approx(1 - np.asarray(x)[pick],
                                                            abs=1e-9)
