"""The compile cache: where compiled libraries are kept, and why one is trusted.

Location, first that applies: the ``cache_dir`` argument, ``$NHHAM_CACHE``,
``$XDG_CACHE_HOME/nhham`` (an absolute ``XDG_CACHE_HOME`` only, as the XDG Base Directory
specification says), ``~/.cache/nhham``. The directory is created with mode 0700.

Loading a shared library runs its code, so nothing in the cache is loaded on trust (the
rules of pip's and ccache's caches):

- the directory must be owned by the user running nhham (the effective uid) and not be
  writable by group or others; otherwise it is not used at all: a warning says why, and
  the process compiles into a private temporary directory (removed at exit) instead;
- every library ``nhham_<key>.so`` has a record ``nhham_<key>.so.sha256`` written when it
  was built (``sha256sum`` format, so ``sha256sum -c`` checks it by hand); both must be
  regular files owned by the user and not writable by group or others, and the library's
  SHA-256 must be the recorded one. A library that fails any of these (corrupted,
  truncated, foreign-owned, writable by others, no record) is never loaded: a warning
  names it and the reason, and it is rebuilt (the new files replace it atomically);
- a library and its record are installed under an exclusive lock (``.lock``) and checked
  under a shared one, each by an atomic rename from a build directory inside the cache,
  so no reader ever sees half a file or a library with another build's record;
- a compilation that failed with compiler diagnostics is remembered (``<library>.failed``,
  with the nhham version), so later models with the same source fail at once instead of
  compiling again; a marker from another nhham version is retried once. A compiler killed
  by a signal or stopped by the time limit, or a full disk, leaves no marker.

The generated sources of a model (``sources_<key>.json``, the Python and C texts and their
layout, keyed by the system's content and a digest of nhham's own code) are kept the same
way, with a hash record, so that a model of a system seen before is loaded without
generating its code again (the bicycle's takes 4 s of sympy; a study's workers each
need it).

Build directories left by a process that was killed (``build-*``) are removed by a later
process once they are an hour old. No sympy here.
"""

from __future__ import annotations

import atexit
import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import stat
import tempfile
import threading
import time
import warnings
from dataclasses import dataclass

from nhham.settings import __version__
from nhham.numerics.model import NumericsWarning

__all__ = ["CompileCache", "cache_location", "untrusted_reason", "file_digest"]

#: Part of every cache key: a change of the cache's layout never meets old files.
CACHE_FORMAT = "2"

#: The texts a model's kept sources hold (what :func:`~nhham.numerics.codegen.emit.
#: generate_sources` returns).
SOURCE_KEYS = ("python", "c", "c_complex", "layout")

_STALE_BUILD_S = 3600.0
_LOCK = threading.Lock()
_PRIVATE: dict = {}  # refused location -> this process's temporary directory
_SWEPT: set = set()  # locations whose stale build directories were removed


def cache_location(cache_dir=None) -> str:
    """The cache directory that applies (absolute; not created, not checked).

    ``cache_dir``, else ``$NHHAM_CACHE``, else ``$XDG_CACHE_HOME/nhham`` when that
    variable is an absolute path, else ``~/.cache/nhham``.
    """
    if cache_dir:
        return os.path.abspath(os.path.expanduser(os.fspath(cache_dir)))
    given = os.environ.get("NHHAM_CACHE")
    if given:
        return os.path.abspath(os.path.expanduser(given))
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return os.path.join(xdg, "nhham")
    return os.path.join(os.path.expanduser("~"), ".cache", "nhham")


def untrusted_reason(st: os.stat_result, directory: bool = False) -> str | None:
    """Why a file (or the directory) with status ``st`` is not to be trusted, or None.

    It must be a regular file (a directory for ``directory``), owned by the effective
    uid, and not writable by group or others.
    """
    if directory and not stat.S_ISDIR(st.st_mode):
        return "is not a directory"
    if not directory and not stat.S_ISREG(st.st_mode):
        return "is not a regular file"
    uid = os.geteuid()
    if st.st_uid != uid:
        return f"is owned by uid {st.st_uid}, not by the user running nhham (uid {uid})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return (f"is writable by group or others (mode {stat.S_IMODE(st.st_mode):04o}; "
                f"chmod go-w fixes it)")
    return None


def file_digest(path: str) -> str:
    """SHA-256 of the file's bytes (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _warn(message: str) -> None:
    warnings.warn(message, NumericsWarning, stacklevel=4)


@dataclass(frozen=True)
class CompileCache:
    """A checked cache directory (see the module docstring); :meth:`open` makes one.

    Attributes
    ----------
    directory : str
    refusal : str or None
        Why the configured directory was refused, when this is the process's own
        temporary directory instead (removed at exit); None for the configured one.
    """

    directory: str
    refusal: str | None = None

    @property
    def private(self) -> bool:
        return self.refusal is not None

    @classmethod
    def open(cls, cache_dir=None) -> "CompileCache":
        """The cache at :func:`cache_location`, created and checked (at every call); a
        private temporary one, with a warning saying why, when that directory cannot be
        trusted or used (one per refused location and process)."""
        location = cache_location(cache_dir)
        reason = _refusal(location)
        with _LOCK:
            if reason is None:
                if location not in _SWEPT:
                    _SWEPT.add(location)
                    _remove_stale_builds(location)
                return cls(location)
            private = _PRIVATE.get(location)
            if private is None:
                private = _PRIVATE[location] = tempfile.mkdtemp(prefix="nhham-cache-")
                atexit.register(shutil.rmtree, private, True)
        _warn(f"compile cache {location} {reason}; compiled code goes to a private "
              f"temporary directory for this process instead (set NHHAM_CACHE to a "
              f"directory only you can write)")
        return cls(private, refusal=reason)

    # ------------------------------------------------------------- names
    def library(self, key: str) -> str:
        """Path of the library with cache key ``key``."""
        return os.path.join(self.directory, f"nhham_{key}.so")

    @staticmethod
    def record(library: str) -> str:
        return library + ".sha256"

    @staticmethod
    def marker(library: str) -> str:
        return library + ".failed"

    # ----------------------------------------------------------- reading
    def lookup(self, key: str, problems: list | None = None) -> str | None:
        """The library of ``key`` when it is there and verified, else None.

        A library that is there but fails verification is never loaded; why (one line
        naming the file) is appended to ``problems`` when given, and None is returned
        (the caller rebuilds it: the new files replace it).
        """
        library = self.library(key)
        if not os.path.lexists(library):
            return None
        with self._locked(fcntl.LOCK_SH):
            reason = self._verify(library)
        if reason is None:
            return library
        if problems is not None:
            problems.append(f"cached library {library} {reason}: not loaded, rebuilt")
        return None

    def _verify(self, library: str) -> str | None:
        """Why ``library`` is not to be loaded, or None."""
        record = self.record(library)
        try:
            reason = untrusted_reason(os.lstat(library))
            if reason:
                return reason
            st = os.lstat(record)
        except FileNotFoundError:
            return "has no hash record (built by an older nhham, or the record was removed)"
        reason = untrusted_reason(st)
        if reason:
            return f"has a hash record that {reason}"
        with open(record, encoding="ascii", errors="replace") as fh:
            fields = fh.read(200).split()
        if len(fields) != 2 or fields[1] != os.path.basename(library) or len(fields[0]) != 64:
            return "has a malformed hash record"
        if file_digest(library) != fields[0]:
            return ("does not match its recorded SHA-256 (corrupted or truncated since it "
                    "was built)")
        return None

    def has_sources(self, key: str) -> bool:
        """Whether sources are kept under ``key`` (not verified: :meth:`sources` does)."""
        return os.path.lexists(os.path.join(self.directory, f"sources_{key}.json"))

    def sources(self, key: str) -> dict | None:
        """Generated sources kept by :meth:`keep_sources` under ``key``, verified like a
        library (their Python text is executed when a model loads), or None."""
        path = os.path.join(self.directory, f"sources_{key}.json")
        if not os.path.lexists(path):
            return None
        with self._locked(fcntl.LOCK_SH):
            reason = self._verify(path)
            if reason is None:
                try:
                    with open(path, encoding="utf-8") as fh:
                        data = json.load(fh)
                except (OSError, ValueError):
                    return None
        if reason is not None:
            _warn(f"cached sources {path} {reason}: not used, generated again")
            return None
        if not isinstance(data, dict) or set(data) != set(SOURCE_KEYS):
            return None
        data["layout"] = {k: tuple(v) if isinstance(v, list) else v
                          for k, v in data["layout"].items()}
        return data

    def keep_sources(self, key: str, sources: dict) -> None:
        """Keep a model's generated sources (and their hash record) under ``key``; a
        failure to write them (a full disk) is ignored."""
        self._keep_json(f"sources_{key}.json", sources)

    def table(self, name: str) -> dict | None:
        """Numbers kept by :meth:`keep_table` under ``name``, verified like a library, or
        None (absent, unreadable or not to be trusted)."""
        path = os.path.join(self.directory, f"{name}.json")
        if not os.path.lexists(path):
            return None
        with self._locked(fcntl.LOCK_SH):
            if self._verify(path) is not None:
                return None
            try:
                with open(path, encoding="utf-8") as fh:
                    data = json.load(fh)
            except (OSError, ValueError):
                return None
        return data if isinstance(data, dict) else None

    def keep_table(self, name: str, table: dict) -> None:
        """Keep ``table`` (JSON numbers: floats round-trip exactly) under ``name``; a
        failure to write it is ignored."""
        self._keep_json(f"{name}.json", table)

    def _keep_json(self, filename: str, data: dict) -> None:
        """Write ``data`` as JSON to ``filename`` in the cache (staged, then moved in
        with its hash record); a failure to write is ignored."""
        path = os.path.join(self.directory, filename)
        with contextlib.suppress(OSError), self.build_directory() as build:
            staged = os.path.join(build, os.path.basename(path))
            with open(staged, "w", encoding="utf-8") as fh:
                json.dump(data, fh)
            self._move_in(staged, path, 0o644)

    def failure(self, key: str) -> str | None:
        """The compiler's message of a failed build of ``key`` remembered by this version
        of nhham, or None (no marker, an untrusted one, or one from another version)."""
        marker = self.marker(self.library(key))
        try:
            if untrusted_reason(os.lstat(marker)):
                return None
            with open(marker, encoding="utf-8") as fh:
                data = json.load(fh)
        except (OSError, ValueError):
            return None
        if not isinstance(data, dict) or data.get("nhham_version") != __version__:
            return None
        return f"{data.get('message', '')} (remembered in {marker}; delete it to retry)"

    # ----------------------------------------------------------- writing
    @contextlib.contextmanager
    def build_directory(self):
        """A fresh private directory inside the cache for one build, removed afterwards."""
        path = tempfile.mkdtemp(prefix="build-", dir=self.directory)
        try:
            yield path
        finally:
            shutil.rmtree(path, ignore_errors=True)

    def install(self, built: str, key: str) -> str:
        """Move the library ``built`` (inside a build directory) into the cache with its
        hash record; return its path."""
        library = self.library(key)
        self._move_in(built, library, 0o755)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.marker(library))
        return library

    def _move_in(self, staged: str, target: str, mode: int) -> None:
        """Move ``staged`` (in a build directory) to ``target`` with its hash record, both
        by atomic renames under the exclusive lock (record first: no reader sees a file
        without its record)."""
        os.chmod(staged, mode)
        record = staged + ".sha256"
        with open(record, "w", encoding="ascii") as fh:
            fh.write(f"{file_digest(staged)}  {os.path.basename(target)}\n")
        os.chmod(record, 0o644)
        with self._locked(fcntl.LOCK_EX):
            os.replace(record, self.record(target))
            os.replace(staged, target)

    def remember_failure(self, key: str, message: str, diagnostics: str,
                         build_dir: str) -> None:
        """Keep the failure of ``key`` (see :meth:`failure`): ``message`` and the
        compiler's whole ``diagnostics``; a failure to write it (a full disk) is ignored:
        the build is then simply retried."""
        staged = os.path.join(build_dir, "failed")
        with contextlib.suppress(OSError):
            with open(staged, "w", encoding="utf-8") as fh:
                json.dump({"nhham_version": __version__, "message": message,
                           "diagnostics": diagnostics}, fh, indent=1)
            os.chmod(staged, 0o644)
            os.replace(staged, self.marker(self.library(key)))

    # ------------------------------------------------------------- misc
    @contextlib.contextmanager
    def _locked(self, how):
        fd = os.open(os.path.join(self.directory, ".lock"),
                     os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        try:
            fcntl.flock(fd, how)
            yield
        finally:
            os.close(fd)


def _refusal(location: str) -> str | None:
    """Why the directory ``location`` (created if missing, mode 0700) is not to be used
    as the cache, or None."""
    try:
        os.makedirs(location, mode=0o700, exist_ok=True)
        reason = untrusted_reason(os.stat(location), directory=True)
    except OSError as exc:
        return f"cannot be created or read ({exc.strerror or exc})"
    if reason is None and not os.access(location, os.W_OK | os.X_OK):
        return "is not writable"
    return reason


def _remove_stale_builds(location: str) -> None:
    """Build directories of killed processes, an hour after they were last written."""
    limit = time.time() - _STALE_BUILD_S
    with contextlib.suppress(OSError):
        for entry in os.scandir(location):
            if (entry.name.startswith("build-") and entry.is_dir(follow_symlinks=False)
                    and entry.stat(follow_symlinks=False).st_mtime < limit):
                shutil.rmtree(entry.path, ignore_errors=True)
