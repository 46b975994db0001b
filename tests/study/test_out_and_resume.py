"""What a study may replace or resume at --out, checked before any work; a full disk; a
store from another nhham, with data missing, or damaged."""

import errno
import shutil
import warnings

import numpy as np
import pytest
import xarray as xr
import zarr

import nhham
import nhham.study.sweep as sweep_module
from nhham.errors import OutputUnwritable
from nhham.study.sweep import sweep

SCENE = "examples/differential_drive.toml"
OVER = ["w=-4.5:5.5:21", "d=0.02:0.1:5"]


@pytest.fixture(scope="module")
def in_memory():
    return sweep(SCENE, "linearize", OVER, workers=1).dataset


@pytest.fixture
def no_work(monkeypatch):
    """Any loading of the scene fails the test: a refusal must come before it."""
    def refuse(*args, **kwargs):
        raise AssertionError("the study was prepared before --out was checked")

    monkeypatch.setattr(sweep_module, "_load", refuse)


def _same(a, b):
    for name in a.data_vars:
        x, y = np.asarray(a[name].values), np.asarray(b[name].values)
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name


def _interrupt_after(points):
    def report(done, total, elapsed):
        if done >= points:
            raise KeyboardInterrupt
    return report


# ---------------------------------------------------------------- --out (item 5)
def test_a_directory_that_is_not_a_study_is_never_replaced(tmp_path, no_work):
    thesis = tmp_path / "thesis.zarr"
    (thesis / "chapters").mkdir(parents=True)
    (thesis / "chapters" / "one.tex").write_text("mine")
    for flags in ({"overwrite": True}, {"resume": True}, {}):
        with pytest.raises(nhham.InputError, match="is not a study nhham wrote") as info:
            sweep(SCENE, "linearize", OVER, workers=1, out=thesis, **flags)
        assert info.value.key == "--out"
    assert (thesis / "chapters" / "one.tex").read_text() == "mine"
    (tmp_path / "notes.nc").write_text("not netCDF")
    with pytest.raises(nhham.InputError, match="is not a study nhham wrote"):
        sweep(SCENE, "linearize", OVER, workers=1, out=tmp_path / "notes.nc", overwrite=True)
    assert (tmp_path / "notes.nc").read_text() == "not netCDF"


def test_links_and_folders_that_cannot_be_written_are_refused(tmp_path, no_work):
    (tmp_path / "real.zarr").mkdir()
    (tmp_path / "link.zarr").symlink_to(tmp_path / "real.zarr")
    cases = [(tmp_path / "link.zarr", "is a symbolic link"),
             (tmp_path / "nowhere" / "x.zarr", "does not exist"),
             ("/proc/x.zarr", "cannot write in '/proc'")]   # not even the superuser can
    for out, fragment in cases:
        with pytest.raises(nhham.InputError, match=fragment) as info:
            sweep(SCENE, "linearize", OVER, workers=1, out=out, overwrite=True)
        assert info.value.key == "--out"
    assert (tmp_path / "real.zarr").is_dir()


def test_a_study_is_replaced_only_once_the_new_one_is_complete(tmp_path, in_memory):
    out = tmp_path / "map.zarr"
    old = sweep(SCENE, "linearize", ["w=4:5:3"], workers=1, out=out)
    assert old.complete
    with pytest.raises(KeyboardInterrupt):
        sweep(SCENE, "linearize", OVER, workers=1, out=out, overwrite=True, chunk_points=21,
              progress=_interrupt_after(42))
    # the old study untouched; the new one beside it, resumable
    kept = xr.open_zarr(out)
    assert list(kept["w"].values) == [4.0, 4.5, 5.0] and bool(kept["done"].all())
    partial = tmp_path / "map.zarr.partial.zarr"
    assert int(xr.open_zarr(partial, consolidated=False)["done"].sum()) == 42
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, resume=True,
                    chunk_points=21)
    assert resumed.complete and resumed.computed == 105 - 42
    assert not partial.exists() and not (tmp_path / "map.zarr.replaced").exists()
    _same(in_memory, xr.open_zarr(out).load())


def test_a_full_disk_keeps_what_finished_and_leaves_nothing_half_written(tmp_path,
                                                                         monkeypatch,
                                                                         in_memory):
    """The writer made to fail with ENOSPC: on the third chunk (the two before are kept,
    the study is resumable), on the netCDF file (no .nc.tmp left, the complete store kept
    for --resume to write it), on the layout (nothing left)."""
    write = xr.Dataset.to_zarr
    chunks = {"n": 0}

    def full_disk_at_third_chunk(self, store=None, *args, **kwargs):
        if kwargs.get("region") is not None and "done" in self.data_vars:
            chunks["n"] += 1
            if chunks["n"] == 3:
                raise OSError(errno.ENOSPC, "No space left on device")
        return write(self, store, *args, **kwargs)

    out = tmp_path / "map.zarr"
    with monkeypatch.context() as m:
        m.setattr(xr.Dataset, "to_zarr", full_disk_at_third_chunk)
        stopped = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21)
    assert not stopped.complete and "No space left on device" in stopped.stopped
    assert "free some space and continue with --resume" in stopped.stopped
    assert int(stopped.dataset["done"].sum()) == 42
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21,
                    resume=True)
    assert resumed.complete and resumed.computed == 63
    _same(in_memory, resumed.dataset)

    nc = tmp_path / "map.nc"

    def full_disk_in_netcdf(self, path=None, *args, **kwargs):
        with open(path, "wb") as f:   # a half-written file, then the failure
            f.write(b"CDF\x01")
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(xr.Dataset, "to_netcdf", full_disk_in_netcdf)
        unwritten = sweep(SCENE, "linearize", OVER, workers=1, out=nc)
    assert not unwritten.complete and "No space left on device" in unwritten.stopped
    assert unwritten.kept == str(tmp_path / "map.nc.partial.zarr")
    assert not nc.exists() and not (tmp_path / "map.nc.tmp").exists()
    assert bool(xr.open_zarr(tmp_path / "map.nc.partial.zarr")["done"].all())
    written = sweep(SCENE, "linearize", OVER, workers=1, out=nc, resume=True)
    assert written.complete and written.computed == 0 and nc.is_file()
    assert not (tmp_path / "map.nc.partial.zarr").exists()

    def full_disk_at_once(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(xr.Dataset, "to_zarr", full_disk_at_once)
        with pytest.raises(OutputUnwritable):
            sweep(SCENE, "linearize", OVER, workers=1, out=tmp_path / "new.zarr")
    assert not (tmp_path / "new.zarr").exists()


def test_a_complete_store_opens_without_a_warning(tmp_path):
    out = tmp_path / "map.zarr"
    sweep(SCENE, "linearize", ["w=4:5:3"], workers=1, out=out)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = xr.open_zarr(out)      # consolidated metadata: nothing to warn about
    assert bool(ds["done"].all())


# ---------------------------------------------------------------- --resume (item 6)
def _stopped_store(tmp_path):
    out = tmp_path / "map.zarr"
    with pytest.raises(KeyboardInterrupt):
        sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21,
              progress=_interrupt_after(42))
    return out


@pytest.mark.parametrize("attribute, value, fragment", [
    ("nhham_version", "0.0.1", "was made by nhham 0.0.1"),
    ("code_hash", "0" * 64, "was made from other generated code")])
def test_a_store_of_another_nhham_or_code_is_not_resumed(tmp_path, attribute, value,
                                                         fragment):
    out = _stopped_store(tmp_path)
    zarr.open_group(str(out), mode="r+").attrs[attribute] = value
    with pytest.raises(nhham.InputError, match=fragment) as info:
        sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21, resume=True)
    assert info.value.key == "--resume"


def test_chunks_marked_done_whose_data_are_missing_are_computed_again(tmp_path, in_memory):
    out = tmp_path / "map.zarr"
    sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21)
    # the data of the second chunk (w 0..20 at d index 1) deleted, its points still done
    shutil.rmtree(out / "eigenvalue_real" / "c" / "0" / "1")
    assert bool(xr.open_zarr(out)["done"].all())
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21,
                    resume=True)
    assert resumed.complete and resumed.computed == 21
    _same(in_memory, resumed.dataset)


def _truncated(path):
    """Half of a file, as a full disk or an interrupted copy leaves it."""
    path.write_bytes(path.read_bytes()[:path.stat().st_size // 2])


def test_chunks_that_cannot_be_read_back_are_computed_again_and_named(tmp_path, in_memory):
    """Issue 43 item 5: a complete store (chunks of 7 points: every line along w is in
    three pieces) with three chunk files truncated: the spectral abscissa of the points w
    7..13 at d index 2, the crossing counts of the line at d index 4 (its three pieces,
    21 points: a line's crossings and count go together) and ``done`` of w 14..20 at d
    index 0. Before, --resume found it complete (0 computed) and it could not be read."""
    out = tmp_path / "map.zarr"
    sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=7)
    for name in ("spectral_abscissa/c/1/2", "boundary_count/c/4", "done/c/2/0"):
        _truncated(out / name)
    with pytest.warns(nhham.NhhamWarning, match="3 chunk file.s. of .* cannot be read "
                                                "back .*their points are computed again"
                      ) as caught:
        resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, resume=True)
    message = str(caught[0].message)
    for name in ("spectral_abscissa/c/1/2", "boundary_count/c/4", "done/c/2/0"):
        assert f"{name}: RuntimeError: Zstd decompression error" in message
    assert resumed.complete and resumed.computed == 7 + 21 + 7
    _same(in_memory, xr.open_zarr(out).load())


def test_another_chunk_size_is_refused_and_none_resumes_with_the_store_s(tmp_path,
                                                                         in_memory):
    out = _stopped_store(tmp_path)
    with pytest.raises(nhham.InputError, match="stored in chunks of 21 x 1 points, not "
                                               "21 x 2") as info:
        sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=42, resume=True)
    assert info.value.key == "--chunk"
    resumed = sweep(SCENE, "linearize", OVER, workers=1, out=out, resume=True)
    assert resumed.complete and resumed.computed == 105 - 42 and resumed.stopped is None
    _same(in_memory, resumed.dataset)


def test_a_damaged_store_is_refused_with_its_reason(tmp_path):
    """Metadata or coordinates that cannot be read: refused, naming the file."""
    out = _stopped_store(tmp_path)
    for name, fragment in [("w/c/0", "its layout file .*/w/c/0 cannot be read back: "
                                     ".*Zstd decompression error"),
                           ("done/zarr.json", "done/zarr.json is not JSON")]:
        _truncated(out / name)
        with pytest.raises(nhham.InputError, match="cannot be read as a study .*"
                                                   + fragment) as info:
            sweep(SCENE, "linearize", OVER, workers=1, out=out, chunk_points=21,
                  resume=True)
        assert info.value.key == "--resume"
    _truncated(out / "zarr.json")      # the attributes: not recognisable as a study
    with pytest.raises(nhham.InputError, match="map.zarr/zarr.json is not JSON .*cannot "
                                               "tell whether it is a study") as info:
        sweep(SCENE, "linearize", OVER, workers=1, out=out, resume=True)
    assert info.value.key == "--out"
    (out / "zarr.json").unlink()       # no attributes left: not recognisable as a study
    with pytest.raises(nhham.InputError, match="is not a study nhham wrote") as info:
        sweep(SCENE, "linearize", OVER, workers=1, out=out, resume=True)
    assert info.value.key == "--out"


def test_zarr_and_xarray_older_than_those_tested_are_refused_before_any_work(
        monkeypatch, tmp_path, no_work):
    """Issue 43 item 8: the pins allowed zarr 2.18, under which xarray 2026 cannot open a
    store (TypeError: open_group() got an unexpected keyword argument 'zarr_format'),
    and zarr 3.0 to 3.1.1 leave chunks equal to their fill unwritten (a resumed study
    computes everything again). An installed zarr or xarray older than the study
    extra's pins is named, exit 2, before any work."""
    monkeypatch.setattr(zarr, "__version__", "2.18.7")
    with pytest.raises(nhham.OptionalDependencyError,
                       match=r"need zarr >= 3\.1\.2 \(this is 2\.18\.7\)") as info:
        sweep(SCENE, "linearize", OVER, workers=1, out=tmp_path / "map.zarr")
    assert isinstance(info.value, nhham.InputError)       # exit 2
    monkeypatch.setattr(xr, "__version__", "2025.7.1")
    with pytest.raises(nhham.OptionalDependencyError, match=r"need xarray >= 2026\.1 "):
        sweep(SCENE, "linearize", OVER, workers=1)
    assert not (tmp_path / "map.zarr").exists()
