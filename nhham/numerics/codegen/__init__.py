"""The one bridge from sympy to numbers: a System in, a :class:`NumericModel` out.

:func:`numeric_model` generates the model's kernels (:mod:`.emit`: sympy to Python, numpy,
mpmath and C text; with :mod:`.contacts`, the arrays of a contact force, the only places in
the numerics layer that import sympy), compiles and
loads the C (:mod:`.build`; the compile cache and how a cached library is verified before
it is loaded: :mod:`.cache`; builds in the background while numpy answers:
:mod:`.background`) and returns a :class:`~nhham.numerics.model.NumericModel` whose
methods take arrays of states and never touch sympy. The C runtime the generated kernels
are compiled with lives in ``nhham/numerics/c/`` (package data):

- the solve of the accelerations ``ksolve``, by the null-space method (Householder QR of
  (mu D)^T with row pivoting, the reduced matrix by LU); RATTLE's saddle solve
  ``ksolve_saddle``: Cholesky of W and of the Schur complement mu W^-1 mu^T (W is
  positive definite for mechanical Lagrangians), LU with partial pivoting of the scaled
  saddle matrix when W is indefinite or nearly singular (``linalg.c``);
- the right-hand side for one state and for a batch (``rhs.c``), the nonholonomic RATTLE
  loop, constant W or W(q) (``rattle.c``), and scipy's explicit Runge-Kutta methods (RK23,
  RK45, DOP853) as one loop with projection onto M_1 (``erk.c``, used by
  :func:`nhham.numerics.integrate.simulate`);
- when the Python and numpy headers are installed, CPython entry points for the
  single-state calls (``pyext.c``; no ctypes on the hot path).

Every fallback (numpy instead of C, the plain library instead of the CPython entry
points, a private cache instead of the configured one, a refused cached library) is
reported with a :class:`~nhham.numerics.model.NumericsWarning`; ``model.backend_note``
says what runs. Only ``NHHAM_NO_CC=1`` (or ``backend="numpy"``) asks for numpy silently.
"""

from __future__ import annotations

import math
import os
import warnings

from nhham.errors import ComputationError, MissingParameterValueError
from nhham.numerics.codegen.background import build_in_background, take_over
from nhham.numerics.codegen.build import (build_library, c_compiler, compile_c,
                                          find_library, load_library)
from nhham.numerics.codegen.cache import CompileCache, cache_location
from nhham.numerics.codegen.emit import (cached_sources, generate_sources, remember_sources,
                                         source_key, with_parameter_layout)
from nhham.numerics.kernels import GeneratedKernels
from nhham.numerics.model import NumericModel, NumericsWarning

__all__ = ["numeric_model", "generate_sources", "compile_c", "c_compiler", "cache_location",
           "system_and_state"]

_BACKENDS = ("numpy", "c", "auto")
_PATHS = ("saddle", "closed_form")


def numeric_model(system, *, backend: str = "auto", path: str = "saddle",
                  parameters=None, cache_dir=None, background: bool = False) -> NumericModel:
    """Generate the numeric model of ``system``.

    Parameters
    ----------
    system : nhham.System
    backend : {"auto", "numpy", "c"}, optional
        ``"numpy"``: generated Python/numpy only. ``"c"``: also compile the
        right-hand side with the system C compiler; if that is impossible a
        :class:`~nhham.numerics.model.NumericsWarning` is issued and numpy is used.
        ``"auto"`` (default): C when a compiler works, else numpy with that warning
        (none when ``NHHAM_NO_CC=1`` asks for numpy).
    path : {"saddle", "closed_form"}, optional
        ``"saddle"`` (default) solves the saddle-point system numerically at
        every evaluation. ``"closed_form"`` evaluates the symbolic closed form
        of P(xi_L) (costly to derive for large systems; meant for comparison).
    parameters : mapping of str to float, optional
        Values overriding ``system.parameter_values``; the values of inputs (NaN
        until given here or by ``NumericModel.with_parameters``).
    cache_dir : str, optional
        The compile cache (default ``$NHHAM_CACHE``, else ``$XDG_CACHE_HOME/nhham``,
        else ``~/.cache/nhham``; see :mod:`nhham.numerics.codegen.cache`).
    background : bool, optional
        With ``backend="auto"``: when the library is not in the cache yet, do not wait
        for the compiler; the model evaluates with numpy, ``model.pending`` is the build
        under way, and :meth:`NumericModel.with_library` gives the compiled model once it
        is done (what :func:`nhham.numerics.integrate.simulate` does for a System).

    Returns
    -------
    NumericModel

    Raises
    ------
    MissingParameterValueError
        When a parameter used by the system has no numeric value.
    ValueError
        For an unknown backend or path.

    Examples
    --------
    The sleigh at theta = 0 moving with u = x' = 1, w = theta' = 1 (so y' = a w = 0.5): by
    hand u' = a w**2 = 0.5 and w' = -m a u w / (I + m a**2) = -1, so x'' = u' - a w**2 = 0
    and y'' = u w + a w' = 0.5.

    >>> import numpy as np
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> model
    NumericModel('Chaplygin sleigh', n=3, m=1, k=0, backend='numpy', path='saddle')
    >>> y = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5, theta_dot=1.0))
    >>> print(np.round(model.rhs(0.0, y), 12) + 0.0)
    [ 1.   0.5  1.   0.   0.5 -1. ]
    """
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if path not in _PATHS:
        raise ValueError(f"path must be one of {_PATHS}, got {path!r}")
    system.require_regular_lagrangian("the numeric model (the accelerations)")
    values = _parameter_values(system, parameters)
    # the system's own parameters: sources are shared by systems that differ only in
    # parameters no expression reads
    sources = with_parameter_layout(_sources(system, path, cache_dir if backend != "numpy"
                                             else None), system)
    kernels = GeneratedKernels.from_source(sources["python"], sources["layout"])
    compiled, note, pending = None, "numpy backend requested", None
    if backend in ("c", "auto"):
        compiled, note, pending = _compiled(sources, cache_dir,
                                            background and backend == "auto")
        if compiled is None and pending is None and (
                backend == "c" or not os.environ.get("NHHAM_NO_CC")):
            warnings.warn(f"C backend unavailable ({note}); using numpy", NumericsWarning,
                          stacklevel=2)
    return NumericModel(
        layout=sources["layout"],
        kernels=kernels,
        parameter_values=tuple(values[p.name] for p in system.parameters),
        compiled=compiled,
        path=path,
        backend_note=note,
        python_source=sources["python"],
        c_source=sources["c"],
        c_complex_source=sources.get("c_complex", ""),
        pending=pending,
    )


def _sources(system, path, cache_dir) -> dict:
    """The system's generated sources: from this process's memory, else from the compile
    cache (verified), else generated (and kept there)."""
    key = source_key(system, path)
    held = cached_sources(key)
    try:
        cache = CompileCache.open(cache_dir)
    except OSError:
        return generate_sources(system, path=path)
    if held is not None:   # generated in this process: kept for the others too
        if not cache.has_sources(key):
            cache.keep_sources(key, held)
        return held
    kept = cache.sources(key)
    if kept is not None:
        return remember_sources(key, kept)
    sources = generate_sources(system, path=path)
    cache.keep_sources(key, sources)
    return sources


def _compiled(sources, cache_dir, background: bool) -> tuple:
    """``(CompiledRHS or None, note, BackgroundBuild or None)`` for a model's sources."""
    problems: list = []
    try:
        cache = CompileCache.open(cache_dir)
        if background:
            built = find_library(sources, cache, problems)
            if built is None:
                return (None, "numpy while the C library is compiled in the background",
                        build_in_background(sources, cache))
        else:
            take_over(sources)
            built = build_library(sources, cache)
            problems += built.problems
    except (ComputationError, OSError) as exc:
        return None, str(exc), None
    finally:
        for problem in problems:
            warnings.warn(problem, NumericsWarning, stacklevel=3)
    compiled, note = load_library(built, sources["layout"])
    return compiled, note, None


def _parameter_values(system, overrides) -> dict:
    """Numeric values for every declared parameter (overrides by name)."""
    overrides = dict(overrides or {})
    names = {p.name for p in system.parameters}
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise MissingParameterValueError(
            f"parameters: {', '.join(unknown)} are not parameters of the system "
            f"(known: {', '.join(sorted(names)) or 'none'})")
    values = {p.name: v for p, v in system.parameter_values.items()}
    # Inputs are NaN until set (a field evaluated with one unset fails, never uses a
    # made-up value); the time slot is set by the loops.
    values.update({u.name: math.nan for u in system.inputs})
    if system.time_slot is not None:
        values[system.parameters[system.time_slot].name] = 0.0
    values.update({k: float(v) for k, v in overrides.items()})
    missing = [p.name for p in system.parameters if p.name not in values]
    if missing:
        raise MissingParameterValueError(
            f"parameters: no numeric value for {', '.join(missing)} (needed for numbers)")
    return values


def system_and_state(obj, y0) -> tuple:
    """(System, state) for :func:`nhham.simulate` from a System or a
    ``sympy.physics.mechanics`` System and a state keyed by any of the user's names
    (dynamicsymbols, speeds, nhham's), the entries left out solved as a scene's
    ``[initial]`` ones (:mod:`nhham.system.state_keys`): the one bridge from sympy's
    names to the numbers. A full state in nhham's names is passed through unchanged."""
    from nhham.system.state_keys import as_system, completed_state

    system, speeds = as_system(obj)
    names = {s.name for s in (*system.coordinates, *system.velocities)}
    if all(isinstance(k, str) for k in y0) and set(y0) == names:
        return system, y0
    return system, completed_state(system, y0, speeds=speeds)[0]
