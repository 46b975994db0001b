"""Linearisation about a steady motion on M_1, by complex-step differentiation (no sympy).

A state y0 = (q0, v0) on M_1 = {g(q) = 0, mu(q) v + h(q) = 0} is *steady* when
the constrained accelerations vanish there and every coordinate that moves
(v^A != 0) is one the dynamics does not depend on (a cyclic coordinate): an
equilibrium (v0 = 0) or a relative equilibrium such as a bicycle rolling
upright at constant speed.

Independent coordinates on M_1 (the chart): k of the coordinates are
dependent, solved from g(q) = 0 by Newton's method; m of the velocities are
dependent, solved from mu(q) v + h(q) = 0. The others, (q_I, u_I), are the
chart's coordinates, and the reduced field is

    F(q_I, u_I) = (q_I', u_I') = (v_I(q, v), a_I(q, v))

at the lifted state. Its Jacobian at the steady state is computed column by
column by the complex step dF/dx_j = Im F(x0 + i h e_j) / h (h = 1e-30): every
operation (the generated numpy kernel of W, F, mu, drift, h, g; the Newton
iteration of the lift; the saddle-point solve) is analytic, so there is no
subtractive cancellation and the derivative is exact to rounding, unlike a
finite difference.

Neutral directions: a chart coordinate whose Jacobian column vanishes is a
direction nothing depends on (a cyclic coordinate such as a position or a
wheel angle, or a rate such as the forward speed whose change only moves to a
neighbouring steady motion). Its eigenvalue is 0 with eigenvector e_j; it is
removed (repeatedly), and stability is decided on what remains: stability of
the steady motion modulo its symmetries and its family, the notion used for
relative equilibria (and by the bicycle benchmark: lean and steer only).

Verdict: asymptotically stable when every remaining eigenvalue has real part
< -tol, unstable when one has real part > tol, undecided (None) otherwise;
"spectrally stable" says that no real part exceeds tol (e.g. a conservative
system's purely imaginary spectrum, where linearisation cannot decide).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from nhham.autonomy import require_autonomous
from nhham.errors import ComputationError, InconsistentInitialDataError, InputError
from nhham.numerics.batch_linearization import (ON_TOLERANCE, ChartChoice, check_states,
                                                linearize_batch, step_vectors)
from nhham.numerics.chart import STEP, ComplexField, chart_jacobians, choose_chart
from nhham.numerics.nullspace import KKT_SOLVE
from nhham.numerics.quotient import MOMENTUM, ORBIT, divide, is_axis
from nhham.numerics.relative import group_block, spin_rate
from nhham.numerics.spectra import EIGENVALUE_TOLERANCE, sort_eigenvalues, spectra, verdicts
from nhham.numerics.status import NumericalFailure

if TYPE_CHECKING:  # the exact matrix comes from the symbolic side; numerics never imports it
    import sympy

__all__ = ["Linearization", "linearize", "linearize_many", "linearization_result", "STEP",
           "ON_TOLERANCE", "EIGENVALUE_TOLERANCE"]

# A Jacobian column is zero (a neutral direction) below this, relative to max |J|.
_NEUTRAL_TOL = 1e-10
#: Relative change of the Jacobian along a steady motion taken as rounding.
_INVARIANCE_TOL = 1e-7


# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class Linearization:
    """The linearised constrained dynamics about a steady state.

    Attributes
    ----------
    coordinates : tuple of str
        Names of the state variables of :attr:`matrix` (independent
        coordinates and velocities on M_1, neutral directions removed).
    matrix : ndarray, shape (d, d)
        State matrix A of x' = A x in those variables.
    eigenvalues : ndarray of complex, shape (d,)
        Eigenvalues of A, sorted by decreasing real part, then imaginary part.
    stable : bool or None
        True: every real part below minus its margin (asymptotically stable); False:
        one above its margin (unstable); None: undecided by linearisation.
    spectrally_stable : bool
        No real part exceeds its margin.
    verdict : str
        The verdict in words.
    method : str
        ``"complex-step"`` or ``"exact"``.
    precision : str
        How the numbers were obtained and the tolerance of the verdict.
    tolerance : float
        ``|Re lambda|`` at or below this counts as zero.
    margins : ndarray, shape (d,)
        Each eigenvalue's: its ``|Re|`` at or below this counts as zero (the tolerance,
        or its error estimate where larger: an eigenvalue in a cluster at 0,
        :mod:`nhham.numerics.spectra`).
    chart : tuple of str
        All independent coordinates and velocities (before removing neutral
        directions).
    full_matrix : ndarray
        The Jacobian in the full chart.
    neutral : tuple of str
        The neutral directions divided out (eigenvalue 0 each), in order
        (:mod:`nhham.numerics.quotient`): chart variables removed, ``orbit(xi)`` (the
        ``[symmetry]``'s orbit), ``d/d<p>`` (the steady family's tangent), ``level(J)``
        (the level of a conserved momentum).
    dependent : tuple of str
        Coordinates and velocities solved from the constraints.
    state : mapping of str to float
        The steady state (every coordinate and velocity).
    residuals : mapping of str to float
        Constraint residuals at the state.
    acceleration_residual : float
        ``max |a|`` at the state (zero for a steady motion).
    exact_matrix : sympy.Matrix or None
        The state matrix with exact entries (``method == "exact"``).
    inputs : tuple of str
        The system's inputs u (empty without any).
    input_matrix : ndarray, shape (d, len(inputs))
        B of x' = A x + B u in the variables of :attr:`matrix`, the inputs at their
        steady values (complex-step derivative in each input, exact to rounding).
    relative : mapping or None
        For a relative equilibrium (a steady motion along a symmetry's generator xi,
        :mod:`nhham.numerics.relative`): ``generator`` ({coordinate: expression}),
        ``rate`` (w), ``group`` (the chart coordinates divided out as the group's
        directions) and ``group_eigenvalues`` (their block's eigenvalues in co-moving
        variables); :attr:`matrix` is then the Jacobian of X - w Xi. None otherwise.
    kkt_solve : str
        How the constrained accelerations were solved: ``"null-space"``
        (:mod:`nhham.numerics.nullspace`, at every state).
    kkt_ratio : float
        max W_AA / min W_AA at the state (:func:`nhham.numerics.nullspace.diagonal_ratio`):
        the spread of the masses in the scene's units, a diagnostic.
    implied : tuple of str
        Neutral directions (``orbit(xi)``, ``d/d<p>``, ``level(J)``) not divided out
        because the chart variables removed span them already (the orbit of a robot at
        rest, whose heading and trailer angle are neutral there): a sweep's reference
        counts them as neutral at this state.

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham.numerics.linearization import linearize
    >>> lin = linearize(model, {**forward, "x_dot": -2.0})     # backwards: w grows
    >>> lin.eigenvalues.round(12), lin.stable
    (array([2.+0.j]), False)
    >>> lin.neutral
    ('x', 'y', 'theta', 'x_dot')
    """

    coordinates: tuple
    matrix: np.ndarray
    eigenvalues: np.ndarray
    stable: bool | None
    spectrally_stable: bool
    verdict: str
    method: str
    precision: str
    tolerance: float
    chart: tuple
    full_matrix: np.ndarray
    neutral: tuple
    dependent: tuple
    state: Mapping[str, float]
    residuals: Mapping[str, float] = field(default_factory=dict)
    acceleration_residual: float = 0.0
    exact_matrix: sympy.Matrix | None = None
    inputs: tuple = ()
    input_matrix: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    relative: Mapping | None = None
    margins: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kkt_solve: str = KKT_SOLVE
    kkt_ratio: float = 1.0
    implied: tuple = ()

    def state_space(self):
        """``scipy.signal.StateSpace(A, B, I, 0)``: the linearisation as a system with the
        inputs u and the full state of :attr:`coordinates` as outputs.

        Without inputs (a closed loop, a system without any) B and D have no columns,
        shape (d, 0): no input is made up. scipy takes such a system (``lsim`` with
        ``U=None`` gives its free response, ``to_discrete`` works), but its
        transfer-function routes (``poles``, ``zeros``, ``to_tf``, ``bode``,
        ``impulse``) need an input and raise; the poles are :attr:`eigenvalues`.
        """
        from scipy import signal

        d, r = self.matrix.shape[0], len(self.inputs)
        B = self.input_matrix if r else np.zeros((d, 0))
        return signal.StateSpace(self.matrix, B, np.eye(d), np.zeros((d, r)))

    def to_dict(self) -> dict:
        """JSON-ready: ``coordinates``, ``matrix``, ``eigenvalues`` ([re, im]), ``stable``..."""
        return {
            "coordinates": list(self.coordinates),
            "matrix": [[float(x) for x in row] for row in self.matrix],
            "eigenvalues": [[float(z.real), float(z.imag)] for z in self.eigenvalues],
            "stable": self.stable,
            "spectrally_stable": self.spectrally_stable,
            "verdict": self.verdict,
            "method": self.method,
            "precision": self.precision,
            "tolerance": self.tolerance,
            "chart": list(self.chart),
            "neutral": list(self.neutral),
            "dependent": list(self.dependent),
            "steady_state": dict(self.state),
            "residuals": dict(self.residuals),
            "acceleration_residual": self.acceleration_residual,
            "margins": [float(x) for x in self.margins],
            "kkt_solve": self.kkt_solve,
            "kkt_ratio": float(self.kkt_ratio),
            **({} if not self.inputs else
               {"inputs": list(self.inputs),
                "input_matrix": [[float(x) for x in row] for row in self.input_matrix]}),
            **({} if self.relative is None else
               {"relative_equilibrium": _relative_dict(self.relative)}),
            **({} if self.exact_matrix is None else
               {"matrix_exact": [[str(x) for x in self.exact_matrix.row(i)]
                                 for i in range(self.exact_matrix.rows)]}),
        }


def _relative_dict(relative) -> dict:
    return {"generator": dict(relative["generator"]), "rate": float(relative["rate"]),
            "frame": ("co-moving (the Jacobian of X - w Xi)" if relative["turning"]
                      else "the Jacobian of X (w = 0, or xi constant: X - w Xi has X's)"),
            "group": list(relative["group"]),
            "orbit": bool(relative.get("orbit", False)),
            "momentum": bool(relative.get("momentum", False)),
            "invariance": dict(relative.get("invariance", {})),
            "group_eigenvalues": [[float(z.real), float(z.imag)]
                                  for z in relative["group_eigenvalues"]]}


def linearization_result(A, coords, method, precision, chart_names, J, removed, dependent,
                         state, residuals, worst, tol=None, eigenvalues=None,
                         exact_matrix=None, inputs=(), B=None,
                         relative=None, margins=None, kkt=("saddle", 1.0),
                         implied=()) -> "Linearization":
    """Eigenvalues and the stability verdict of a state matrix, as a :class:`Linearization`.

    ``A`` is the state matrix in the variables ``coords``; ``eigenvalues``
    may be given (e.g. computed with more digits; their margins then ``tol``), otherwise
    LAPACK's with their margins (:func:`nhham.numerics.spectra.spectra`).
    ``tol`` (default 1e-9 max(1, max |A|)) is the real part counted as zero.
    ``kkt``: (the acceleration solve's name, its ratio). The other arguments are stored
    as the attributes of the same names.
    """
    A = np.asarray(A, dtype=float)
    if eigenvalues is None:
        e, m, t, _ = spectra(A[None], None if tol is None else [tol])
        ev, margins, tol = e[0], m[0], float(t[0])
    elif margins is None:   # computed elsewhere (with more digits): the tolerance each
        ev = sort_eigenvalues(np.asarray(eigenvalues, dtype=complex))
        tol = (EIGENVALUE_TOLERANCE * max(1.0, float(np.abs(A).max(initial=0.0)))
               if tol is None else tol)
        margins = np.full(ev.shape, float(tol))
    else:                   # a batch's: sorted, with their margins
        ev, margins = np.asarray(eigenvalues, dtype=complex), np.asarray(margins, float)
    code = int(verdicts(ev[None], margins[None])[0])
    if not ev.size:
        stable, verdict = None, "no non-neutral directions: linearisation cannot decide"
    elif code == 1:
        stable, verdict = True, "asymptotically stable (every eigenvalue has Re < 0)"
    elif code == 0:
        stable, verdict = False, "unstable (an eigenvalue has Re > 0)"
    else:
        stable = None
        verdict = ("spectrally stable: the largest real part is 0 to the tolerance; "
                   "linearisation cannot decide")
    wide = int(np.sum(margins > tol))
    note = (f" ({wide} eigenvalue(s) in a cluster at 0 to {float(margins.max()):.1e}, "
            f"their rounding error)" if wide else "")
    return Linearization(
        coordinates=coords, matrix=A, eigenvalues=ev, stable=stable,
        spectrally_stable=bool(np.all(ev.real <= margins)), verdict=verdict, method=method,
        precision=f"{precision}; |Re| <= {tol:.1e} counts as 0{note}", tolerance=float(tol),
        chart=tuple(chart_names), full_matrix=J, neutral=tuple(removed),
        dependent=tuple(dependent), state=MappingProxyType(state),
        residuals=MappingProxyType(residuals), acceleration_residual=worst,
        exact_matrix=exact_matrix, inputs=tuple(inputs),
        input_matrix=np.zeros((A.shape[0], 0)) if B is None else B,
        relative=None if relative is None else MappingProxyType(dict(relative)),
        margins=np.asarray(margins, dtype=float), kkt_solve=kkt[0], kkt_ratio=float(kkt[1]),
        implied=tuple(implied))


# ------------------------------------------------------------------ public
def linearize(model, state, *, independent: Sequence[str] | None = None,
              neutral: bool | Sequence[str] = True, step: float = STEP,
              family: Mapping[str, Mapping[str, float]] | None = None,
              generator=None) -> Linearization:
    """Linearise the constrained dynamics about a steady state on M_1.

    Parameters
    ----------
    model : nhham.numerics.NumericModel
        From :func:`nhham.numerics.codegen.numeric_model` (parameter values
        as in the model; use ``model.with_parameters`` to change them).
    state : mapping of str to float, or sequence
        Every coordinate and velocity (see ``model.state``).
    independent : sequence of str, optional
        Names of the chart's independent coordinates and velocities; default:
        dependent ones chosen greedily from the left among well-conditioned
        columns of dg/dq and mu (velocities of dependent coordinates first).
    neutral : bool or sequence of str, optional
        True (default): divide out every neutral direction (a zero Jacobian column, the
        ``[symmetry]``'s orbit, a family tangent, a conserved momentum's level:
        :mod:`nhham.numerics.quotient`); False: keep all; a sequence: those labels
        (chart variables checked to be neutral; the others where they hold).
    step : float, optional
        The imaginary step (default 1e-30).
    family : mapping of str to mapping of str to float, optional
        Tangents of the family of steady motions the state belongs to:
        ``{parameter: {state name: d(value)/d(parameter)}}`` (e.g. the
        derivative of a scene's ``[steady]`` entries in the forward speed).
        A tangent that the state matrix maps to zero is a neutral direction
        (a neighbouring steady motion) and is divided out as well; it is
        listed in ``neutral`` as ``d/d<parameter>``.
    generator : nhham.numerics.relative.Generator, optional
        The tangent lift Xi of a symmetry's generator xi (checked to leave L, the
        constraints and the forces invariant by the caller: a scene's ``[symmetry]``).
        The state may then move along xi: v0 = w xi(q0) + a motion of cyclic
        coordinates, with X(y0) = w Xi(y0) (a relative equilibrium); X - w Xi is
        linearised (co-moving variables) and the group's directions divided out: the
        orbit Xi(y0) (for w = 0 as for w != 0) and, where the symmetry's momentum is
        conserved, its level.

    Returns
    -------
    Linearization

    Raises
    ------
    InconsistentInitialDataError
        The state is not on M_1 or not steady (the message shows the
        residuals); with a generator: not a relative equilibrium along it.
    ComputationError
        A constraint or the saddle-point matrix is singular at the state.

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham.numerics.linearization import linearize
    >>> lin = linearize(model, forward)     # w' = -m a u w / (I + m a**2) = -2 w at u = 2
    >>> lin.coordinates, lin.eigenvalues.round(12), lin.stable
    (('theta_dot',), array([-2.+0.j]), True)
    """
    if not hasattr(model, "kernels"):
        raise InputError(f"linearize: expected a NumericModel (nhham.numeric_model(system)), "
                         f"got {type(model).__name__}", key="model")
    y0 = model.state(state)
    _check_inputs(model)
    P = np.asarray(model.parameter_values, dtype=float)[:, None]
    motion = None if generator is None else spin_rate(generator, y0, model.n, P.T)
    cf = ComplexField(model)
    residuals, worst = _check_steady(cf, model, y0, P.T, motion)
    chart = choose_chart(model, y0, independent)
    rates = None if motion is None else np.array([motion.rate])

    def jacobian(y):
        return chart_jacobians(cf, chart, y[None, :], step, P, generator=generator,
                               rates=rates)[0]

    J = jacobian(y0)
    if not np.all(np.isfinite(J)):  # the user's state: no linearisation there
        raise _not_smooth_there()
    moved = _moved_along(y0, model.n, None if motion is None else motion.rest)
    choice, info, implied = _decide(cf, model, y0, P, chart, J, lambda: jacobian(moved),
                                    neutral, family, step, generator, motion)
    # the state matrix, its quotient and its spectrum: a batch of one
    batch = linearize_batch(model, y0[None, :], P.T, reference=choice, families=[family],
                            step=step, generator=generator, build=False)
    if batch.status[0] != 0:
        raise ComputationError("linearize: the linearisation failed at the state (a neutral "
                               "direction not in the kernel, or a singular solve)")
    n, names = model.n, model.names
    dependent = tuple(names[i] for i in chart.dq) + tuple(names[n + i] for i in chart.dv)
    return linearization_result(
        batch.matrices[0], choice.coordinates, "complex-step",
        f"float64, complex-step Jacobian (step {step:g}i, exact to rounding), LAPACK "
        f"eigenvalues", choice.chart, J, choice.neutral, dependent,
        dict(zip(names, map(float, y0))), residuals, worst, tol=float(batch.tolerances[0]),
        eigenvalues=batch.eigenvalues[0], inputs=model.input_names,
        B=batch.input_matrices[0], relative=info, margins=batch.margins[0],
        kkt=(KKT_SOLVE, float(batch.kkt_ratios[0])),
        implied=implied)


#: From this many states :func:`linearize_many` compiles the model's complex-step kernels
#: (0.6 s for the bicycle's at -O0) instead of evaluating the complex step with numpy
#: (about 20 ms a state there).
BUILD_COMPLEX_FROM = 32


def linearize_many(models: Sequence, states: Sequence, independent: Sequence[str], *,
                   neutral: bool | Sequence[str] = True, step: float = STEP,
                   families: Sequence | None = None, generator=None) -> list:
    """:func:`linearize` at many (model, state) pairs in one chart, each deciding its
    neutral directions (a family of states with one set of decisions: a reference and
    :func:`~nhham.numerics.batch_linearization.linearize_batch`).

    Parameters
    ----------
    models : sequence of NumericModel
        One model (the same one with other parameter values, ``with_parameters``) per
        state.
    states : sequence of mappings or sequences
        As for :func:`linearize`.
    independent : sequence of str
        The chart of every state (e.g. ``Linearization.chart`` of a first
        :func:`linearize`), checked at each.
    neutral, step
        As for :func:`linearize`.
    families : sequence of mappings, optional
        The ``family`` of each state.
    generator : nhham.numerics.relative.Generator, optional
        As for :func:`linearize` (each state its own rate w).

    Returns
    -------
    list of Linearization
        The same as :func:`linearize` at each pair, to rounding.

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import linearize_many
    >>> from nhham.numerics.linearization import linearize
    >>> chart = linearize(model, forward).chart
    >>> lins = linearize_many([model.with_parameters(a=a) for a in (0.5, 1.0)],
    ...                       [forward, forward], chart)
    >>> [lin.eigenvalues.round(12) for lin in lins]    # -m a u / (I + m a**2)
    [array([-2.+0.j]), array([-1.6+0.j])]
    """
    families = families or [None] * len(models)
    if len(models) >= BUILD_COMPLEX_FROM and models[0].compiled is not None:
        from nhham.numerics.codegen.build import complex_kernels

        complex_kernels(models[0], build_now=True)  # then every linearize below uses them
    return [linearize(m, s, independent=independent, neutral=neutral, step=step, family=f,
                      generator=generator) for m, s, f in zip(models, states, families)]


def _check_inputs(model):
    unset = model.unset_inputs()
    if unset:
        raise InputError(f"linearize: no steady value for the input(s) {', '.join(unset)} "
                         f"(a scene's [steady] gives one for every input; in Python: "
                         f"model.with_parameters({unset[0]}=...))", key="steady")
    require_autonomous("linearize_geometry", model.time_in_geometry, key=model.timed_key)
    require_autonomous("linearize", model.time_slot is not None)


def _check_steady(cf, model, y0, P, motion=None):
    """(residuals, largest acceleration) at a state checked to be on M_1 and steady (with
    ``motion``: X(y0) = w Xi(y0), the accelerations those of the group motion): the
    batch's decision (:func:`~nhham.numerics.batch_linearization.check_states`), said
    with the names."""
    n, names = model.n, model.names
    checks = check_states(cf, y0[None, :], P,
                          None if motion is None else np.array([motion.rate]),
                          None if motion is None else motion.lifted[None, :])
    status = int(checks.status[0])
    raw = model.residuals(y0)
    if status == 1:
        listed = "; ".join(f"{nm} = {r:.3g}" for nm, r, sc in
                           zip(model.residual_names, raw, checks.scaled[0])
                           if not sc <= ON_TOLERANCE)
        raise InconsistentInitialDataError(f"steady: the state is not on M_1: {listed}")
    acc = checks.accelerations[0]
    not_finite = status == 2 and not np.all(np.isfinite(acc))
    if not_finite and _real_field_finite(model, y0):
        raise _not_smooth_there()   # atan2(0, 0): 0 in real arithmetic, NaN in complex
    if status == 3 or not_finite:
        # the user's state: no motion is defined there (bad input, not a failure of ours)
        raise InconsistentInitialDataError(
            f"steady: the equations of motion are not defined at the state: "
            f"{_undefined_there(model, y0, status == 3)}; choose a [steady] state where they "
            f"are", key="steady")
    worst = float(checks.acceleration_residuals[0])
    if status == 2:
        scale = max(1.0, float(np.abs(y0).max()))
        listed = ", ".join(f"{names[n + i]}' = {acc[i]:.3g}" for i in np.argsort(-np.abs(acc))[:4]
                           if abs(acc[i]) > ON_TOLERANCE * scale ** 2)
        if motion is not None:
            raise InconsistentInitialDataError(
                f"steady: the state is not a relative equilibrium along the [symmetry] "
                f"generator (w = {motion.rate:.6g}): the accelerations minus w times its lift "
                f"are {listed} (largest {worst:.3g}; they vanish on a motion "
                f"q(t) = exp(t w xi) q0)")
        raise InconsistentInitialDataError(
            f"steady: the state is not steady: accelerations {listed} (largest {worst:.3g}; "
            f"a steady motion has every acceleration zero)")
    return {nm: float(r) for nm, r in zip(model.residual_names, raw)}, worst


#: How a scene declares the symmetry a steady motion follows (the refusals say it).
DECLARE_HINT = ("declare the symmetry the motion follows in a [symmetry] table of the scene "
                "(its generator xi by coordinate, e.g. yaw = \"1\", x = \"-y\", y = \"x\" for "
                "the rotation about the vertical), and linearize linearises in co-moving "
                "variables")


def _decide(cf, model, y0, P, chart, J, moved_jacobian, neutral, family, step, generator,
            motion):
    """The neutral directions at y0 from the full Jacobian J of the chart (and, when the
    state moves, checked along the motion): (ChartChoice, relative-equilibrium info)."""
    n, names = model.n, model.names
    chart_names = tuple(names[i] for i in chart.iq) + tuple(names[n + i] for i in chart.iv)
    # a constant xi (cyclic coordinates) leaves X's Jacobian and today's quotient
    turning = motion is not None and motion.rate != 0.0 and not generator.constant
    coordinates = set(names[:n]) if turning else set()
    axes = neutral if isinstance(neutral, bool) else [s for s in neutral if is_axis(s)]
    keep, removed, group = _neutral_directions(J, chart_names, axes, coordinates)
    scale = max(1.0, float(np.abs(y0).max()))
    velocity = y0[n:] if motion is None else motion.rest
    moving = [names[i] for i in range(n) if abs(velocity[i]) > ON_TOLERANCE * scale]
    not_cyclic = [s for s in moving if s not in removed]
    relative = None if motion is None else (generator, motion)
    if not_cyclic and relative is not None:
        _not_along(relative, not_cyclic, "the dynamics depends on them")
    if not_cyclic:
        raise InconsistentInitialDataError(
            f"steady: the coordinates {', '.join(not_cyclic)} move at the state but the dynamics "
            f"depends on them (or they are dependent), so the motion is not steady; if it is "
            f"a relative equilibrium, {DECLARE_HINT}")
    if moving:
        change = float(np.abs(moved_jacobian() - J).max(initial=0.0))
        if change > _INVARIANCE_TOL * max(1.0, float(np.abs(J).max(initial=0.0))):
            if relative is not None:
                _not_along(relative, moving, f"the linearised dynamics changes along that "
                           f"motion (by {change:.3g} over the first half radian or unit)")
            raise InconsistentInitialDataError(
                f"steady: the motion moves {', '.join(moving)} and the linearised dynamics "
                f"changes along it (by {change:.3g} over the first half radian or unit), so the "
                f"state matrix at this point does not describe its stability; linearize needs "
                f"coordinates in which every moving one is cyclic, or, for a motion along a "
                f"symmetry group (a rotation about the vertical that also turns the "
                f"constraints): {DECLARE_HINT}")
    kept = [chart_names[i] for i in keep]
    # the other neutral directions: the orbit, the family's tangents, the momentum's level
    wanted = (None if neutral is True else set() if neutral is False
              else {s for s in neutral if not is_axis(s)})
    labels = ([ORBIT] if generator is not None else []) + \
        [f"d/d{p}" for p in (family or {})] + \
        ([MOMENTUM] if generator is not None and generator.momentum is not None else [])
    labels = [s for s in labels if wanted is None or s in wanted]
    taken: list = []
    coords = kept
    implied = []
    if labels:
        full = step_vectors(cf, chart, y0[None, :], P.T, step, list(chart_names), labels,
                            [family], generator,
                            None if motion is None else motion.lifted[None, :])[0]
        vectors = [(label, None if v is None else v[keep]) for label, v in full]
        _, _, coords, taken = divide(J[np.ix_(keep, keep)], None, kept, vectors)
        # a direction inside the span of the chart variables removed (the orbit of a
        # robot at rest, whose heading and trailer angle are both neutral there)
        implied = [label for label, v in full if v is not None and label not in taken
                   and np.abs(v).max(initial=0.0) > 0.0 and np.abs(v[keep]).max(initial=0.0)
                   <= 1e-9 * np.abs(v).max(initial=0.0)]
    info = None
    if motion is not None:
        block = J[np.ix_(group, group)]
        info = {"generator": generator.to_dict(), "rate": motion.rate,
                "turning": turning, "invariance": dict(generator.checked),
                "group": tuple(chart_names[i] for i in group),
                "orbit": ORBIT in taken, "momentum": MOMENTUM in taken,
                "group_eigenvalues": tuple(sort_eigenvalues(np.linalg.eigvals(block))
                                           if group else ())}
    return ChartChoice(chart_names, tuple(removed) + tuple(taken), tuple(coords)), info, \
        tuple(implied)


def _not_along(relative, moving, why):
    generator, motion = relative
    raise InconsistentInitialDataError(
        f"steady: the velocities are not along the [symmetry] generator "
        f"xi = {generator.text()} (w = {motion.rate:.6g}) plus cyclic coordinates: "
        f"{', '.join(moving)} move besides the group motion and {why}")


def _moved_along(y0, n, rest=None):
    """y(t) = (q0 + t v0, v0), the steady motion itself, moved until some coordinate has
    changed by 1/2; None when nothing moves (``rest``: the velocity besides a symmetry
    group's motion, in place of v0: the flow of X - w Xi). A steady motion whose moving
    coordinates are cyclic has the same Jacobian all along; zero Jacobian columns at y0
    alone do not show that (the spinning Chaplygin sphere: the yaw column vanishes, but
    turning the yaw turns the constraints' velocity block)."""
    v0 = y0[n:] if rest is None else rest
    top = float(np.abs(v0).max(initial=0.0))
    if top <= ON_TOLERANCE * max(1.0, float(np.abs(y0).max())):
        return None
    y1 = y0.astype(float).copy()
    y1[:n] += 0.5 / top * v0
    return y1


def _not_smooth_there() -> InconsistentInitialDataError:
    return InconsistentInitialDataError(
        "steady: the state matrix is not finite at the state (a derivative of the "
        "lagrangian or of a constraint is not finite there: atan2(0, 0), sqrt at 0); "
        "choose a [steady] state where the motion is smooth", key="steady")


def _real_field_finite(model, y0) -> bool:
    """Whether the field is finite at y0 in real arithmetic (the complex step's was not)."""
    try:
        with np.errstate(all="ignore"):
            return bool(np.all(np.isfinite(model.rhs(0.0, y0))))
    except NumericalFailure:
        return False


def _undefined_there(model, y0, singular) -> str:
    """Why the field is not defined at y0, in the words of the scene: W, the constraints,
    or C (``singular``: the saddle-point solve found its matrix singular)."""
    with np.errstate(all="ignore"):
        W, mu, h, _ = model.geometry(y0)
        if not np.all(np.isfinite(W)):
            return "the Hessian W = d2L/dv dv of the lagrangian is not finite there"
        if np.linalg.matrix_rank(W) < model.n:
            return "the Hessian W = d2L/dv dv of the lagrangian is singular there"
        if not (np.all(np.isfinite(mu)) and np.all(np.isfinite(h))):
            return "a constraint is not finite there"
    if singular:
        return "C = mu W^-1 mu^T is singular there (the multipliers are not determined)"
    return "the field is not finite there (the lagrangian or a constraint leaves its domain)"


def _neutral_directions(J, chart_names, neutral, coordinates=frozenset()):
    """(kept indices, removed names, group indices): the chart variables divided out.
    ``coordinates``: the names of Q's coordinates when X - w Xi is linearised, whose
    group block (:func:`~nhham.numerics.relative.group_block`) is divided out too."""
    d = J.shape[0]
    keep = list(range(d))
    scale = max(1.0, float(np.abs(J).max(initial=0.0)))
    if neutral is False:
        return keep, (), []
    if neutral is True:
        removed: list = []
        group: list = []
        changed = True
        while changed:
            changed = _zero_columns(J, keep, removed, chart_names, scale)
            block = group_block(J, chart_names, coordinates, keep, _NEUTRAL_TOL * scale)
            if block:
                group += block
                for j in block:
                    keep.remove(j)
                    removed.append(chart_names[j])
                changed = True
        return keep, tuple(removed), sorted(group)
    wanted = list(neutral)
    unknown = [s for s in wanted if s not in chart_names]
    if unknown:
        raise InputError(f"linearize: neutral: {', '.join(unknown)} not in the chart "
                         f"({', '.join(chart_names)})")
    pending = [chart_names.index(s) for s in wanted]
    group = []
    while pending:
        zero = [j for j in pending
                if np.abs(J[np.ix_(keep, [j])]).max(initial=0.0) <= _NEUTRAL_TOL * scale]
        if not zero and coordinates:
            block = [j for j in group_block(J, chart_names, coordinates, keep,
                                            _NEUTRAL_TOL * scale) if j in pending]
            zero = block if block and set(block) <= set(pending) else []
            group += zero
        if not zero:
            raise InputError(f"linearize: neutral: the dynamics depends on "
                             f"{', '.join(chart_names[j] for j in pending)} at this state; "
                             f"not neutral directions")
        for j in zero:
            keep.remove(j)
            pending.remove(j)
    return keep, tuple(wanted), sorted(group)


def _zero_columns(J, keep, removed, chart_names, scale) -> bool:
    """Remove (repeatedly) the kept variables whose column vanishes in the kept rows."""
    found = False
    changed = True
    while changed:
        changed = False
        for j in list(keep):
            if np.abs(J[np.ix_(keep, [j])]).max(initial=0.0) <= _NEUTRAL_TOL * scale:
                keep.remove(j)
                removed.append(chart_names[j])
                changed = found = True
    return found
