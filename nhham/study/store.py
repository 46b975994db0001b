"""Where a study's results go: a labelled xarray Dataset, written chunk by chunk.

The Dataset has one dimension per swept parameter, named after it, with its values as the
coordinate (``sample`` for samples, with the drawn values as coordinates along it), the
variables of the study's kind (:mod:`~nhham.study.stability`,
:mod:`~nhham.study.ensemble`, :mod:`~nhham.study.classes`), a boolean ``done`` per point,
and in its attributes the scene (its text), the nhham version, what was computed, the
design and the options (JSON texts) and the hash of the generated code.

On disk it is a Zarr store (``.zarr``; where it is written and what may be replaced:
:mod:`~nhham.study.target`): the layout is written first, without data (a chunk never
written reads as its variable's fill value: NaN, -1, False), then each finished chunk is
written to its region (every chunk file written, also one equal to the fill), ``done``
last. An interrupted study leaves a store whose ``done`` says which chunks are there, so
:meth:`Store.resume` continues with the others and loses nothing; a resumed study must be
the same one (the nhham version, the hash of the generated code, and its ``study_key``
attribute: scene, kind, design and options), and a chunk marked done whose data files are
missing is computed again. A netCDF output (``.nc``) is collected in
``<out>.partial.zarr`` the same way and written as netCDF (by xarray, with the first
engine that is installed: netCDF4, h5netcdf, scipy) when the study is complete. The
metadata of a complete store is consolidated (``xarray.open_zarr`` reads it at once,
without a warning). Without a path the Dataset stays in memory.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import warnings
from itertools import product
from pathlib import Path

import numpy as np

from nhham.errors import InputError, OptionalDependencyError, OutputUnwritable
from nhham.study.target import (NETCDF_SUFFIXES, PARTIAL, ZARR_SUFFIXES, Target, remove,
                                replace_store)

__all__ = ["Store", "study_key", "attrs_text", "xarray_module", "regions_of", "unwritable",
           "NETCDF_SUFFIXES", "ZARR_SUFFIXES"]


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


def unwritable(exc: OSError, where) -> OutputUnwritable:
    """The failure of a write to a study's store (a full disk, a quota, a folder made
    read-only meanwhile): what to do about it, in one line."""
    reason = exc.strerror or str(exc)
    hint = ("free some space" if exc.errno in (errno.ENOSPC, errno.EDQUOT)
            else "make it writable")
    return OutputUnwritable(f"could not write the study to {where} ({reason}); what "
                            f"finished before is kept there: {hint} and continue with "
                            f"--resume", key="--out")


class Store:
    """A study's Dataset, in memory or on disk (see the module docstring).

    Use :meth:`create` or :meth:`resume`; then :meth:`write` each finished chunk and
    :meth:`finish`.
    """

    def __init__(self, target: Target | None, dataset, line_dims):
        self.target = target        # where it goes (None: memory)
        self.dataset = dataset      # in memory: the data; on disk: the layout (lazy)
        self.line_dims = line_dims  # dims of the per-line variables (without 'crossing')

    @property
    def path(self):
        """The output asked for (None: memory)."""
        return None if self.target is None else self.target.path

    @property
    def working(self):
        """The Zarr store written chunk by chunk (None: memory)."""
        return None if self.target is None else self.target.working

    # ------------------------------------------------------------ making
    @classmethod
    def create(cls, target: Target | None, template, chunks: dict,
               fills: dict | None = None) -> "Store":
        """A new store holding ``template`` (on disk its variables are lazy arrays of
        their fill values, ``fills`` by name: only the layout is written), chunked as
        ``chunks`` ({dim: size}), where ``target``
        (:func:`~nhham.study.target.check_out`) says.

        Raises
        ------
        OutputUnwritable
            The layout could not be written (nothing is left of it).
        """
        if target is None:
            return cls(None, template, _line_dims(template))
        working = target.working
        remove(working)   # a study (check_out made sure): an abandoned replacement
        if target.in_place:
            remove(working.with_name(working.name + PARTIAL))
        encoding: dict = {}
        for name, var in template.data_vars.items():
            encoding[name] = {"chunks": tuple(chunks.get(d, n) for d, n in var.sizes.items())}
            if var.dtype.kind in "iub":   # an unwritten chunk reads as the fill
                encoding[name]["fill_value"] = (fills or {}).get(name)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", category=UserWarning)
                template.to_zarr(working, mode="w-", encoding=encoding, consolidated=False,
                                 compute=False)
        except OSError as exc:
            remove(working)
            raise unwritable(exc, working) from None
        return cls(target, _open(working), _line_dims(template))

    @classmethod
    def resume(cls, target: Target, attrs: dict) -> "Store":
        """The store of the interrupted study at ``target.working``; refuses one that
        cannot be read, made by another nhham or code, or by another study (naming what
        differs)."""
        working = target.working
        try:
            ds = _open(working)
            ds["done"]
        except Exception as exc:
            raise InputError(f"--resume: {working} cannot be read as a study "
                             f"({type(exc).__name__}: {exc}); give --overwrite to compute "
                             f"it again", key="--resume") from None
        old = dict(ds.attrs)
        if old.get("nhham_version") != attrs["nhham_version"]:
            raise InputError(f"--resume: {working} was made by nhham "
                             f"{old.get('nhham_version')} (this is {attrs['nhham_version']}); "
                             f"results of two versions are not mixed: give --overwrite",
                             key="--resume")
        if old.get("code_hash") != attrs["code_hash"]:
            raise InputError(f"--resume: {working} was made from other generated code (code "
                             f"hash {str(old.get('code_hash'))[:12]} against "
                             f"{attrs['code_hash'][:12]}: another nhham, code generator or "
                             f"scene); give --overwrite", key="--resume")
        if old.get("study_key") != attrs["study_key"]:
            differs = [k for k in ("scene", "what", "design", "options")
                       if old.get(k) != attrs.get(k)]
            raise InputError(f"--resume: {working} holds another study (its "
                             f"{', '.join(differs) or 'key'} differ(s)); give the same "
                             f"scene and options, or --overwrite", key="--resume")
        return cls(target, ds, _line_dims(ds))

    # ------------------------------------------------------------ using
    def chunk_sizes(self, dims: tuple) -> tuple | None:
        """The Zarr chunk sizes of ``done`` along ``dims`` (None in memory)."""
        if self.target is None:
            return None
        chunks = self.dataset["done"].encoding.get("chunks")
        return None if chunks is None else tuple(int(c) for c in chunks)

    def done(self, regions=None, names=None) -> np.ndarray:
        """Boolean array of the design's shape: the points already computed. With
        ``regions`` (on disk), a region marked done whose data files (of the variables
        ``names``, those each chunk writes; default all) are not all there (deleted, or
        never written) is taken as not done, to be computed again."""
        done = np.array(self.dataset["done"].values, dtype=bool)   # a copy
        if regions is None or self.target is None:
            return done
        present = _ChunkFiles(self.working, self.dataset, names)
        for region in regions:
            if done[region].all() and not present.all_there(region):
                done[region] = False
        return done

    def lines(self, dims: tuple, region: tuple, names) -> dict:
        """The per-line variables ``names`` stored for the lines of ``region``."""
        # each variable's own lines (those along the second axis have other dims); on
        # disk the layout is lazy: its values are read from the store now
        return {n: np.array(self.dataset[n].isel(
            {d: s for d, s in zip(dims, region) if d in self.dataset[n].dims}).values)
            for n in names}

    def write(self, dims: tuple, region: tuple, data: dict) -> None:
        """Write one finished chunk: ``data`` (variable -> array of the region's shape and
        the variable's own dimensions), ``done`` last.

        Raises
        ------
        OutputUnwritable
            A write failed (``done`` of the region is then not set: it is computed
            again on resume).
        """
        xr = xarray_module()
        where = dict(zip(dims, region))
        point: dict = {}
        line: dict = {}
        for name, value in data.items():
            var_dims = self.dataset[name].dims
            (line if var_dims[:len(dims)] != dims else point)[name] = (var_dims, value)
        if self.target is None:
            for group in (point, line):
                for name, (var_dims, value) in group.items():
                    at = tuple(where.get(d, slice(None)) for d in var_dims)
                    self.dataset[name].values[at] = value
            self.dataset["done"].values[region] = True
            return
        groups: dict = {}   # the per-line variables by the design dims of their lines
        for name, (var_dims, value) in line.items():
            line_at = {d: where[d] for d in var_dims if d in where}
            groups.setdefault(tuple(line_at), ({}, line_at))[0][name] = (var_dims, value)
        shape = tuple(len(range(*s.indices(n))) for s, n in
                      zip(region, self.dataset["done"].shape))
        targets: list = [(point, where), *groups.values(),
                         ({"done": (dims, np.ones(shape, dtype=bool))}, where)]
        try:
            for group, at in targets:
                if group:
                    xr.Dataset(group).to_zarr(self.working, region=at, mode="r+",
                                              consolidated=False, write_empty_chunks=True)
        except OSError as exc:
            raise unwritable(exc, self.working) from None

    def finish(self, complete: bool):
        """The Dataset (on disk: opened lazily; a netCDF output: loaded). A complete
        study's metadata is consolidated and it is put where it was asked for: a
        replaced study swapped for it, a netCDF file written.

        Raises
        ------
        OutputUnwritable
            The netCDF file (or the move into place) could not be written; the complete
            store is kept beside it and ``--resume`` writes it.
        """
        if self.target is None:
            return self.dataset
        target = self.target
        if not complete:
            return _open(target.working)
        try:
            _consolidate(target.working)
            if target.netcdf:
                ds = _open(target.working).load()
                _write_netcdf(ds, target.path)
                remove(target.working)
                return ds
            if not target.in_place:
                replace_store(target.working, target.path)
        except OSError as exc:
            raise unwritable(exc, target.working) from None
        return _open(target.path)


class _ChunkFiles:
    """Which chunk files of a Zarr store are on disk (the store's own layout of keys)."""

    def __init__(self, working: Path, ds, names=None):
        self.working, self.ds = Path(working), ds
        self.arrays: dict = {}
        try:
            import zarr

            group = zarr.open_group(str(working), mode="r")
            for name, var in ds.data_vars.items():
                chunks = var.encoding.get("chunks")
                if names is not None and name not in names or var.size == 0:
                    continue   # not written by the chunks (or no file at all)
                if chunks is not None:
                    self.arrays[name] = (group[name].metadata, var.dims, tuple(chunks))
        except Exception:   # a layout of keys not known here: nothing is checked
            self.arrays = {}

    def all_there(self, region: tuple) -> bool:
        dims = self.ds["done"].dims
        starts = {d: s.start or 0 for d, s in zip(dims, region)}
        for name, (meta, var_dims, chunks) in self.arrays.items():
            coords = tuple(starts.get(d, 0) // c for d, c in zip(var_dims, chunks))
            try:
                key = meta.encode_chunk_key(coords)
            except Exception:
                return True
            if not (self.working / name / key).exists():
                return False
        return True


def regions_of(shape: tuple, sizes: tuple) -> list:
    """The regions of a regular grid of chunks of ``sizes`` over ``shape``, in C order."""
    ranges = [range(0, n, s) for n, s in zip(shape, sizes)]
    return [tuple(slice(a, min(a + s, n)) for a, s, n in zip(starts, sizes, shape))
            for starts in product(*ranges)]


def _open(working):
    xr = xarray_module()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=UserWarning)
        return xr.open_zarr(working, consolidated=False)


def _consolidate(working) -> None:
    """Consolidated metadata (one read opens the store; ``xarray.open_zarr`` does not
    warn that it is missing). Zarr 3 warns that the format does not specify it yet."""
    import zarr

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zarr.consolidate_metadata(str(working))


def _line_dims(ds) -> tuple:
    """The design dimensions of the per-line variables (those with a ``crossing`` dim)."""
    for name, var in ds.data_vars.items():
        if "crossing" in var.dims:
            return tuple(d for d in var.dims if d != "crossing")
    return ()


def _write_netcdf(ds, path: Path) -> None:
    """netCDF with the first engine installed (netCDF4, h5netcdf, scipy's netCDF3),
    written to ``<path>.tmp`` and renamed: a failure (a full disk) leaves neither a
    half-written file nor the temporary one."""
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
        var.encoding.pop("fill_value", None)
    try:
        out.to_netcdf(tmp, engine=engine)
        os.replace(tmp, path)
    except BaseException:
        remove(tmp)
        raise


def attrs_text(value) -> str:
    """A JSON text for an attribute (netCDF and Zarr both keep strings)."""
    return json.dumps(value, sort_keys=True, default=str)
