"""The one bridge from sympy to numbers: a System in, a :class:`NumericModel` out.

:func:`numeric_model` generates the model's kernels (:mod:`.emit`: sympy to Python, numpy,
mpmath and C text, the only place in the numerics layer that imports sympy), compiles and
loads the C (:mod:`.build`: the cache of shared libraries) and returns a
:class:`~nhham.numerics.model.NumericModel` whose methods take arrays of states and never
touch sympy. The C runtime the generated kernels are compiled with lives in
``nhham/numerics/c/`` (package data):

- the saddle solve ``ksolve``: Cholesky of W and of the Schur complement mu W^-1 mu^T
  (W is positive definite for mechanical Lagrangians), LU with partial pivoting of the
  scaled saddle matrix when W is indefinite or nearly singular (``linalg.c``);
- the right-hand side for one state and for a batch (``rhs.c``), the nonholonomic RATTLE
  loop for constant W (``rattle.c``), and scipy's explicit Runge-Kutta methods (RK23,
  RK45, DOP853) as one loop with projection onto M_1 (``erk.c``, used by
  :func:`nhham.numerics.integrate.simulate`);
- when the Python and numpy headers are installed, CPython entry points for the
  single-state calls (``pyext.c``; no ctypes on the hot path).

When no compiler works the model falls back to numpy and says why (``model.backend_note``).
"""

from __future__ import annotations

import warnings

from nhham.errors import MissingParameterValueError
from nhham.numerics.codegen.build import c_compiler, compile_c, build_compiled
from nhham.numerics.codegen.emit import generate_sources
from nhham.numerics.kernels import GeneratedKernels
from nhham.numerics.model import NumericModel, NumericsWarning

__all__ = ["numeric_model", "generate_sources", "compile_c", "c_compiler"]

_BACKENDS = ("numpy", "c", "auto")
_PATHS = ("saddle", "closed_form")


def numeric_model(system, *, backend: str = "auto", path: str = "saddle",
                  parameters=None, cache_dir=None) -> NumericModel:
    """Generate the numeric model of ``system``.

    Parameters
    ----------
    system : nhham.System
    backend : {"auto", "numpy", "c"}, optional
        ``"numpy"``: generated Python/numpy only. ``"c"``: also compile the
        right-hand side with the system C compiler; if that is impossible a
        :class:`~nhham.numerics.model.NumericsWarning` is issued and numpy is used.
        ``"auto"`` (default): C when a compiler works, numpy otherwise
        (silently; ``model.backend_note`` says why).
    path : {"saddle", "closed_form"}, optional
        ``"saddle"`` (default) solves the saddle-point system numerically at
        every evaluation. ``"closed_form"`` evaluates the symbolic closed form
        of P(xi_L) (costly to derive for large systems; meant for comparison).
    parameters : mapping of str to float, optional
        Values overriding ``system.parameter_values``.
    cache_dir : str, optional
        Where compiled libraries are kept (default ``$NHHAM_CACHE`` or
        ``~/.cache/nhham``).

    Returns
    -------
    NumericModel

    Raises
    ------
    MissingParameterValueError
        When a parameter used by the system has no numeric value.
    ValueError
        For an unknown backend or path.
    """
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if path not in _PATHS:
        raise ValueError(f"path must be one of {_PATHS}, got {path!r}")
    values = _parameter_values(system, parameters)
    sources = generate_sources(system, path=path)
    kernels = GeneratedKernels.from_source(sources["python"], sources["layout"])
    compiled, note = None, "numpy backend requested"
    if backend in ("c", "auto"):
        compiled, note = build_compiled(sources, cache_dir)
        if compiled is None and backend == "c":
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
    )



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
    values.update({k: float(v) for k, v in overrides.items()})
    missing = [p.name for p in system.parameters if p.name not in values]
    if missing:
        raise MissingParameterValueError(
            f"parameters: no numeric value for {', '.join(missing)} (needed for numbers)")
    return values

