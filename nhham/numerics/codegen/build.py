"""Compiling the generated C and loading it: the cache of shared libraries.

:func:`compile_c` compiles a translation unit (made by :mod:`nhham.numerics.codegen.emit`)
with the system C compiler into a cache directory; the file name is a hash of the source,
the compiler, the flags and the platform, so a library is built once and reused across
runs and processes. :func:`build_compiled` builds and loads the library of a model: with
the CPython entry points when the Python and numpy headers are installed (single-state
calls without ctypes), else the plain ctypes library. A failed build of the CPython entry
points is remembered in the cache (a ``.failed`` file beside where the library would be),
so the next model with the same source goes straight to the plain library. No sympy here.

``$NHHAM_CFLAGS`` adds compiler flags (e.g. ``-O3 -march=native``; the default ``-O2`` is
portable: the cache may be shared between machines); ``$CC`` chooses the compiler;
``NHHAM_NO_CC=1`` disables the compiled backend; ``$NHHAM_CACHE`` moves the cache.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile

from nhham.errors import ComputationError
from nhham.numerics.kernels import CompiledRHS

__all__ = ["c_compiler", "compile_c", "build_compiled", "pyext_flags", "cache_directory"]

_FLAGS = ["-O2", "-fno-math-errno", "-shared", "-fPIC", "-std=c99"]


def c_compiler() -> str | None:
    """Path of the C compiler used for the compiled backend, or None.

    ``$CC`` is used when set, else ``cc``. Setting ``NHHAM_NO_CC=1`` disables
    the compiled backend (used to test the numpy fallback).
    """
    if os.environ.get("NHHAM_NO_CC"):
        return None
    return shutil.which(os.environ.get("CC", "cc"))


def cache_directory(cache_dir=None) -> str:
    """``cache_dir``, else ``$NHHAM_CACHE``, else ``~/.cache/nhham`` (created if needed)."""
    base = cache_dir or os.environ.get("NHHAM_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "nhham")
    os.makedirs(base, exist_ok=True)
    return base


def _user_flags() -> list:
    """Extra compiler flags from ``$NHHAM_CFLAGS``."""
    return os.environ.get("NHHAM_CFLAGS", "").split()


def pyext_flags():
    """Flags that also build the CPython entry points (``pyext.c``) and the ABI tag that
    belongs in the cache key, or None when the Python or numpy headers are not installed."""
    try:
        import numpy

        include = sysconfig.get_paths().get("include") or ""
        if not os.path.exists(os.path.join(include, "Python.h")):
            return None
        flags = ["-DNHHAM_PYEXT", f"-I{include}", f"-I{numpy.get_include()}"]
        return flags, f"{sysconfig.get_config_var('EXT_SUFFIX')} numpy {numpy.__version__}"
    except Exception:  # pragma: no cover - exotic installations
        return None


def compile_c(source: str, cache_dir=None, flags=(), tag: str = "",
              remember_failure: bool = False) -> str:
    """Compile ``source`` to a shared library in the cache; return its path.

    The file name is a hash of the source, the compiler, the flags, ``tag`` and the
    platform. ``flags`` are added to the portable defaults (and to ``$NHHAM_CFLAGS``).
    With ``remember_failure`` a failed compilation leaves ``<library>.failed`` with the
    compiler's message, and later calls with the same key fail at once with it.

    Raises
    ------
    ComputationError
        When no compiler is available or compilation fails (message included).
    """
    cc = c_compiler()
    if cc is None:
        raise ComputationError("no C compiler found (set CC, or unset NHHAM_NO_CC)")
    allflags = [*_FLAGS, *_user_flags(), *flags]
    key = hashlib.sha256("\0".join([source, cc, *allflags, tag, sys.platform,
                                    os.uname().machine]).encode()).hexdigest()[:20]
    directory = cache_directory(cache_dir)
    target = os.path.join(directory, f"nhham_{key}.so")
    failed = target + ".failed"
    if os.path.exists(target):
        return target
    if remember_failure and os.path.exists(failed):
        with open(failed, encoding="utf-8") as fh:
            raise ComputationError(fh.read())
    with tempfile.TemporaryDirectory(dir=directory) as tmp:
        src = os.path.join(tmp, "model.c")
        lib = os.path.join(tmp, "model.so")
        with open(src, "w") as fh:
            fh.write(source)
        proc = subprocess.run([cc, *allflags, "-o", lib, src, "-lm"], capture_output=True,
                              text=True, timeout=300)
        if proc.returncode != 0:
            message = f"C compilation failed: {proc.stderr.strip()[:2000]}"
            if remember_failure:
                with open(os.path.join(tmp, "failed"), "w", encoding="utf-8") as fh:
                    fh.write(message)
                os.replace(os.path.join(tmp, "failed"), failed)
            raise ComputationError(message)
        os.replace(lib, target)  # atomic: concurrent builders never see half a file
    return target


def build_compiled(sources, cache_dir):
    """``(CompiledRHS or None, note)``: the model's library, with the CPython entry points
    when they can be built, else plain ctypes, else None and why."""
    ext = pyext_flags() if "PyInit_nhham_ext" in sources["c"] else None
    ext_error = None
    if ext is not None:
        try:
            path = compile_c(sources["c"], cache_dir, ext[0], tag=ext[1], remember_failure=True)
            return (CompiledRHS.load(path, sources["layout"], extension=True),
                    f"compiled C with CPython entry points ({os.path.basename(path)})")
        except (ComputationError, OSError, ImportError, subprocess.SubprocessError) as exc:
            ext_error = str(exc)[:200]
    try:
        path = compile_c(sources["c"], cache_dir)
        compiled = CompiledRHS.load(path, sources["layout"])
    except (ComputationError, OSError, subprocess.SubprocessError) as exc:
        return None, str(exc)
    note = f"compiled C ({os.path.basename(path)})"
    if ext_error is not None:
        note += f"; CPython entry points unavailable ({ext_error})"
    return compiled, note
