"""Compiling the generated C into the compile cache, and loading it.

:func:`compile_c` compiles one translation unit (made by :mod:`nhham.numerics.codegen.emit`)
with the system C compiler into the compile cache (:mod:`.cache`: where it is, and how a
cached library is verified before it is loaded); the cache key is a hash of the source,
the compiler, the flags, a tag and the platform, so a library is built once and reused
across runs and processes. :func:`build_library` builds the library of a model: with the
CPython entry points when the Python and numpy headers are installed (single-state calls
without ctypes), else the plain ctypes library; :func:`find_library` only looks.

The compiler runs in a process group of its own: when the caller is interrupted, or a
background build is stopped (:mod:`.background`), the whole group (driver, ``cc1``,
assembler, linker) is killed and the build directory removed, so no compiler is left
running and no half-written file reaches the cache.

``$CC`` chooses the compiler; ``NHHAM_NO_CC=1`` disables the compiled backend;
``$NHHAM_CFLAGS`` adds compiler flags (e.g. ``-O3 -march=native``; the default ``-O2`` is
portable: the cache may be shared between machines of one user). No sympy here.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import signal
import subprocess
import sys
import sysconfig
import threading
from dataclasses import dataclass

from nhham.errors import BudgetExceeded, ComputationError
from nhham.numerics.codegen.cache import CACHE_FORMAT, CompileCache
from nhham.numerics.kernels import CompiledRHS, ComplexKernels

__all__ = ["c_compiler", "compile_c", "complex_kernels", "build_library", "find_library", "load_library",
           "pyext_flags", "Compilation", "LibraryBuild", "CompilerStopped"]

_FLAGS = ("-fno-math-errno", "-fcx-limited-range", "-shared", "-fPIC", "-std=c99")
#: The optimisation level of the model's library (the integrators' inner loop).
OPTIMIZE = "-O2"
#: ... and of the complex-step kernels. GCC's register allocator spends 13-18 s at -O1 or
#: -O2 on the bicycle's straight-line complex code (65 % of it assigning hard registers)
#: and 0.6 s at -O0; the kernel runs 7.7 instead of 5.8 us a state, bit for bit the same
#: (no fast-math: IEEE arithmetic at every level).
OPTIMIZE_COMPLEX = "-O0"
_TIMEOUT_S = 300


def c_compiler() -> str | None:
    """Path of the C compiler used for the compiled backend, or None.

    ``$CC`` is used when set, else ``cc``. Setting ``NHHAM_NO_CC=1`` disables
    the compiled backend (used to test the numpy fallback).
    """
    if os.environ.get("NHHAM_NO_CC"):
        return None
    return shutil.which(os.environ.get("CC", "cc"))


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
    except BudgetExceeded:  # an expiry is not an exotic installation
        raise
    except Exception:  # pragma: no cover - exotic installations
        return None


@dataclass(frozen=True)
class Compilation:
    """One translation unit to compile: the compiler's command and the cache key.

    Attributes
    ----------
    source : str
    compiler : str
    flags : tuple of str
        The optimisation level, the portable defaults, then ``$NHHAM_CFLAGS``, then the
        caller's (a later ``-O`` wins).
    key : str
        Hash of the source, compiler, flags, tag, platform and the cache format.
    extension : bool
        The library is also a CPython extension module (``pyext.c``).
    """

    source: str
    compiler: str
    flags: tuple
    key: str
    extension: bool = False

    @classmethod
    def of(cls, source: str, flags=(), tag: str = "", extension: bool = False,
           optimize: str = OPTIMIZE):
        """The compilation of ``source`` with the system compiler, at ``optimize``.

        Raises
        ------
        ComputationError
            When no compiler is available.
        """
        cc = c_compiler()
        if cc is None:
            why = "NHHAM_NO_CC is set" if os.environ.get("NHHAM_NO_CC") else \
                "set CC, or install one"
            raise ComputationError(f"no C compiler found ({why})")
        allflags = (optimize, *_FLAGS, *os.environ.get("NHHAM_CFLAGS", "").split(), *flags)
        parts = [source, cc, *allflags, tag, sys.platform, os.uname().machine, CACHE_FORMAT]
        key = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:20]
        return cls(source, cc, allflags, key, extension)

    def command(self, src: str, lib: str) -> list:
        return [self.compiler, *self.flags, "-o", lib, src, "-lm"]


def compile_c(source: str, cache_dir=None, flags=(), tag: str = "") -> str:
    """Compile ``source`` to a shared library in the compile cache; return its path.

    ``flags`` are added to the portable defaults (and to ``$NHHAM_CFLAGS``). A verified
    cached library is reused; a cached one that fails verification is rebuilt (with a
    :class:`~nhham.numerics.model.NumericsWarning` saying why).

    Raises
    ------
    ComputationError
        When no compiler is available or compilation fails (message included; a failure
        remembered in the cache is reported at once).
    """
    import warnings

    from nhham.numerics.model import NumericsWarning

    problems: list = []
    try:
        return build(CompileCache.open(cache_dir), Compilation.of(source, flags, tag),
                     problems)
    finally:
        for problem in problems:
            warnings.warn(problem, NumericsWarning, stacklevel=2)


def build(cache: CompileCache, job: Compilation, problems: list | None = None,
          on_start=None) -> str:
    """The verified library of ``job`` in ``cache``, compiled first if needed.

    ``problems`` collects why a cached file was refused; ``on_start(process)`` is called
    with the compiler's ``Popen`` (so that another thread may stop it).
    """
    library = cache.lookup(job.key, problems)
    if library is not None:
        return library
    failure = cache.failure(job.key)
    if failure is not None:
        raise ComputationError(failure)
    with cache.build_directory() as tmp:
        src, lib = os.path.join(tmp, "model.c"), os.path.join(tmp, "model.so")
        with open(src, "w", encoding="utf-8") as fh:
            fh.write(job.source)
        returncode, stderr = run_compiler(job.command(src, lib), tmp, on_start)
        if returncode == 0:
            return cache.install(lib, job.key)
        if returncode < 0:
            raise CompilerStopped(f"the C compiler was stopped by signal {-returncode}")
        message = f"C compilation failed: {_first_error(stderr)}"
        if "No space left on device" not in stderr:  # a full disk is no property of the source
            cache.remember_failure(job.key, message, stderr, tmp)
        raise ComputationError(message)


def _first_error(stderr: str) -> str:
    """The compiler's first error line (the whole message is kept in the failure marker)."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if "error" in line.lower()]
    return (errors or lines or ["no message"])[0][:500]


class CompilerStopped(ComputationError):
    """The compiler was killed by a signal (by a stop at exit, or from outside): nothing
    is known about the source, so nothing is remembered and no other build is tried."""


def run_compiler(command: list, cwd: str, on_start=None) -> tuple:
    """``(returncode, stderr)`` of the compiler run in a process group of its own; the
    group is killed when the caller is interrupted or the time limit passes."""
    process = subprocess.Popen(command, cwd=cwd, stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        if on_start is not None:
            on_start(process)
        _, stderr = process.communicate(timeout=_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        kill_group(process)
        raise ComputationError(f"the C compiler did not finish in {_TIMEOUT_S} s") from None
    except BaseException:
        kill_group(process)
        raise
    return process.returncode, stderr


def signal_group(process) -> None:
    """Kill the compiler's whole process group, not once the driver is reaped (its pid,
    the group's id, may belong to another process by then). Safe from a thread that does
    not own ``process``: the owner reaps it (see :func:`kill_group`)."""
    if process.returncode is None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)


def kill_group(process) -> None:
    """Kill the compiler's whole process group and reap the driver. Only the thread that
    runs the compiler may call it: a second ``communicate`` would close the pipe under
    the first, whose read then fails with EBADF instead of reporting the signal."""
    signal_group(process)
    try:
        process.communicate()
    except BudgetExceeded:  # the group is killed: the expiry goes on to the command
        raise
    except Exception:  # reaping is best effort
        pass


# -------------------------------------------------------- a model's library
@dataclass(frozen=True)
class LibraryBuild:
    """The outcome of building a model's library.

    Attributes
    ----------
    path : str or None
        The verified library, or None when none could be built.
    extension : bool
        It has the CPython entry points.
    note : str
        What was built, or why nothing was (the compiler's message).
    fallback : str or None
        Set when the CPython entry points could not be built and the plain library is
        used instead (why).
    problems : tuple of str
        Cached files refused on the way (see :meth:`CompileCache.lookup`).
    """

    path: str | None
    extension: bool
    note: str
    fallback: str | None = None
    problems: tuple = ()


def compilations(sources) -> list:
    """The libraries a model may use, best first: with the CPython entry points (when the
    headers are there and the source has them), then the plain one."""
    jobs = []
    ext = pyext_flags() if "PyInit_nhham_ext" in sources["c"] else None
    if ext is not None:
        jobs.append(Compilation.of(sources["c"], ext[0], tag=ext[1], extension=True))
    jobs.append(Compilation.of(sources["c"]))
    return jobs


def find_library(sources, cache: CompileCache, problems: list) -> LibraryBuild | None:
    """The model's library when it is in the cache and verified (the best one that may
    still be built: a plain library is used only after the extension failed), else None.

    Raises
    ------
    ComputationError
        When no compiler is available.
    """
    fallback = None
    for job in compilations(sources):
        library = cache.lookup(job.key, problems)
        if library is not None:
            return LibraryBuild(library, job.extension, _note(library, job.extension),
                                fallback)
        fallback = cache.failure(job.key)
        if fallback is None:
            return None
    return None


def build_library(sources, cache: CompileCache, on_start=None) -> LibraryBuild:
    """The model's library, from the cache or compiled: the CPython entry points when they
    can be built, else the plain library, else ``path=None`` and why."""
    problems: list = []
    fallback = None
    try:
        jobs = compilations(sources)
    except ComputationError as exc:
        return LibraryBuild(None, False, str(exc))
    for job in jobs:
        try:
            library = build(cache, job, problems, on_start)
        except (ComputationError, OSError) as exc:
            if job.extension and not isinstance(exc, CompilerStopped):
                fallback = str(exc)
                continue
            return LibraryBuild(None, False, str(exc), fallback, tuple(problems))
        return LibraryBuild(library, job.extension, _note(library, job.extension), fallback,
                            tuple(problems))
    raise AssertionError("the plain library is always the last compilation")


def load_library(built: LibraryBuild, layout) -> tuple:
    """``(CompiledRHS or None, note)`` of a built library, loaded; a
    :class:`~nhham.numerics.model.NumericsWarning` for every fallback (the plain library
    instead of the CPython entry points, numpy when nothing was built or it cannot be
    loaded: the note says why)."""
    import warnings

    from nhham.numerics.model import NumericsWarning

    if built.path is None:
        return None, built.note
    try:
        compiled = CompiledRHS.load(built.path, layout, extension=built.extension)
    except (OSError, ImportError) as exc:
        return None, f"the compiled library {built.path} could not be loaded: {exc}"
    note = built.note
    if built.fallback is not None:
        note += f"; CPython entry points unavailable ({built.fallback})"
        warnings.warn(f"the CPython entry points could not be built ({built.fallback}); "
                      f"the plain compiled library is used (single-state calls go through "
                      f"ctypes)", NumericsWarning, stacklevel=3)
    return compiled, note


def _note(path: str, extension: bool) -> str:
    what = "compiled C with CPython entry points" if extension else "compiled C"
    return f"{what} ({os.path.basename(path)})"


#: Complex-step kernels loaded in this process, by a digest of their source (None: they
#: could not be built here, and why is not asked again).
_COMPLEX: dict = {}
_COMPLEX_LOCK = threading.Lock()


def complex_kernels(model, build_now: bool = True) -> ComplexKernels | None:
    """The model's complex-step kernels, from the compile cache or (``build_now``)
    compiled now; None when the model has none (a function without a complex
    continuation), runs on numpy, no compiler is available, or they are not built and
    ``build_now`` is False: numpy then evaluates the complex step.

    Only the complex step needs them, so the model's own library does not carry them,
    and they are compiled at :data:`OPTIMIZE_COMPLEX`. A study, which evaluates thousands
    of states, and ``linearize_many`` over many states build them (once: the cache keeps
    them); one linearisation, a few evaluations, uses them when they are there and numpy
    otherwise.
    """
    source = model.c_complex_source
    if not source or (model.compiled is None and model.pending is None):
        return None
    key = hashlib.sha256(source.encode()).hexdigest()
    with _COMPLEX_LOCK:   # the threads of a study build it once
        if key in _COMPLEX:
            return _COMPLEX[key]
        problems: list = []
        try:
            cache = CompileCache.open(None)
            job = Compilation.of(source, tag="complex", optimize=OPTIMIZE_COMPLEX)
            path = build(cache, job, problems) if build_now else cache.lookup(job.key,
                                                                               problems)
            if path is None:   # not built yet: numpy now, perhaps compiled by a study
                return None
            _COMPLEX[key] = ComplexKernels.load(path, model.layout)
        except (ComputationError, OSError):
            _COMPLEX[key] = None
        finally:
            if problems:
                import warnings

                from nhham.numerics.model import NumericsWarning

                for problem in problems:
                    warnings.warn(problem, NumericsWarning, stacklevel=2)
        return _COMPLEX[key]
