"""Where a study's results go (``--out``), checked before any work is done.

A study writes its Zarr store chunk by chunk. The output asked for is:

- a ``.zarr`` directory: written in place when nothing is there; a study nhham wrote
  that is replaced (``--overwrite``) is kept untouched while the new one is computed
  beside it in ``<out>.partial.zarr``, and swapped in only once the new one is complete;
- a ``.nc`` file: collected in ``<out>.partial.zarr`` and written as netCDF (to
  ``<out>.tmp``, then renamed) when the study is complete.

Only a store nhham wrote is replaced or resumed: one recognised by its attributes
(:func:`study_attrs`: the scene, what was computed, the study key and the nhham version).
A user's directory or file at ``--out`` that is not a study is refused, untouched. So is a
symbolic link (nhham does not replace what a link points to), a folder that does not
exist or where this process cannot write (tried, not guessed from permission bits), and a
store of another nhham version on ``--resume``.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

from nhham.errors import InputError

__all__ = ["Target", "check_out", "study_attrs", "unreadable_metadata", "replace_store",
           "remove", "PARTIAL", "NETCDF_SUFFIXES", "ZARR_SUFFIXES", "STUDY_ATTRS"]

NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf")
ZARR_SUFFIXES = (".zarr",)

#: The suffix of the store a study is computed in when it is not written in place.
PARTIAL = ".partial.zarr"

#: The metadata files of a Zarr store (format 3; format 2).
METADATA_FILES = ("zarr.json", ".zgroup", ".zattrs", ".zarray", ".zmetadata")

#: The attributes every store nhham writes has (how a study is recognised).
STUDY_ATTRS = ("scene", "what", "study_key", "nhham_version")


@dataclass(frozen=True)
class Target:
    """Where one study goes.

    Attributes
    ----------
    path : Path
        The output asked for.
    working : Path
        The Zarr store written chunk by chunk (``path`` itself, or beside it).
    netcdf : bool
        ``path`` is a netCDF file (written from ``working`` at the end).
    resuming : bool
        ``working`` holds an interrupted study to continue.
    """

    path: Path
    working: Path
    netcdf: bool
    resuming: bool = False

    @property
    def in_place(self) -> bool:
        """The study is written where it was asked for (nothing to move at the end)."""
        return self.working == self.path


def check_out(out, *, resume: bool = False, overwrite: bool = False) -> Target | None:
    """The :class:`Target` of ``--out`` (None: the results stay in memory).

    Raises
    ------
    InputError
        Naming ``--out`` (or ``--resume``): a suffix that is neither ``.zarr`` nor
        ``.nc``, a symbolic link, a folder that does not exist or cannot be written, an
        existing output without ``--resume`` or ``--overwrite``, an existing output that
        is not a study nhham wrote, a finished netCDF study to resume, a store of another
        nhham version to resume.
    """
    if out is None:
        return None
    path = Path(os.fspath(out))
    suffix = path.suffix.lower()
    if suffix not in ZARR_SUFFIXES + NETCDF_SUFFIXES:
        raise InputError(f"--out: {path}: give a .zarr directory or a .nc file (netCDF)",
                         key="--out")
    netcdf = suffix in NETCDF_SUFFIXES
    partial = path.with_name(path.name + PARTIAL)
    for p in (path, partial):
        if p.is_symlink():
            raise InputError(f"--out: {p} is a symbolic link; nhham replaces only what it "
                             f"wrote itself: give the path it points to, or another --out",
                             key="--out")
    folder = path.parent
    if not folder.is_dir():
        raise InputError(f"--out: the directory {str(folder)!r} does not exist", key="--out")
    problem = _unwritable(folder)
    if problem:
        raise InputError(f"--out: cannot write in {str(folder)!r} ({problem})", key="--out")
    for p in (path, partial):
        if p.exists() and study_attrs(p) is None:
            damaged = unreadable_metadata(p, arrays=False) if p.is_dir() else None
            if damaged:   # a store whose own metadata is damaged: named
                raise InputError(f"--out: {p} exists and {damaged}: nhham cannot tell "
                                 f"whether it is a study it wrote; move it away or give "
                                 f"another --out", key="--out")
            raise InputError(f"--out: {p} exists and is not a study nhham wrote (it has no "
                             f"study attributes); nhham replaces or resumes only its own "
                             f"results: move it away or give another --out", key="--out")
    if resume:
        return _resumed(path, partial, netcdf)
    if (path.exists() or partial.exists()) and not overwrite:
        there = path if path.exists() else partial
        raise InputError(f"--out: {there} exists; give --resume to continue that study or "
                         f"--overwrite to replace it", key="--out")
    # a study replacing one is computed beside it and swapped in once complete
    return Target(path, partial if (netcdf or path.exists()) else path, netcdf)


def _resumed(path: Path, partial: Path, netcdf: bool) -> Target:
    if partial.exists():
        working = partial
    elif path.exists():
        if netcdf:
            raise InputError(f"--resume: {path} is a finished study (nothing to resume); "
                             f"give --overwrite to compute it again", key="--resume")
        working = path
    else:   # nothing to resume: a new study
        return Target(path, partial if netcdf else path, netcdf)
    attrs = study_attrs(working) or {}
    from nhham.settings import __version__

    if attrs.get("nhham_version") != __version__:
        raise InputError(f"--resume: {working} was made by nhham {attrs.get('nhham_version')} "
                         f"(this is {__version__}); results of two versions are not mixed: "
                         f"give --overwrite to compute the study again", key="--resume")
    problem = _unwritable(working)
    if problem:
        raise InputError(f"--resume: cannot write in {working} ({problem})", key="--resume")
    return Target(path, working, netcdf, resuming=True)


def study_attrs(path) -> dict | None:
    """The attributes of the study stored at ``path`` (a Zarr directory or a netCDF
    file), or None when it is not a study nhham wrote (or cannot be read as one)."""
    path = Path(os.fspath(path))
    try:
        if path.is_dir():
            import zarr

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                attrs = dict(zarr.open_group(str(path), mode="r").attrs)
        elif path.is_file():
            import xarray as xr

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                with xr.open_dataset(path) as ds:
                    attrs = dict(ds.attrs)
        else:
            return None
    except Exception:   # anything that does not read as a study is not one
        return None
    if not all(isinstance(attrs.get(k), str) for k in STUDY_ATTRS):
        return None
    return attrs


def unreadable_metadata(path, arrays: bool = True) -> str | None:
    """Why the metadata of the Zarr store at ``path`` cannot be read (naming the file:
    one that is not JSON, or a folder of an array without one), or None. Read at the
    store's top and (``arrays``) in each folder of it (nhham's stores are flat: one
    folder an array).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "x.zarr"
    >>> (store / "done").mkdir(parents=True)
    >>> _ = (store / "zarr.json").write_text('{"zarr_format": 3, "node_type": "group"}')
    >>> _ = (store / "done" / "zarr.json").write_text('{"zarr_format": 3, "node_')
    >>> print(unreadable_metadata(store).split(store.name)[1])
    /done/zarr.json is not JSON (Unterminated string starting at: line 1 column 20 (char 19))
    """
    path = Path(os.fspath(path))
    format3 = (path / METADATA_FILES[0]).exists()
    folders = sorted(p for p in path.iterdir() if p.is_dir()) if arrays else []
    for folder in [path, *folders]:
        files = [folder / n for n in METADATA_FILES if (folder / n).is_file()]
        if not files and folder != path:
            return (f"{folder / ('zarr.json' if format3 else '.zarray')} is missing (the "
                    f"metadata of the array {folder.name})")
        for file in files:
            try:
                json.loads(file.read_bytes())
            except (OSError, ValueError) as exc:
                return f"{file} is not JSON ({exc})"
    return None


def _unwritable(folder: Path) -> str | None:
    """Why nothing can be created in ``folder`` (a file made and removed there), or
    None. Tried rather than read from the permission bits: a read-only file system, or
    a folder the superuser may not write in (``/proc``), is seen too."""
    try:
        fd, name = tempfile.mkstemp(prefix=".nhham-probe-", dir=folder)
    except OSError as exc:
        return exc.strerror or str(exc)
    os.close(fd)
    os.unlink(name)
    return None


def replace_store(new: Path, old: Path) -> None:
    """Put the complete store ``new`` at ``old`` (whatever study was there goes): the
    old one is moved aside, the new one renamed into place, the old one removed; at no
    moment is a half-written store at ``old``."""
    aside = old.with_name(old.name + ".replaced")
    remove(aside)
    if old.exists():
        os.rename(old, aside)
    os.rename(new, old)
    remove(aside)


def remove(path: Path) -> None:
    """Remove a file or directory tree if it is there."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    elif path.exists() or path.is_symlink():
        path.unlink()
