"""The integration methods of :func:`~nhham.numerics.integrate.simulate`, as data.

One frozen :class:`Method` record per method in :data:`METHODS` (name -> record), as
:mod:`scipy.integrate` maps names to ``OdeSolver`` classes that carry an ``order``. A
record says what the method is (family, order, the stepper that runs it, the loops it
runs in) and what it takes (forces, time-dependent forces, a Lagrangian that is not
quadratic in the velocities, projection onto M_1: not when it keeps the constraints
itself). Every list of method names in the package, and every test of what a method can
do, reads this registry: ``simulate``'s checks and dispatch, the work-precision study,
the ensembles of a parameter study, the command line's ``--method`` choices and its
refusals, the plots' captions.

The families and the options each takes (:mod:`nhham.numerics.simulate_options`):

========== ============================================ ==================================
family     options                                      stepper
========== ============================================ ==================================
adaptive   rtol, atol, max_step, first_step             a :mod:`scipy.integrate` solver
                                                        (``scipy.integrate:NAME``), stepped
                                                        by ``scipy_loop`` or, for the
                                                        explicit Runge-Kutta ones, in C
                                                        (``compiled_loop``)
fixed-step step                                         a function ``f(model, y0, t0, t1,
                                                        h, *, recorder, progress, deadline
                                                        [, projection, baumgarte])``
                                                        returning a ``Run``
reference  reference_digits                             the mpmath extrapolation
========== ============================================ ==================================

Adding an integrator is one entry here plus its stepper: a fixed-step scheme is a
function beside :func:`nhham.numerics.integrators.rk4` (the signature above) and a
:class:`Method` with ``family="fixed-step"`` and ``stepper="module:function"``; an
adaptive scipy solver is an entry with ``stepper="scipy.integrate:CLASS"``. ``simulate``,
the command line (``--method`` and its checks), ``nhham bench`` and the tests of
``tests/numerics/test_methods.py`` (whose empirical order test measures ``order``) pick
it up from here.

This module imports nothing but the standard library and :mod:`nhham.errors`: the
command line reads it before numpy is imported.

Examples
--------
>>> from nhham.numerics.methods import METHODS, lookup, names
>>> METHODS["rattle"].keeps_constraints, METHODS["rattle"].takes_forces
(True, False)
>>> lookup("rk4").order
4
>>> names(lambda m: m.fixed_step)
('rattle', 'rattle4', 'discrete_gradient', 'hamiltonized', 'rk4')
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable

from nhham.errors import InputError

__all__ = ["Method", "METHODS", "DEFAULT_METHOD", "FAMILIES", "FAMILY_OPTIONS", "lookup",
           "names"]

#: The families, and the options (``simulate``'s keywords) each one takes.
FAMILIES = ("adaptive", "fixed-step", "reference")
FAMILY_OPTIONS = MappingProxyType({
    "adaptive": ("rtol", "atol", "max_step", "first_step"),
    "fixed-step": ("step",),
    "reference": ("reference_digits",),
})

#: The loops a method runs in: ``compiled`` (the whole integration in C), ``scipy``
#: (a scipy solver stepped in Python: dense output, events, Python controls), ``fixed``
#: (the fixed-step loop of ``integrators``), ``mpmath`` (the reference).
LOOPS = ("compiled", "scipy", "fixed", "mpmath")


@dataclass(frozen=True)
class Method:
    """One integration method: what it is and what it takes.

    Attributes
    ----------
    name : str
        The name ``simulate(method=...)`` and ``--method`` take.
    family : {"adaptive", "fixed-step", "reference"}
        Which options it takes (:data:`FAMILY_OPTIONS`).
    order : int
        Classical order (for a variable-order method the highest it uses: BDF 5,
        LSODA 12; 0 for the reference, whose extrapolation adapts its order).
    stepper : str
        ``"module:attribute"`` of what advances the state: a scipy ``OdeSolver``
        class, a fixed-step function, the reference solver (:meth:`load`).
    loops : tuple of str
        The loops it can run in (:data:`LOOPS`), the preferred first.
    summary : str
        One line for documentation and help.
    keeps_constraints : bool
        The scheme itself keeps phi = 0 at its points: projection and Baumgarte
        stabilisation do not apply.
    takes_forces : bool
        Applied and dissipative forces are allowed (else ``forces_refused`` says why).
    takes_time : bool
        t may enter L, the constraints and the forces (the stages set the time; rattle's
        scheme is built for an autonomous constrained field and refuses it).
    needs_quadratic : bool
        L must be 1/2 v^T W(q) v - V(q) (with ``takes_gyroscopic``, 1/2 v^T W(q) v +
        b(q) . v - V(q)).
    takes_gyroscopic : bool
        Terms linear in v (a magnetic or Coriolis term b(q) . v) are allowed beside
        ``needs_quadratic``.
    stiff : bool
        Meant for stiff problems (advised when an explicit method gives up).
    batched_jacobian : bool
        Its finite-difference Jacobian comes from one batched evaluation
        (``vectorized`` for scipy).
    carries_work : bool
        The loop integrates the work of the forces along with the state.
    background_build : bool
        Its loop evaluates the field, so a compiled library built in the background
        while it runs can take over (``simulate`` starts again on it).
    forces_refused : str
        Why it takes no forces (completes "METHOD is ...").
    nonlinear_refused : str
        Why it takes no constraint nonlinear in the velocities (Chetaev's rule), or ""
        when it takes them.
    quick_bench : bool
        One of the adaptive methods of the quick work-precision study
        (``nhham bench --quick``: one explicit, one implicit, one switching).
    needs_reduction : bool
        It integrates a scene's Hamiltonized reduction (``reduced``: made by the
        journey from the scene, :mod:`nhham.journeys.hamiltonized_motion`).
    auto_for : tuple of str
        The rules of ``method="auto"``'s decision table
        (:data:`nhham.numerics.method_choice.RULES`) that choose it.
    """

    name: str
    family: str
    order: int
    stepper: str
    loops: tuple[str, ...]
    summary: str
    keeps_constraints: bool = False
    takes_forces: bool = True
    takes_time: bool = True
    needs_quadratic: bool = False
    takes_gyroscopic: bool = False
    stiff: bool = False
    batched_jacobian: bool = False
    carries_work: bool = True
    background_build: bool = True
    forces_refused: str = ""
    quick_bench: bool = False
    nonlinear_refused: str = ""
    needs_reduction: bool = False
    auto_for: tuple[str, ...] = ()

    def __post_init__(self):
        # The registry is data that other modules trust: an entry that contradicts
        # itself is a programming error, found when this module is imported.
        assert self.family in FAMILIES, self.family
        assert self.loops and set(self.loops) <= set(LOOPS), self.loops
        assert self.takes_forces or self.forces_refused, self.name
        assert ":" in self.stepper, self.stepper

    @property
    def options(self) -> tuple[str, ...]:
        """The family's own options (``simulate``'s keywords)."""
        return FAMILY_OPTIONS[self.family]

    @property
    def adaptive(self) -> bool:
        return self.family == "adaptive"

    @property
    def fixed_step(self) -> bool:
        return self.family == "fixed-step"

    @property
    def reference(self) -> bool:
        return self.family == "reference"

    @property
    def takes_projection(self) -> bool:
        """Projection onto M_1 and Baumgarte stabilisation apply."""
        return not self.keeps_constraints

    @property
    def takes_nonlinear(self) -> bool:
        """Constraints nonlinear in the velocities (Chetaev's rule) are allowed."""
        return not self.nonlinear_refused

    @property
    def takes_t_eval(self) -> bool:
        """Output at given times (a fixed-step method keeps its grid points)."""
        return not self.fixed_step

    @property
    def scipy_loop(self) -> bool:
        """Runs in scipy's loop: ``dense_output``, ``events`` and Python controls."""
        return "scipy" in self.loops

    @property
    def compiled_loop(self) -> bool:
        return "compiled" in self.loops

    @property
    def scipy_name(self) -> str | None:
        """The :mod:`scipy.integrate` class it runs, or None."""
        module, _, attribute = self.stepper.partition(":")
        return attribute if module == "scipy.integrate" else None

    def load(self) -> Any:
        """The stepper itself (imports its module: scipy for the adaptive methods)."""
        module, _, attribute = self.stepper.partition(":")
        return getattr(importlib.import_module(module), attribute)


_CONSERVATIVE = "a structure-preserving scheme for conservative systems"
# t in L or a constraint, and Chetaev's constraints, take the Python stepper's extended
# step (symmetric, second order: nhham.numerics.integrators); forces that do work do not.
_RATTLE: dict[str, Any] = dict(family="fixed-step", loops=("fixed",), keeps_constraints=True,
               takes_forces=False, needs_quadratic=True, carries_work=False,
               background_build=False, forces_refused=_CONSERVATIVE)
_SCIPY: dict[str, Any] = dict(family="adaptive", loops=("scipy",))
_ERK: dict[str, Any] = dict(family="adaptive", loops=("compiled", "scipy"))

#: Every method, in the order the command line lists them (the default first).
METHODS = MappingProxyType({m.name: m for m in (
    Method("DOP853", order=8, stepper="scipy.integrate:DOP853",
           summary="explicit Runge-Kutta 8(5,3) (Dormand-Prince)", quick_bench=True,
           auto_for=("not mechanical", "short horizon", "tolerances given"), **_ERK),
    Method("RK45", order=5, stepper="scipy.integrate:RK45",
           summary="explicit Runge-Kutta 5(4) (Dormand-Prince)", **_ERK),
    Method("RK23", order=3, stepper="scipy.integrate:RK23",
           summary="explicit Runge-Kutta 3(2) (Bogacki-Shampine)", **_ERK),
    Method("Radau", order=5, stepper="scipy.integrate:Radau", stiff=True,
           batched_jacobian=True, quick_bench=True, summary="implicit Radau IIA of order 5",
           auto_for=("stiff",), **_SCIPY),
    Method("BDF", order=5, stepper="scipy.integrate:BDF", stiff=True, batched_jacobian=True,
           summary="implicit backward differentiation formulas, orders 1 to 5", **_SCIPY),
    Method("LSODA", order=12, stepper="scipy.integrate:LSODA", stiff=True, quick_bench=True,
           summary="Adams/BDF with automatic stiffness detection", **_SCIPY),
    Method("rattle", order=2, stepper="nhham.numerics.integrators:rattle",
           summary="nonholonomic RATTLE (Lobatto IIIA-IIIB with multipliers)",
           auto_for=("reversible",), **_RATTLE),
    Method("rattle4", order=4, stepper="nhham.numerics.integrators:rattle4",
           summary="RATTLE composed by the triple jump", **_RATTLE),
    Method("discrete_gradient", family="fixed-step", order=2,
           stepper="nhham.numerics.discrete_gradient:energy_exact", loops=("fixed",),
           keeps_constraints=True, needs_quadratic=True, takes_gyroscopic=True,
           takes_forces=False, takes_time=False, background_build=False,
           forces_refused="energy-exact for systems without applied forces, whose "
                          "balance would need the applied force apart from the field",
           nonlinear_refused="its reaction is built for constraints affine in v",
           summary="energy-exact discrete gradient (Gonzalez), constraints kept at each step",
           auto_for=("mechanical",)),
    Method("hamiltonized", family="fixed-step", order=2,
           stepper="nhham.numerics.hamiltonized:hamiltonized", loops=("fixed",),
           keeps_constraints=True, needs_quadratic=True, takes_forces=False,
           takes_time=False, carries_work=False, background_build=False,
           needs_reduction=True, auto_for=("hamiltonizable",),
           forces_refused="the integrator of a Hamiltonized reduction, which has no forces",
           nonlinear_refused="a Chaplygin reduction has constraints linear in v",
           summary="implicit midpoint in Chaplygin's time on a Hamiltonizable reduction, "
                   "t and the group coordinates reconstructed"),
    Method("rk4", family="fixed-step", order=4, stepper="nhham.numerics.integrators:rk4",
           loops=("fixed",), summary="classical Runge-Kutta 4", auto_for=("fixed step given",)),
    Method("reference", family="reference", order=0,
           stepper="nhham.numerics.reference:reference_solution", loops=("mpmath",),
           keeps_constraints=True,
           summary="Gragg-Bulirsch-Stoer extrapolation in mpmath (for measuring errors)"),
)})

#: The method of ``simulate`` and ``nhham simulate`` when none is given.
DEFAULT_METHOD = "DOP853"


def lookup(name, key: str = "method") -> Method:
    """The :class:`Method` called ``name`` (a Method is returned as it is).

    Raises
    ------
    InputError
        For an unknown name, naming ``key`` and the choices.

    Examples
    --------
    >>> lookup("DOP853").family
    'adaptive'
    >>> lookup("Euler")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.InputError: method: unknown method 'Euler'; choose one of DOP853, RK45, ...
    """
    if isinstance(name, Method):
        return name
    try:
        return METHODS[name]
    except (KeyError, TypeError):
        raise InputError(f"{key}: unknown method {name!r}; choose one of "
                         f"{', '.join(METHODS)}", key=key) from None


def names(where: Callable[[Method], bool] | None = None, *,
          cheapest_first: bool = False) -> tuple[str, ...]:
    """The names of the methods for which ``where`` holds (all by default), in the
    registry's order or, with ``cheapest_first``, the non-stiff ones from low to high
    order, then the stiff ones.

    Examples
    --------
    >>> names(lambda m: m.compiled_loop, cheapest_first=True)
    ('RK23', 'RK45', 'DOP853')
    >>> names(lambda m: m.adaptive, cheapest_first=True)
    ('RK23', 'RK45', 'DOP853', 'Radau', 'BDF', 'LSODA')
    """
    chosen = [m for m in METHODS.values() if where is None or where(m)]
    if cheapest_first:
        chosen.sort(key=lambda m: (m.stiff, 0 if m.stiff else m.order))
    return tuple(m.name for m in chosen)
