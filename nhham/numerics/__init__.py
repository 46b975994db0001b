"""Numbers: no sympy here, apart from ``codegen``, the one bridge in.

Modules: ``codegen`` (turns a System into a :class:`NumericModel`: generated
kernels in Python, numpy, mpmath and C), ``model`` (the numeric model behind
an array API), ``integrate`` (:func:`simulate`), ``integrators`` (fixed-step
RATTLE and RK4), ``reference`` (the mpmath reference integrator),
``diagnostics`` (residual, energy, conditioning along a trajectory),
``workprecision`` (the speed/accuracy study).
"""

from nhham.lazy import lazy_exports

_LAZY = {
    "numeric_model": "codegen",
    "NumericModel": "model",
    "simulate": "integrate",
    "SimulationResult": "integrate",
    "work_precision": "workprecision",
    "reference_solution": "reference",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
