"""Numbers: no sympy here, apart from ``codegen``, the one bridge in.

``codegen/`` (a System in, a :class:`NumericModel` out: ``emit`` prints the kernels as
Python, numpy, mpmath and C, ``build`` compiles and caches the C), ``c/`` (the C runtime
the kernels are compiled with, package data), ``kernels`` (the generated code behind
Python calls), ``saddle`` (the saddle-point solve in numpy), ``model`` (the numeric model
behind an array API), ``status`` (the one status vocabulary and failure exception),
``run`` (the raw output of an integration loop), ``scipy_loop`` and ``compiled_loop``
(scipy's solvers stepped here; the explicit Runge-Kutta methods as one compiled loop),
``methods`` (the integration methods as data), ``simulate_options`` (``simulate``'s
options), ``integrators`` (fixed-step RATTLE and RK4), ``reference`` (the mpmath reference
integrator), ``diagnostics`` (residual, energy, conditioning along a trajectory),
``integrate`` (:func:`simulate`), ``workprecision`` (the speed/accuracy study).

The integration methods are records of ``methods`` (``METHODS``), their options those of
``simulate_options``. A new integrator is one record there plus its stepper (a function
beside ``integrators.rk4`` for a fixed-step scheme, returning a
:class:`~nhham.numerics.run.Run`); ``integrate.simulate`` dispatches by the record.
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
