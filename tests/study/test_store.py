"""Results on disk: Zarr chunk by chunk, netCDF at the end, resumed where they stopped."""

import json

import numpy as np
import pytest
import xarray as xr

import nhham
from nhham.study.sweep import sweep

# the differential drive's straight run at wheel rate w: one eigenvalue, -mc d r w / J
SCENE = "examples/differential_drive.toml"
OVER = ["w=-4.5:5.5:21", "d=0.02:0.1:5"]


@pytest.fixture(scope="module")
def in_memory():
    return sweep(SCENE, "linearize", OVER, workers=1).dataset


def _same(a, b):
    for name in a.data_vars:
        x, y = np.asarray(a[name].values), np.asarray(b[name].values)
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), name
        else:
            assert np.array_equal(x, y), name


def test_zarr_holds_the_labelled_dataset_and_what_made_it(tmp_path, in_memory):
    out = tmp_path / "map.zarr"
    result = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=40)
    assert result.chunks > 1 and result.path == str(out)
    ds = xr.open_zarr(out, consolidated=False)
    assert ds["stable"].dims == ("w", "d") and list(ds["d"].values) == [0.02, 0.04, 0.06, 0.08,
                                                                         0.1]
    assert ds.attrs["nhham_version"] == nhham.__version__ and ds.attrs["what"] == "linearize"
    assert ds.attrs["scene"] == open(SCENE).read()
    assert json.loads(ds.attrs["design"])["over"] == OVER
    assert json.loads(ds.attrs["options"])["along"] == "w"
    _same(in_memory, ds.load())
    # the closed form (examples/make_differential_drive.py): lambda = -mc d r w / J
    mc, Ic, mw, Iw, Id, r, b = 4.0, 0.08, 0.3, 0.0015, 0.001, 0.1, 0.15
    w, d = np.meshgrid(ds["w"].values, ds["d"].values, indexing="ij")
    J = Ic + mc * d ** 2 + 2 * (Id + mw * b ** 2) + 2 * Iw * b ** 2 / r ** 2
    assert np.allclose(ds["eigenvalue_real"].values[..., 0], -mc * d * r * w / J, rtol=1e-12,
                       atol=1e-14)
    assert np.allclose(ds["boundary"].values[:, 0], 0.0, atol=1e-12)   # stable for w > 0


def test_netcdf_is_written_when_the_study_is_complete(tmp_path, in_memory):
    out = tmp_path / "map.nc"
    sweep(SCENE, "linearize", OVER, workers=1, out=out)
    assert out.is_file() and not (tmp_path / "map.nc.partial.zarr").exists()
    with xr.open_dataset(out) as ds:
        ds = ds.load()
    assert ds["stable"].dtype == bool or ds["stable"].attrs.get("dtype") == "bool"
    _same(in_memory.drop_vars("stable"), ds.drop_vars("stable"))
    assert np.array_equal(np.asarray(ds["stable"].values, dtype=bool),
                          np.asarray(in_memory["stable"].values))


def test_an_existing_output_is_kept_unless_asked(tmp_path):
    out = tmp_path / "map.zarr"
    sweep(SCENE, "linearize", ["w=4:5:3"], workers=1, out=out)
    with pytest.raises(nhham.InputError, match="exists; give --resume") as info:
        sweep(SCENE, "linearize", ["w=4:5:3"], workers=1, out=out)
    assert info.value.key == "--out"
    with pytest.raises(nhham.InputError, match="holds another study .*design") as info:
        sweep(SCENE, "linearize", ["w=4:6:3"], workers=1, out=out, resume=True)
    again = sweep(SCENE, "linearize", ["w=4:6:3"], workers=1, out=out, overwrite=True)
    assert again.complete and list(again.dataset["w"].values) == [4.0, 5.0, 6.0]


def test_an_interrupted_study_resumes_to_the_same_result(tmp_path, in_memory):
    """Ctrl-C after two chunks (raised from the progress report, between two chunks):
    the two are kept, and --resume computes the others only."""
    out = tmp_path / "map.zarr"

    def interrupt(done, total, elapsed):
        if done >= 42:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21,
              progress=interrupt)
    done_before = int(xr.open_zarr(out, consolidated=False)["done"].sum())
    assert done_before == 42
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21, resume=True)
    assert resumed.complete and resumed.computed == resumed.points - done_before
    _same(in_memory, resumed.dataset)


def test_a_study_out_of_budget_keeps_what_it_has(tmp_path):
    """The first chunk's report outlasts the budget: no chunk starts after it."""
    import time

    out = tmp_path / "drive.zarr"
    drive = "examples/differential_drive_motors.toml"
    # the model built and the modules imported first: the preparation then fits the budget
    assert sweep(drive, "simulate", ["c=0.01:0.05:4"], workers=1).complete
    stopped = sweep(drive, "simulate", ["c=0.01:0.05:4"], workers=1, out=out, chunk_points=1,
                    budget=2.0, progress=lambda done, total, elapsed: time.sleep(2.0))
    assert not stopped.complete and stopped.computed == 1
    with pytest.raises(nhham.InputError, match="--budget"):
        sweep(drive, "simulate", ["c=0.01:0.05:4"], workers=1, budget=0.0)
    assert sweep(drive, "simulate", ["c=0.01:0.05:4"], workers=1, out=out, chunk_points=1,
                 resume=True).computed == 3
