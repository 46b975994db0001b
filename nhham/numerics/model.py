"""The numeric model: generated kernels behind a small array API (no sympy).

A :class:`NumericModel` is made by :func:`nhham.numerics.codegen.numeric_model`. It
evaluates, on one state ``y`` of shape (2n,) or on a batch of shape (k, 2n)
(rows are states ``[q^1..q^n, v^1..v^n]``, no Python loop over states):

- the constrained vector field ``y' = f(t, y) = (v, a)`` where ``(a, lambda)``
  solve the saddle-point system (``DESIGN.md`` §2, sign as in
  :class:`nhham.lagrangian.DynamicsIngredients`)::

      [ W   mu^T ] [ a      ]   [ F      ]
      [ mu  0    ] [ lambda ] = [ -drift ]

  i.e. d/dt(dL/dv) - dL/dq = -lambda^i mu_i;
- the multipliers lambda, the constraint residuals (phi_i = mu_i v + h_i, then
  the holonomic g_a), the energy E_L, cond(C) with C = -mu W^{-1} mu^T, cond(W);
- the power P = -lambda . (mu v) of the constraint forces, plus Q . v of the applied
  forces and the dissipation when the system has any (``forced``). Along any solution
  dE_L/dt = P exactly; on M_1 (mu v = -h) the constraints' part is lambda . h, the
  energy balance for affine constraints (zero for linear ones). With the opposite
  sign convention for lambda it reads dE/dt = -lambda . h.

Inputs u and the time t of the forces are parameter slots (``input_names``,
``time_slot``): an input is NaN until set (``with_parameters``), the time is set by
:meth:`rhs` and the integration loops.

The small linear systems are solved at run time; nothing is inverted
symbolically. The constrained accelerations and the projections onto the constraints
by the null-space method (:mod:`nhham.numerics.nullspace`; in C ``ksolve`` in
``nhham/numerics/c/linalg.c``), free of the coordinates' units.

Failures are statuses of :class:`~nhham.numerics.status.Status` (``evaluate``) or a
:class:`~nhham.numerics.status.NumericalFailure` carrying one (``rhs``, ``project``).
This module must not import sympy (``DESIGN.md`` §4).
"""

from __future__ import annotations

import math
import warnings
from typing import Any
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

from nhham.errors import InconsistentInitialDataError, InputError
from nhham.numerics.chetaev import padded, velocities_newton
from nhham.numerics.kernels import (CompiledRHS, GeneratedKernels, ParameterBlock,
                                    baumgarte_terms, columns, read_parameters)
from nhham.numerics.nullspace import solve_null_space
from nhham.numerics.saddle import SingleStateSolver, cond_each, condition
from nhham.numerics.status import NumericalFailure, Status

__all__ = ["NumericModel", "NumericsWarning", "LibraryReady", "ProjectionOutcome",
           "ParameterBlock", "COND_C_WARN"]

#: cond(C) above which results are flagged (errors grow like cond(C) * eps).
COND_C_WARN = 1e10


class NumericsWarning(UserWarning):
    """A numeric result may be unreliable (conditioning, residuals, fallbacks)."""


class LibraryReady(Exception):
    """The compiled library of a model that evaluates with numpy meanwhile is built.

    Raised by the field of :meth:`NumericModel.field_function` on a model with a
    ``pending`` build, at the first evaluation after the build succeeded, so that the
    caller can run again on :meth:`NumericModel.with_library` (not an error: deliberately
    not a :class:`~nhham.errors.NhhamError`, so no loop mistakes it for a failed step).
    """


# --------------------------------------------------------------- results
@dataclass(frozen=True)
class ProjectionOutcome:
    """A state projected onto M_1 = {g = 0, phi = 0}.

    Attributes
    ----------
    y : ndarray, shape (2n,)
        The projected state.
    residual_before, residual_after : float
        Largest |phi_i| or |g_a| before and after.
    displacement_q, displacement_v : float
        Euclidean size of the changes of q and v.
    newton_iterations : int
        Newton iterations for the position constraints (0 without any).
    """

    y: np.ndarray
    residual_before: float
    residual_after: float
    displacement_q: float
    displacement_v: float
    newton_iterations: int


# ------------------------------------------------------------------ model
@dataclass(frozen=True, eq=False)
class NumericModel:
    """Numeric evaluation of a constrained system (see the module docstring).

    Attributes
    ----------
    n, m, k : int
        Coordinates, affine constraints phi (complete lifts first), holonomic
        constraints g.
    names : tuple of str
        State names: coordinates then velocities (``x``, ..., ``x_dot``, ...).
    parameter_names : tuple of str
    parameter_values : tuple of float
    backend : {"c", "numpy"}
        What evaluates :meth:`rhs`; ``backend_note`` says why.
    pending : object or None
        The build of the compiled library under way while numpy evaluates the model
        (``numeric_model(..., background=True)``; a
        :class:`nhham.numerics.codegen.background.BackgroundBuild`), else None.
    path : {"saddle", "closed_form"}
    constant_W : bool
        W does not depend on q.
    quadratic : bool
        L = 1/2 v^T W(q) v - V(q) (what the RATTLE-type integrator needs).
    linear_constraints : bool
        Every h_i is zero (energy is conserved).

    Examples
    --------
    >>> import numpy as np
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> model.parameters
    {'m': 1.0, 'I': 0.25, 'a': 0.5}
    >>> y = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5, theta_dot=1.0))
    >>> print(np.round(model.multipliers(y), 12))    # I theta'' = a lambda, theta'' = -1
    [-0.5]
    """

    layout: MappingProxyType
    kernels: GeneratedKernels
    parameter_values: tuple
    compiled: CompiledRHS | None = None
    path: str = "saddle"
    backend_note: str = ""
    python_source: str = field(default="", repr=False)
    c_source: str = field(default="", repr=False)
    c_complex_source: str = field(default="", repr=False)
    pending: Any = field(default=None, repr=False)
    # Set once by __post_init__, never changed (the model stays immutable).
    _p: np.ndarray = field(init=False, repr=False)
    _plist: list = field(init=False, repr=False)
    _block0: "ParameterBlock" = field(init=False, repr=False)
    _ext: Any = field(init=False, repr=False)
    _one: "SingleStateSolver" = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "layout", MappingProxyType(dict(self.layout)))
        p = np.array(self.parameter_values, dtype=float)
        object.__setattr__(self, "_p", p if p.size else np.zeros(1))
        object.__setattr__(self, "_plist", [float(x) for x in self.parameter_values])
        used = read_parameters(self.layout)   # the compiled code reads these, in order
        object.__setattr__(self, "_block0", ParameterBlock.of(
            self._plist if used is None else [self._plist[i] for i in used]))
        ext = None
        if self.compiled is not None and self.path == "saddle":
            ext = self.compiled.ext
        object.__setattr__(self, "_ext", ext)
        object.__setattr__(self, "_one", SingleStateSolver(self.layout))
        if self.path == "closed_form" and "closed" not in self.kernels.functions:
            raise ValueError("closed_form path requested but no closed-form kernel generated")

    def __repr__(self):
        name = f"{self.name!r}, " if self.name else ""
        return (f"NumericModel({name}n={self.n}, m={self.m}, k={self.k}, "
                f"backend={self.backend!r}, path={self.path!r})")

    # ---------------------------------------------------------- metadata
    n = property(lambda self: self.layout["n"])
    m = property(lambda self: self.layout["m"])
    k = property(lambda self: self.layout["k"])
    name = property(lambda self: self.layout["name"])
    constant_W = property(lambda self: self.layout["constant_W"])
    quadratic = property(lambda self: self.layout["quadratic"])
    linear_constraints = property(lambda self: self.layout["linear_constraints"])
    coordinate_names = property(lambda self: self.layout["coordinate_names"])
    velocity_names = property(lambda self: self.layout["velocity_names"])
    parameter_names = property(lambda self: self.layout["parameter_names"])
    forced = property(lambda self: self.layout.get("forced", False))
    input_names = property(lambda self: self.layout.get("input_names", ()))
    time_slot = property(lambda self: self.layout.get("time_slot"))
    #: t in L or a constraint (not only in the forces): E_L, the residuals and the
    #: conditions of a state depend on its time.
    time_in_geometry = property(lambda self: bool(self.layout.get("time_in_geometry")))
    #: The first scene key whose expression uses t (``lagrangian``, ``constraints[0]``),
    #: or "" (t in the forces only, or not at all).
    timed_key = property(lambda self: self.layout.get("time_in_geometry") or "")
    #: A constraint not affine in v (Chetaev's rule): velocities onto M_1 by Newton.
    nonlinear = property(lambda self: self.layout.get("nonlinear_constraints", False))
    #: The geometry kernel reads (q, v): a nonlinear constraint's mu and h, or the W of a
    #: Lagrangian not quadratic in v.
    geometry_reads_v = property(lambda self: self.layout.get(
        "geometry_reads_v", self.nonlinear))

    @property
    def energy_change(self) -> str:
        """Why E_L is not conserved, or "" where it is (else the energy balance residual
        max |E(t) - E(0) - int P dt| measures a method's error, DESIGN.md §2).

        >>> from nhham import models, numeric_model
        >>> numeric_model(models.chaplygin_sleigh(), backend="numpy").energy_change
        ''
        """
        if self.forced:
            return "the forces do work"
        if self.time_in_geometry:
            return f"{self.timed_key} depends on t"
        if self.nonlinear or not self.linear_constraints:
            return ("the reaction of a nonlinear (Chetaev) constraint may do work" if
                    self.nonlinear else "the reactions of the affine constraints do work")
        return ""

    @property
    def names(self) -> tuple:
        return self.coordinate_names + self.velocity_names

    @property
    def residual_names(self) -> tuple:
        """Labels of :meth:`residuals`: the phi_i, then the holonomic g_a."""
        return tuple(self.layout["constraint_labels"]) + tuple(
            f"{lab} (position)" for lab in self.layout["holonomic_labels"])

    @property
    def backend(self) -> str:
        if self.compiled is None:
            return "numpy"
        if self.path == "closed_form" and not self.compiled.has_closed():
            return "numpy"
        return "c"

    @property
    def parameters(self) -> dict:
        return dict(zip(self.parameter_names, self.parameter_values))

    def with_parameters(self, **values) -> "NumericModel":
        """The same model with some parameter values changed (no regeneration)."""
        unknown = sorted(set(values) - set(self.parameter_names))
        if unknown:
            raise KeyError(f"not parameters of the model: {', '.join(unknown)}")
        new = [float(values.get(name, v)) for name, v in self.parameters.items()]
        return replace(self, parameter_values=tuple(new))

    def state(self, values) -> np.ndarray:
        """A state vector from ``{name: value}`` (every coordinate and velocity)
        or from a sequence of length 2n."""
        if isinstance(values, dict) or hasattr(values, "keys"):
            missing = [s for s in self.names if s not in values]
            extra = sorted(set(values) - set(self.names))
            if missing or extra:
                parts = []
                if missing:
                    parts.append("missing " + ", ".join(missing))
                if extra:
                    parts.append("unknown " + ", ".join(extra))
                raise InconsistentInitialDataError(
                    f"initial data: {'; '.join(parts)} (state names: {', '.join(self.names)})")
            return np.array([float(values[s]) for s in self.names])
        y = np.array(values, dtype=float)
        if y.shape != (2 * self.n,):
            raise InconsistentInitialDataError(
                f"initial data: expected {2 * self.n} values ({', '.join(self.names)}), "
                f"got shape {y.shape}")
        return y

    # -------------------------------------------------------------- core
    def _check(self, y):
        y = np.asarray(y, dtype=float)
        if y.shape[-1] != 2 * self.n or y.ndim not in (1, 2):
            raise ValueError(f"states must have shape (2n,) or (k, 2n) with 2n = {2 * self.n}, "
                             f"got {y.shape}")
        return y

    def evaluate(self, y, baumgarte=None, *, field_only: bool = False):
        """Field, multipliers and constraint power at one state or a batch.

        Parameters
        ----------
        y : array_like, shape (2n,) or (k, 2n)
        baumgarte : (alpha, beta) or None
            Replace the constraint-acceleration condition d(phi)/dt = 0 by
            d(phi)/dt = -2 alpha phi - beta^2 g (g only for the complete-lift
            rows): Baumgarte stabilisation.
        field_only : bool
            Only ``dy`` is wanted: the closed-form path may then return zeros for the
            power of a batch (it needs mu from another kernel).

        Returns
        -------
        dy : ndarray, shape like y
        lam : ndarray, shape (m,) or (k, m)
        power : float or ndarray (k,)
            -lambda . (mu v), the exact dE_L/dt of this field.
        status : Status
            ``Status.SUCCESS`` (0), or ``SINGULAR``/``NONFINITE`` when a linear system was
            singular or the result is not finite (the values are then not to be used).
        """
        a2, b2 = baumgarte_terms(baumgarte)
        if self._ext is not None:
            block = self._block0 if baumgarte is None else self._block0.with_terms(a2, b2)
            out = self._ext.evaluate(y, block.address)
            if out is not None:  # None: not one contiguous float state (handled below)
                n2 = 2 * self.n
                if type(out) is int:
                    return (np.full(n2, np.nan), np.full(self.m, np.nan), math.nan, Status(out))
                return out[:n2], out[n2:n2 + self.m], float(out[-1]), Status.SUCCESS
        if type(y) is not np.ndarray or y.dtype != np.float64:
            y = np.asarray(y, dtype=float)
        if y.shape[-1] != 2 * self.n or y.ndim not in (1, 2):
            self._check(y)
        if self.path == "closed_form":
            if baumgarte is not None:
                raise ValueError("Baumgarte stabilisation needs the saddle path")
            return self._evaluate_closed(y, field_only)
        if self.compiled is not None:
            return self._evaluate_compiled(y, a2, b2)
        if y.ndim == 1:
            out = self.kernels.scalar_list("saddle", y.tolist(), self._plist)
            dy, lam, power, status = self._one(out, y, a2, b2)
            return dy, lam, power, Status(status)
        return self._evaluate_numpy(y, a2, b2)

    def _evaluate_compiled(self, y, a2, b2):
        block = self._block0 if (a2, b2) == (0.0, 0.0) else self._block0.with_terms(a2, b2)
        n2 = 2 * self.n
        if y.ndim == 1:
            out, status = self.compiled.one(y, block.pointer)
            return out[:n2].copy(), out[n2:n2 + self.m].copy(), float(out[-1]), Status(status)
        OUT, bad = self.compiled.batch(y, block.pointer)
        return (OUT[:, :n2], OUT[:, n2:n2 + self.m], OUT[:, -1],
                Status.NONFINITE if bad else Status.SUCCESS)

    def with_library(self) -> "NumericModel":
        """The same model on the compiled library of its ``pending`` build, once that
        build is over (numpy still, with a warning saying why, when it failed)."""
        compiled, note = self.pending.load(self.layout)
        return replace(self, compiled=compiled, backend_note=note, pending=None)

    def parameter_block(self, baumgarte=None) -> ParameterBlock:
        """The parameters (and Baumgarte terms) as the compiled code reads them."""
        if baumgarte is None:
            return self._block0
        return self._block0.with_terms(*baumgarte_terms(baumgarte))

    def field_function(self, baumgarte=None):
        """f(z) -> [dy, power] (2n + 1) at one state z of length 2n or 2n + 1
        (the last entry, e.g. the work of the constraint forces, is ignored), or
        the failure status (an int: a Status or the C code). Through the CPython
        entry point when there is one (what the scipy solvers call at every
        stage), else through :meth:`evaluate`."""
        n2 = 2 * self.n

        def f_slow(z):
            dy, _, P, status = self.evaluate(np.asarray(z, dtype=float)[:n2], baumgarte)
            if status:
                return status  # a Status (an int): callers test isinstance(out, int)
            out = np.empty(n2 + 1)
            out[:n2] = dy
            out[n2] = P
            return out

        if self._ext is None:
            return f_slow if self.pending is None else _until_built(f_slow, self.pending)
        field, block = self._ext.field, self.parameter_block(baumgarte)
        addr = block.address  # the closure keeps ``block`` (and so its array) alive

        def f(z, _block=block):
            out = field(z, addr)
            return f_slow(z) if out is None else out

        return f

    def at_time(self, t: float) -> "NumericModel":
        """The model with its time slot at t (itself when the forces do not depend on t)."""
        slot = self.time_slot
        if slot is None:
            return self
        values = list(self.parameter_values)
        values[slot] = float(t)
        return replace(self, parameter_values=tuple(values))

    def unset_inputs(self) -> tuple:
        """Names of the inputs without a value (NaN)."""
        return tuple(u for u in self.input_names if math.isnan(self.parameters[u]))

    def require_inputs(self) -> None:
        """Raise InputError naming the inputs without a value (an integration never runs
        on a made-up value)."""
        unset = self.unset_inputs()
        if unset:
            raise InputError(f"inputs: no value for {', '.join(unset)} (give a control law, "
                             f"[control] in a scene or System.closed_loop, or a value with "
                             f"parameters=...)", key="inputs")

    def rhs(self, t, y, baumgarte=None) -> np.ndarray:
        """y' = f(t, y) for y of shape (2n,) or (k, 2n); t matters only where the forces
        depend on time (``time_slot``).

        Raises
        ------
        NumericalFailure
            If the saddle-point system is singular or the value is not finite (its
            ``status`` says which).
        """
        if self.time_slot is not None and self._p[self.time_slot] != t:
            return self.at_time(t).rhs(t, y, baumgarte)
        ext = self._ext
        if ext is not None and baumgarte is None:
            # The hot path (what an integrator calls): one C call, a new array.
            out = ext.rhs(y, self._block0.address)
            if out is not None:  # None: not one contiguous float state (handled below)
                if type(out) is int:
                    raise NumericalFailure(out, _failure_message(out, y))
                return out
        compiled = self.compiled
        if (baumgarte is None and compiled is not None and self.backend == "c"
                and type(y) is np.ndarray and y.ndim == 1 and y.shape[0] == 2 * self.n):
            # The hot path (what an integrator calls): no extras.
            out, status = compiled.one(y, self._block0.pointer, self.path == "closed_form")
            if status:
                raise NumericalFailure(status, _failure_message(status, y))
            return out[:2 * self.n].copy()
        dy, _, _, status = self.evaluate(y, baumgarte, field_only=True)
        if status:
            raise NumericalFailure(status, _failure_message(status, y))
        return dy

    def multipliers(self, y) -> np.ndarray:
        """lambda, shape (m,) or (k, m)."""
        return self.evaluate(y)[1]

    def power(self, y):
        """-lambda . (mu v): the rate of change of E_L along the field."""
        return self.evaluate(y)[2]

    def _unpack_saddle(self, out):
        n, m, k = self.n, self.m, self.k
        lead = out.shape[:-1]
        W, F, mu, drift, h, g = columns(out, (n * n, n, m * n, m, m, k))
        return W.reshape(lead + (n, n)), F, mu.reshape(lead + (m, n)), drift, h, g

    def _evaluate_numpy(self, y, a2, b2):
        if y.ndim == 1:
            out = self.kernels.scalar("saddle", y.tolist(), self._plist)
        else:
            out = self.kernels.batch("saddle", y, self._plist)
        W, F, mu, drift, h, g = self._unpack_saddle(out)
        v = y[..., self.n:]
        muv = np.einsum("...ij,...j->...i", mu, v)
        bottom = -drift
        if a2:
            bottom = bottom - a2 * (muv + h)
        if b2 and self.k:
            pad = np.zeros_like(bottom)
            pad[..., :self.k] = g
            bottom = bottom - b2 * pad
        try:
            with np.errstate(all="ignore"):
                a, lam = solve_null_space(W, mu, F, bottom)
        except np.linalg.LinAlgError:
            nan = np.full_like(y, np.nan)
            return nan, np.full(y.shape[:-1] + (self.m,), np.nan), np.nan, Status.SINGULAR
        dy = np.concatenate([v, a], axis=-1)
        power = -np.sum(lam * muv, axis=-1)
        if self.forced:
            power = power + out[..., -1]  # the applied power Q . v
        status = Status.SUCCESS if np.all(np.isfinite(dy)) else Status.NONFINITE
        if y.ndim == 1:
            power = float(power)
        return dy, lam, power, status

    def _evaluate_closed(self, y, field_only):
        Y = y[None] if y.ndim == 1 else y
        n2 = 2 * self.n
        if self.backend == "c":
            OUT, bad = self.compiled.batch(Y, self._block0.pointer, closed=True)
            dY, LAM = OUT[:, :n2], OUT[:, n2:n2 + self.m]
            if y.ndim == 2 and not bad and field_only:
                return dY, LAM, np.zeros(Y.shape[0]), Status.SUCCESS
        else:
            if y.ndim == 1:
                out = self.kernels.scalar("closed", y.tolist(), self._plist)[None]
            else:
                out = self.kernels.batch("closed", y, self._plist)
            dY = np.concatenate([Y[:, self.n:], out[:, :self.n]], axis=1)
            LAM = out[:, self.n:]
        _, mu, _, _ = self.geometry(Y)
        muv = np.einsum("kij,kj->ki", mu, Y[:, self.n:])
        power = -np.sum(LAM * muv, axis=-1)
        if self.forced:  # the applied power Q . v, the last output of the saddle kernel
            power = power + self.kernels.batch("saddle", Y, self._plist)[:, -1]
        status = Status.SUCCESS if np.all(np.isfinite(dY)) else Status.NONFINITE
        if y.ndim == 1:
            return dY[0].copy(), LAM[0].copy(), float(power[0]), status
        return dY, LAM, power, status

    # ------------------------------------------------------ other kernels
    def geometry(self, y):
        """W, mu, h, g at the coordinates of y (shape (2n,)/(n,) or (k, 2n)/(k, n)).

        Returns
        -------
        W : (…, n, n);  mu : (…, m, n);  h : (…, m);  g : (…, k)
        """
        y = np.asarray(y, dtype=float)
        n, m, k = self.n, self.m, self.k
        width = 2 * n if self.geometry_reads_v else n
        if y.ndim == 1:
            out = self.kernels.scalar("geometry", y[:width].tolist(), self._plist)
        else:
            out = self.kernels.batch("geometry", y[:, :width], self._plist)
        lead = out.shape[:-1]
        W, mu, h, g = columns(out, (n * n, m * n, m, k))
        return W.reshape(lead + (n, n)), mu.reshape(lead + (m, n)), h, g

    def residuals(self, y) -> np.ndarray:
        """Constraint residuals [phi_1..phi_m, g_1..g_k], shape (m+k,) or (K, m+k).

        phi_i = mu_i(q) v + h_i(q) (complete lifts of the g first); g_a are the
        holonomic constraints themselves. Names: :attr:`residual_names`.
        """
        y = self._check(y)
        W, mu, h, g = self.geometry(y)
        phi = np.einsum("...ij,...j->...i", mu, y[..., self.n:]) + h
        return np.concatenate([phi, g], axis=-1)

    def scaled_residuals(self, y) -> np.ndarray:
        """Residuals divided by their natural size: |phi_i| / (1 + |mu_i| |v| + |h_i|),
        |g_a| / (1 + |grad g_a| |q|). Used for tolerance checks at any velocity scale."""
        y = self._check(y)
        W, mu, h, g = self.geometry(y)
        v, q = y[..., self.n:], y[..., :self.n]
        phi = np.einsum("...ij,...j->...i", mu, v) + h
        mnorm = np.sqrt(np.sum(mu * mu, axis=-1))
        vnorm = np.sqrt(np.sum(v * v, axis=-1))[..., None]
        qnorm = np.sqrt(np.sum(q * q, axis=-1))[..., None]
        sphi = np.abs(phi) / (1.0 + mnorm * vnorm + np.abs(h))
        sg = np.abs(g) / (1.0 + mnorm[..., :self.k] * qnorm)
        return np.concatenate([sphi, sg], axis=-1)

    def energy(self, y):
        """E_L = v . dL/dv - L; float for one state, (k,) for a batch."""
        y = self._check(y)
        if y.ndim == 1:
            return float(self.kernels.scalar("energy", y.tolist(), self._plist)[0])
        return self.kernels.batch("energy", y, self._plist)[:, 0].copy()

    def lagrangian_q(self, y) -> np.ndarray:
        """dL/dq at (q, v), shape (n,) or (k, n)."""
        y = np.asarray(y, dtype=float)
        if y.ndim == 1:
            return self.kernels.scalar("lq", y.tolist(), self._plist)
        return self.kernels.batch("lq", y, self._plist)

    def constraint_jacobian_q(self, y) -> np.ndarray:
        """d(phi)/dq at (q, v), shape (m, n) or (k, m, n)."""
        y = np.asarray(y, dtype=float)
        n, m = self.n, self.m
        if y.ndim == 1:
            return self.kernels.scalar("jphi", y.tolist(), self._plist).reshape(m, n)
        return self.kernels.batch("jphi", y, self._plist).reshape(-1, m, n)

    def cond_W(self, y):
        """2-norm condition number of W(q); float or (k,)."""
        return condition(self.geometry(self._check(y))[0])

    def cond_C(self, y):
        """2-norm condition number of C = -mu W^{-1} mu^T; 1.0 when m = 0."""
        y = self._check(y)
        W, mu, _, _ = self.geometry(y)
        if self.m == 0:
            return 1.0 if y.ndim == 1 else np.ones(y.shape[0])
        with np.errstate(all="ignore"):
            try:
                X = np.linalg.solve(W, np.swapaxes(mu, -1, -2))
                C = -mu @ X
                c = condition(C)
            except np.linalg.LinAlgError:
                c = np.inf if y.ndim == 1 else cond_each(W, mu)
        c = np.where(np.isfinite(c), c, np.inf)
        return float(c) if np.ndim(c) == 0 else c

    # ---------------------------------------------------------- projection
    def project(self, y, tol: float = 1e-14, maxiter: int = 50) -> ProjectionOutcome:
        """Project one state onto M_1 = {g(q) = 0, mu(q) v + h(q) = 0}.

        Positions: Newton iterations dq = -W^{-1} G^T (G W^{-1} G^T)^{-1} g with
        G = dg/dq (the complete-lift rows of mu): the step of least kinetic
        length. Velocities: the kinetic-metric orthogonal projection
        dv = -W^{-1} mu^T (mu W^{-1} mu^T)^{-1} (mu v + h), one solve (exact for
        affine constraints) plus one refinement for round-off.

        Raises
        ------
        NumericalFailure
            With ``Status.NOT_CONVERGED`` if Newton does not reach ``tol`` (scaled by
            1 + |q|) in ``maxiter``.
        """
        y = self._check(y).copy()
        if y.ndim != 1:
            raise ValueError("project works on one state")
        n, k = self.n, self.k
        before = float(np.max(np.abs(self.residuals(y)), initial=0.0))
        q0, v0 = y[:n].copy(), y[n:].copy()
        q, it = y[:n].copy(), 0
        if k:
            q, it = self._newton_positions(q, tol, maxiter)
        v = self._velocities_onto(q, v0)
        out = np.concatenate([q, v])
        after = float(np.max(np.abs(self.residuals(out)), initial=0.0))
        return ProjectionOutcome(out, before, after, float(np.linalg.norm(q - q0)),
                                 float(np.linalg.norm(v - v0)), it)

    def project_many(self, Y, tol: float = 1e-14, maxiter: int = 50) -> tuple:
        """:meth:`project` for K states at once: ``(projected (K, 2n), distances (K,))``.

        The velocities of all states are projected in one batched saddle solve (the
        same kinetic-metric projection and refinement as :meth:`project`); positions that
        violate a holonomic constraint are projected state by state first (Newton).
        """
        Y = np.atleast_2d(self._check(Y)).copy()
        n = self.n
        start = Y.copy()
        if self.k:
            _, _, _, g = self.geometry(Y)
            for i in np.flatnonzero(np.abs(g).max(axis=1) > 0):
                Y[i, :n], _ = self._newton_positions(Y[i, :n].copy(), tol, maxiter)
        Y[:, n:] = self._velocities_onto(Y[:, :n], Y[:, n:])
        return Y, np.linalg.norm(Y - start, axis=1)

    def _velocities_onto(self, q, v):
        """The velocities v (n,) or (K, n) at q projected onto mu(q) v + h(q) = 0 in the
        kinetic metric: dv = -W^{-1} mu^T (mu W^{-1} mu^T)^{-1} (mu v + h), one solve
        (exact for affine constraints) and one refinement for round-off."""
        if self.m == 0:
            return v
        if self.nonlinear:
            return velocities_newton(self.geometry, q, v)
        # W(q, v) of an L not quadratic in v: the metric at the given velocities
        W, mu, h, _ = self.geometry(np.concatenate([q, v], -1) if self.geometry_reads_v else q)
        for _ in range(2):
            r = (mu @ v[..., None])[..., 0] + h
            if not np.any(r):
                break
            dv, _ = solve_null_space(W, mu, np.zeros_like(v), -r)
            v = v + dv
        return v

    def _newton_positions(self, q, tol, maxiter):
        k, best = self.k, np.inf
        for it in range(1, maxiter + 1):
            W, mu, _, g = self.geometry(padded(q, self.geometry_reads_v))
            err = float(np.max(np.abs(g)))
            scale = 1.0 + float(np.max(np.abs(q)))
            if err <= tol * scale:
                return q, it - 1
            if it > 3 and err >= best:
                break  # round-off floor reached: no further decrease
            best = min(best, err)
            dq, _ = solve_null_space(W, mu[:k], np.zeros(self.n), -g)
            q = q + dq
        W, mu, _, g = self.geometry(padded(q, self.geometry_reads_v))
        err = float(np.max(np.abs(g)))
        if err <= max(tol, 1e-12) * (1.0 + float(np.max(np.abs(q)))):
            return q, maxiter
        raise NumericalFailure(
            Status.NOT_CONVERGED, f"projection onto the holonomic constraints did not "
            f"converge: |g| = {err:.3g} after {maxiter} Newton iterations")


def _until_built(f, pending):
    """``f`` until ``pending`` is built (:class:`LibraryReady`; a failed build: numpy goes
    on, with a :class:`NumericsWarning` saying why). One cheap test per call."""
    told = []

    def g(z):
        if pending.ready() and not told:
            if pending.succeeded():
                raise LibraryReady("the compiled library is built")
            told.append(True)
            warnings.warn(f"C backend unavailable ({pending.failure()}); numpy goes on",
                          NumericsWarning, stacklevel=2)
        return f(z)

    return g


def _failure_message(status, y) -> str:
    where = np.asarray(y).tolist() if np.ndim(y) == 1 else "(batch)"
    return f"{Status(status).message} at state {where}"
