"""Where a study's results go: a labelled xarray Dataset, written chunk by chunk.

The Dataset has one dimension per swept parameter, named after it, with its values as the
coordinate (``sample`` for samples, with the drawn values as coordinates along it), the
variables of the study's kind (:mod:`~nhham.study.stability`,
:mod:`~nhham.study.ensemble`, :mod:`~nhham.study.classes`), a boolean ``done`` per point,
and in its attributes the scene (its text), the nhham version, what was computed, the
design and the options (JSON texts) and the hash of the generated code.

On disk it is a Zarr store (``.zarr``): the whole layout is written first, filled with
NaN (or -1), then each finished chunk is written to its region, ``done`` last. An
interrupted study leaves a store whose ``done`` says which chunks are there, so
:meth:`Store.resume` continues with the others and loses nothing; a resumed study must be
the same one (its ``study_key`` attribute: scene, kind, design and options). A netCDF
output (``.nc``) is collected in ``<out>.partial.zarr`` the same way and written as
netCDF (by xarray, with the first engine that is installed: netCDF4, h5netcdf, scipy)
when the study is complete. Without a path the Dataset stays in memory.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np

from nhham.errors import InputError, OptionalDependencyError

__all__ = ["Store", "study_key", "attrs_text", "xarray_module", "NETCDF_SUFFIXES",
           "ZARR_SUFFIXES"]

NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf")
ZARR_SUFFIXES = (".zarr",)


def study_key(attrs: dict) -> str:
    """A hash of what makes two studies the same (scene text, kind, design, options)."""
    parts = [attrs["scene"], attrs["what"], attrs["design"], attrs["options"]]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def xarray_module():
    """xarray, or the error naming the extra that installs it."""
    try:
        import xarray as xr
    except ImportError:
        raise OptionalDependencyError(
            "parameter studies store their results with xarray (and zarr); install the "
            "study extra: pip install 'nhham[study]'") from None
    return xr


class Store:
    """A study's Dataset, in memory or on disk (see the module docstring).

    Use :meth:`create` or :meth:`resume`; then :meth:`write` each finished chunk and
    :meth:`finish`.
    """

    def __init__(self, path, working, dataset, line_dims):
        self.path = path            # the output the user asked for (None: memory)
        self.working = working      # the Zarr store written chunk by chunk (None: memory)
        self.dataset = dataset      # in memory: the data; on disk: the layout (lazy)
        self.line_dims = line_dims  # dims of the per-line variables (without 'crossing')

    # ------------------------------------------------------------ making
    @classmethod
    def create(cls, path, template, chunks: dict, *, overwrite: bool = False) -> "Store":
        """A new store holding ``template`` (filled Dataset), chunked as ``chunks``
        ({dim: size}); refuses to replace an existing output unless ``overwrite``."""
        if path is None:
            return cls(None, None, template, _line_dims(template))
        path, working = _paths(path)
        for p in {path, working}:
            if p.exists() and not overwrite:
                raise InputError(f"--out: {p} exists; give --resume to continue that study "
                                 f"or --overwrite to replace it", key="--out")
        for p in {path, working}:
            _remove(p)
        encoding = {name: {"chunks": tuple(chunks.get(d, n) for d, n in var.sizes.items())}
                    for name, var in template.data_vars.items()}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", category=UserWarning)
            template.to_zarr(working, mode="w", encoding=encoding, consolidated=False)
        return cls(path, working, _open(working), _line_dims(template))

    @classmethod
    def resume(cls, path, attrs: dict) -> "Store | None":
        """The store of an interrupted study at ``path`` (None when there is none); refuses
        one made by another study, naming what differs."""
        path, working = _paths(path)
        if not working.exists():
            if path.exists() and path != working:   # a finished netCDF output
                raise InputError(f"--resume: {path} is a finished study (nothing to resume); "
                                 f"give --overwrite to compute it again", key="--resume")
            return None
        ds = _open(working)
        old = dict(ds.attrs)
        if old.get("study_key") != attrs["study_key"]:
            differs = [k for k in ("scene", "what", "design", "options")
                       if old.get(k) != attrs.get(k)]
            raise InputError(f"--resume: {working} holds another study (its "
                             f"{', '.join(differs) or 'key'} differ(s)); give the same "
                             f"scene and options, or --overwrite", key="--resume")
        return cls(path, working, ds, _line_dims(ds))

    # ------------------------------------------------------------ using
    def done(self) -> np.ndarray:
        """Boolean array of the design's shape: the points already computed."""
        return np.asarray(self.dataset["done"].values, dtype=bool)

    def write(self, dims: tuple, region: tuple, data: dict) -> None:
        """Write one finished chunk: ``data`` (variable -> array of the region's shape and
        the variable's own dimensions), ``done`` last."""
        xr = xarray_module()
        where = dict(zip(dims, region))
        point: dict = {}
        line: dict = {}
        for name, value in data.items():
            var_dims = self.dataset[name].dims
            (line if var_dims[:len(dims)] != dims else point)[name] = (var_dims, value)
        if self.working is None:
            for group in (point, line):
                for name, (var_dims, value) in group.items():
                    at = tuple(where.get(d, slice(None)) for d in var_dims)
                    self.dataset[name].values[at] = value
            self.dataset["done"].values[region] = True
            return
        line_where = {d: where[d] for d in self.line_dims}
        targets: list = [(point, where), (line, line_where)]
        for group, at in targets:
            if group:
                xr.Dataset(group).to_zarr(self.working, region=at, mode="r+",
                                          consolidated=False)
        shape = tuple(len(range(*s.indices(n))) for s, n in
                      zip(region, self.dataset["done"].shape))
        xr.Dataset({"done": (dims, np.ones(shape, dtype=bool))}).to_zarr(
            self.working, region=where, mode="r+", consolidated=False)

    def finish(self, complete: bool):
        """The Dataset, loaded; a complete netCDF study is written to its path (and the
        working store removed)."""
        if self.working is None:
            return self.dataset
        ds = _open(self.working).load()
        if complete and self.path != self.working:
            _write_netcdf(ds, self.path)
            _remove(self.working)
        return ds


def _paths(path) -> tuple:
    """(output, working Zarr store) of an ``--out`` path."""
    path = Path(os.fspath(path))
    suffix = path.suffix.lower()
    if suffix in ZARR_SUFFIXES:
        return path, path
    if suffix in NETCDF_SUFFIXES:
        return path, path.with_name(path.name + ".partial.zarr")
    raise InputError(f"--out: {path}: give a .zarr directory or a .nc file (netCDF)",
                     key="--out")


def _open(working):
    xr = xarray_module()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=UserWarning)
        return xr.open_zarr(working, consolidated=False)


def _line_dims(ds) -> tuple:
    """The design dimensions of the per-line variables (those with a ``crossing`` dim)."""
    for name, var in ds.data_vars.items():
        if "crossing" in var.dims:
            return tuple(d for d in var.dims if d != "crossing")
    return ()


def _remove(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()


def _write_netcdf(ds, path: Path) -> None:
    """netCDF with the first engine installed (netCDF4, h5netcdf, scipy's netCDF3)."""
    import importlib.util

    engine = next((e for e, mod in (("netcdf4", "netCDF4"), ("h5netcdf", "h5py"))
                   if importlib.util.find_spec(mod)), "scipy")
    tmp = path.with_name(path.name + ".tmp")
    out = ds.copy()
    if engine == "scipy":   # netCDF3: no bool variables
        for name, var in out.data_vars.items():
            if var.dtype == bool:
                out[name] = var.astype(np.int8)
                out[name].attrs["dtype"] = "bool"
    for var in out.variables.values():
        var.encoding.pop("chunks", None)
        var.encoding.pop("preferred_chunks", None)
    out.to_netcdf(tmp, engine=engine)
    os.replace(tmp, path)


def attrs_text(value) -> str:
    """A JSON text for an attribute (netCDF and Zarr both keep strings)."""
    return json.dumps(value, sort_keys=True, default=str)
