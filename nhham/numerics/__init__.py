"""Numbers: no sympy here, apart from ``codegen``, the one bridge in.

``codegen/`` (a System in, a :class:`NumericModel` out: ``emit`` prints the kernels as
Python, numpy, mpmath and C, ``build`` compiles and caches the C), ``c/`` (the C runtime
the kernels are compiled with, package data), ``kernels`` (the generated code behind
Python calls), ``saddle`` (the saddle-point solve in numpy), ``model`` (the numeric model
behind an array API), ``status`` (the one status vocabulary and failure exception),
``run`` (the raw output of an integration loop), ``scipy_loop`` and ``compiled_loop``
(scipy's solvers stepped here; the explicit Runge-Kutta methods as one compiled loop),
``integrators`` (fixed-step RATTLE and RK4), ``reference`` (the mpmath reference
integrator), ``diagnostics`` (residual, energy, conditioning along a trajectory),
``integrate`` (:func:`simulate`), ``workprecision`` (the speed/accuracy study).

A new integrator goes beside ``integrators`` (fixed step) or ``scipy_loop`` (adaptive),
returns a :class:`~nhham.numerics.run.Run` and is dispatched by ``integrate.simulate``.
"""

from nhham.lazy import by_module, lazy_exports

_LAZY = by_module({
    "codegen": ("numeric_model",),
    "model": ("NumericModel",),
    "integrate": ("simulate", "SimulationResult"),
    "workprecision": ("work_precision",),
    "reference": ("reference_solution",),
    "status": ("Status", "NumericalFailure"),
})
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
