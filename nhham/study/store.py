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
attribute: scene, kind, design and options). A resumed store is read back, every chunk
of it (about as long as reading the results once): a chunk file that cannot be decoded
(truncated by a full disk or an interrupted copy) is removed, with the chunks of the
other values of its points or lines, and named in a warning; a chunk marked done whose
data files are missing (or were so removed) is computed again. Metadata or coordinates
that cannot be read refuse the store, naming the file. A netCDF output (``.nc``) is
collected in ``<out>.partial.zarr`` the same way and written as netCDF (by xarray, with
the first engine that is installed: netCDF4, h5netcdf, scipy) when the study is
complete. The metadata of a complete store is consolidated (``xarray.open_zarr`` reads
it at once, without a warning). Without a path the Dataset stays in memory.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import warnings
from itertools import product
from pathlib import Path

import numpy as np

from nhham.errors import InputError, NhhamWarning, OptionalDependencyError, OutputUnwritable
from nhham.study.target import (NETCDF_SUFFIXES, PARTIAL, ZARR_SUFFIXES, Target, remove,
                                replace_store, unreadable_metadata)

__all__ = ["Store", "study_key", "attrs_text", "xarray_module", "zarr_module",
           "MINIMUM_VERSIONS", "regions_of", "unwritable",
           "NETCDF_SUFFIXES", "ZARR_SUFFIXES"]


def study_key(attrs: dict) -> str:
    """A hash of what makes two studies the same (scene text, kind, design, options)."""
    parts = [attrs["scene"], attrs["what"], attrs["design"], attrs["options"]]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


#: The oldest versions the study's results are tested with (the study extra's pins):
#: zarr before 3.1.2 leaves a chunk equal to its fill value unwritten though xarray asks
#: for every chunk (``write_empty_chunks``; a resumed study then takes its chunks for
#: missing and computes them all again), and zarr 2 no longer runs under xarray 2026
#: (``open_group() got an unexpected keyword argument 'zarr_format'``); xarray before
#: 2026.1 cannot write the netCDF output (its names: numpy's StringDType) and before
#: 2025.10 a one-dimensional study's lines (``region``).
MINIMUM_VERSIONS = {"xarray": (2026, 1), "zarr": (3, 1, 2)}


def xarray_module():
    """xarray, or the error naming the extra that installs it (or a newer one)."""
    try:
        import xarray as xr
    except ImportError:
        raise OptionalDependencyError(
            "parameter studies store their results with xarray (and zarr); install the "
            "study extra: pip install 'nhham[study]'") from None
    return _checked(xr, "xarray")


def zarr_module():
    """zarr, or the error naming the extra that installs it (or a newer one)."""
    try:
        import zarr
    except ImportError:
        raise OptionalDependencyError(
            "parameter studies write their results with zarr; install the study extra: "
            "pip install 'nhham[study]'") from None
    return _checked(zarr, "zarr")


def _checked(module, name: str):
    """``module``, refused when it is older than :data:`MINIMUM_VERSIONS` says.

    Examples
    --------
    >>> import types
    >>> _checked(types.SimpleNamespace(__version__="2.18.7"), "zarr")
    Traceback (most recent call last):
    ...
    nhham.errors.OptionalDependencyError: parameter studies need zarr >= 3.1.2 (this is 2.18.7); update the study extra: pip install -U 'nhham[study]'
    """
    version = str(getattr(module, "__version__", ""))
    release = tuple(int(n) for n in re.findall(r"\d+", version.split("+")[0])[:3])
    least = MINIMUM_VERSIONS[name]
    if release and release < least:
        raise OptionalDependencyError(
            f"parameter studies need {name} >= {'.'.join(map(str, least))} (this is "
            f"{version}); update the study extra: pip install -U 'nhham[study]'")
    return module


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
        zarr_module()
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
    def resume(cls, target: Target, attrs: dict, written=()) -> "Store":
        """The store of the interrupted study at ``target.working``, every chunk read
        back; refuses one whose metadata or layout (coordinates) cannot be read, made by
        another nhham or code, or by another study (naming what differs).

        ``written``: the variables each chunk writes. A chunk of one of them (or of
        ``done``) that cannot be read back (truncated by a full disk or an interrupted
        copy) is removed, so that it reads as never written: its points are computed
        again, and a warning names it.

        Raises
        ------
        InputError
            Naming ``--resume`` and the file that cannot be read.
        """
        zarr_module()
        working = target.working
        damaged = unreadable_metadata(working)
        if damaged:
            raise InputError(f"--resume: {working} cannot be read as a study ({damaged}); "
                             f"give --overwrite to compute it again", key="--resume")
        try:
            ds = _open(working)
            ds["done"]
        except Exception as exc:
            damage = _unreadable_layout(working)   # an index's chunk, named
            if damage is not None:
                raise damage from None
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
        _read_back(working, ds, {*written, "done"})
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
        present = _ChunkFiles(self.working, names, self.dataset)
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
    """The chunk files of a Zarr store's arrays (in the store's own layout of keys): which
    are there, and which cannot be read back.

    ``names``: the arrays looked at (default: all those of the store); an array without
    elements has no file at all and is skipped. ``ds``: the store opened by xarray (the
    dimensions of its variables, for :meth:`key` and :meth:`all_there`).
    """

    #: At most this many bytes are decoded at once when a store is read back.
    SLAB_BYTES = 64 * 2 ** 20

    def __init__(self, working: Path, names=None, ds=None):
        self.working, self.ds = Path(working), ds
        group = _group(working)
        arrays = dict(group.arrays()) if names is None else {n: group[n] for n in names}
        self.arrays: dict = {n: a for n, a in arrays.items() if np.prod(a.shape) > 0}

    def key(self, name: str, region: tuple) -> tuple:
        """The chunk of ``name`` holding ``region``'s values (its chunk coordinates)."""
        dims = self.ds["done"].dims
        starts = {d: s.start or 0 for d, s in zip(dims, region)}
        array = self.arrays[name]
        return tuple(starts.get(d, 0) // c for d, c in zip(self.ds[name].dims, array.chunks))

    def path(self, name: str, coords: tuple) -> Path:
        """The file of one chunk of ``name``."""
        # the store's own key encoding (format 3: c/0/1; format 2: 0.1)
        return self.working / name / self.arrays[name].metadata.encode_chunk_key(coords)

    def all_there(self, region: tuple) -> bool:
        """Every file of ``region``'s chunks is on disk."""
        return all(self.path(name, self.key(name, region)).exists() for name in self.arrays)

    def unreadable(self) -> list:
        """(name, chunk coordinates, why) of each chunk file that is there and cannot be
        decoded (truncated, overwritten): every chunk is read back, a slab of chunks at a
        time, and a slab that fails one chunk at a time."""
        found = []
        for name, array in self.arrays.items():
            for coords, exc in _unreadable_blocks(array, self.SLAB_BYTES):
                found.append((name, coords, f"{type(exc).__name__}: {exc}"))
        return found


def _unreadable_blocks(array, slab_bytes: int):
    """(chunk coordinates, exception) of the chunks of a zarr ``array`` that cannot be
    read. Slabs along the axis with the most chunks, of at most ``slab_bytes`` (at least
    one chunk thick); a missing chunk reads as the fill value and is not one of them."""
    grid = [-(-n // c) for n, c in zip(array.shape, array.chunks)]
    if not grid:
        try:
            array[...]
        except Exception as exc:
            yield (), exc
        return
    axis = max(range(len(grid)), key=lambda a: grid[a])
    itemsize = getattr(array.dtype, "itemsize", 0) or 8
    layer = int(np.prod(array.shape)) * itemsize // max(grid[axis], 1)
    step = max(1, slab_bytes // max(layer, 1))
    chunk = array.chunks[axis]
    for first in range(0, grid[axis], step):
        last = min(first + step, grid[axis])
        slab = [slice(None)] * len(grid)
        slab[axis] = slice(first * chunk, min(last * chunk, array.shape[axis]))
        try:
            array[tuple(slab)]
            continue
        except Exception:
            pass
        ranges = [range(n) for n in grid]
        ranges[axis] = range(first, last)
        for coords in product(*ranges):
            try:
                array.get_block_selection(coords)
            except Exception as exc:
                yield coords, exc


def _read_back(working: Path, ds, written: set) -> None:
    """Read back every chunk of the store at ``working``: one of the ``written``
    variables that cannot be decoded is removed (it reads as never written), with the
    chunks of the other written variables of the same points or lines (whose values go
    together: a line's crossings and their count), and named in one warning; one of the
    layout (coordinates) refuses the store."""
    files = _ChunkFiles(working)
    broken = files.unreadable()
    for name, coords, why in broken:
        if name not in written:
            raise _damaged(working, files, name, coords, why)
    if not broken:
        return
    design = ds["done"].dims
    for name, coords, _ in broken:
        at = {d: c for d, c in zip(ds[name].dims, coords) if d in design}
        for other in written & set(files.arrays):
            dims = ds[other].dims
            if {d for d in dims if d in design} == set(at):
                remove(files.path(other, tuple(at.get(d, 0) for d in dims)))
    shown = "; ".join(f"{files.path(name, coords).relative_to(files.working)}: {why}"
                      for name, coords, why in broken[:3])
    more = f"; and {len(broken) - 3} more" if len(broken) > 3 else ""
    warnings.warn(f"--resume: {len(broken)} chunk file(s) of {working} cannot be read back "
                  f"({shown}{more}): removed, their points are computed again",
                  NhhamWarning, stacklevel=3)


def _unreadable_layout(working: Path) -> InputError | None:
    """The refusal naming the first chunk of the store that cannot be read back, if one
    is found (None: none, or the store cannot even be listed)."""
    try:
        files = _ChunkFiles(working)
        broken = files.unreadable()
    except Exception:   # nothing more precise to say than the caller's reason
        return None
    return _damaged(working, files, *broken[0]) if broken else None


def _damaged(working, files, name, coords, why) -> InputError:
    """The refusal of a store whose layout (a coordinate) cannot be read back."""
    return InputError(f"--resume: {working} cannot be read as a study (its layout file "
                      f"{files.path(name, coords)} cannot be read back: {why}); give "
                      f"--overwrite to compute it again", key="--resume")


def regions_of(shape: tuple, sizes: tuple) -> list:
    """The regions of a regular grid of chunks of ``sizes`` over ``shape``, in C order."""
    ranges = [range(0, n, s) for n, s in zip(shape, sizes)]
    return [tuple(slice(a, min(a + s, n)) for a, s, n in zip(starts, sizes, shape))
            for starts in product(*ranges)]


def _group(working):
    """The store's root group, read only."""
    import zarr

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return zarr.open_group(str(working), mode="r")


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
