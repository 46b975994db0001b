"""Linearisations at steady states, one or many at once: the one implementation of the
state matrices, their neutral directions divided out, their spectra and verdicts.

:func:`~nhham.numerics.linearization.linearize` decides the chart and the neutral
directions at its state and checks them (the Jacobian in every chart variable, and
again along the motion), then takes its state matrix from :func:`linearize_batch` as a
batch of one. A study or a sweep takes those decisions once from a *reference*
linearisation (made at probe states by the caller) and computes, for all states in one
batch of the generated kernel, only what changes from state to state:

- whether the state is on M_1 and steady (scaled residuals and the largest
  acceleration), as a status per state (``linearize`` raises with the same numbers);
- the complex-step Jacobian columns of the variables kept (the reference's ``chart``
  less the variables it deleted), so the bicycle needs 4 columns per state instead of
  the 2 x 10 of ``linearize``'s decisions;
- the vectors of the other neutral directions at each state (the [symmetry]'s orbit,
  the steady family's tangents, the level of a conserved momentum) and the quotient by
  them (:func:`nhham.numerics.quotient.divide`);
- the eigenvalues, their margins and the verdict (:func:`nhham.numerics.spectra.spectra`).

The neutral directions are the reference's: the caller checks them at its probes (a
column zero at one state of a smooth family is zero at its neighbours only generically);
a state where a direction is not in the kernel has status 3. No sympy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from typing import TYPE_CHECKING

from nhham.errors import ComputationError
from nhham.numerics.chart import (STEP, Chart, ComplexField, chart_gradients,
                                  chart_jacobians, input_jacobians, lift)
from nhham.numerics.quotient import MOMENTUM, ORBIT, divide, is_axis
from nhham.numerics.relative import spin_rates
from nhham.numerics.nullspace import solve_null_space
from nhham.numerics.spectra import spectra, unstable_counts

if TYPE_CHECKING:   # a reference may be a Linearization (the batch reads three fields)
    from nhham.numerics.linearization import Linearization

__all__ = ["ChartChoice", "LinearizationBatch", "Spectrum", "linearize_batch", "STATUS_TEXT",
           "ON_TOLERANCE", "check_states", "step_vectors"]

#: Relative tolerance for "on M_1" and "steady" (residual / natural size).
ON_TOLERANCE = 1e-9

#: Status of a state (``LinearizationBatch.status``): what each code means.
STATUS_TEXT = {0: "linearised", 1: "not on M_1", 2: "not steady",
               3: "singular (the saddle-point matrix or a constraint at the state, or a "
                  "neutral direction of the reference not in the kernel there)"}


@dataclass(frozen=True)
class ChartChoice:
    """What a batch takes from its reference linearisation (plain data: it crosses
    process boundaries).

    Attributes
    ----------
    chart : tuple of str
        The independent coordinates and velocities.
    neutral : tuple of str
        The neutral directions divided out, in order (:mod:`nhham.numerics.quotient`):
        chart variables deleted, then ``orbit(xi)``, ``d/d<p>`` tangents and
        ``level(J)``.
    coordinates : tuple of str
        The variables of the state matrices.

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import ChartChoice
    >>> from nhham.numerics.linearization import linearize
    >>> ChartChoice.of(linearize(model, forward))
    ChartChoice(chart=('x', 'y', 'theta', 'x_dot', 'theta_dot'), neutral=('x', 'y', 'theta', 'x_dot'), coordinates=('theta_dot',))
    """

    chart: tuple
    neutral: tuple
    coordinates: tuple

    @classmethod
    def of(cls, lin: "Linearization") -> "ChartChoice":
        return cls(tuple(lin.chart), tuple(lin.neutral), tuple(lin.coordinates))


@dataclass(frozen=True)
class Spectrum:
    """Eigenvalues with the tolerance of their verdict and each one's margin (what
    locating a crossing reads; :mod:`nhham.numerics.spectra`)."""

    eigenvalues: np.ndarray
    tolerance: float
    margins: np.ndarray | None = None


@dataclass(frozen=True)
class LinearizationBatch:
    """Linearisations of N steady states in one chart.

    Attributes
    ----------
    coordinates : tuple of str
        The variables of every state matrix (the reference's).
    matrices : ndarray, shape (N, d, d)
        State matrices A (NaN where ``status`` is not 0).
    eigenvalues : ndarray of complex, shape (N, d)
        Sorted as in :class:`~nhham.numerics.linearization.Linearization` (decreasing
        real part, then imaginary part); NaN where ``status`` is not 0.
    verdicts : ndarray of int8, shape (N,)
        1 asymptotically stable (every Re < -margin), 0 unstable (some Re > margin), -1
        not decided by linearisation (or not linearised)
        (:data:`nhham.numerics.spectra.VERDICT_TEXT`).
    tolerances : ndarray, shape (N,)
        ``1e-9 max(1, max |A|)``.
    status : ndarray of int8, shape (N,)
        0 linearised; 1 not on M_1; 2 not steady; 3 singular (:data:`STATUS_TEXT`).
    constraint_residuals : ndarray, shape (N,)
        The largest scaled constraint residual at each state.
    acceleration_residuals : ndarray, shape (N,)
        ``max |a|`` at each state (0 for a steady motion).
    inputs : tuple of str
    input_matrices : ndarray, shape (N, d, len(inputs))
        B of x' = A x + B u.
    margins : ndarray, shape (N, d)
        ``|Re|`` at or below each eigenvalue's margin counts as 0
        (:func:`nhham.numerics.spectra.spectra`).
    kkt_ratios : ndarray, shape (N,)
        max W_AA / min W_AA (:func:`nhham.numerics.nullspace.diagonal_ratio`): the spread
        of the masses in the scene's units, a diagnostic (the accelerations come from
        the null-space solve at every state).

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import ChartChoice, linearize_batch
    >>> from nhham.numerics.linearization import linearize
    >>> reference = ChartChoice.of(linearize(model, forward))
    >>> parameters = [[1.0, 0.25, 0.5], [1.0, 0.25, 1.0]]     # m, I, a
    >>> batch = linearize_batch(model, [model.state(forward)] * 2, parameters,
    ...                         reference=reference)
    >>> batch.coordinates, batch.matrices.round(12).ravel()   # a = 0.5, 1: -2, -1.6
    (('theta_dot',), array([-2. , -1.6]))
    """

    coordinates: tuple
    matrices: np.ndarray
    eigenvalues: np.ndarray
    verdicts: np.ndarray
    tolerances: np.ndarray
    status: np.ndarray
    constraint_residuals: np.ndarray
    acceleration_residuals: np.ndarray
    inputs: tuple
    input_matrices: np.ndarray
    margins: np.ndarray
    kkt_ratios: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        """Boolean (N,): asymptotically stable."""
        return self.verdicts == 1

    @property
    def unstable_counts(self) -> np.ndarray:
        """(N,): the eigenvalues with Re above their margin (-1: not linearised); what a
        crossing of the imaginary axis changes (:mod:`nhham.numerics.crossings`)."""
        return np.where(self.status == 0, unstable_counts(self.eigenvalues, self.margins), -1)

    def spectrum(self, i: int) -> Spectrum | None:
        """The eigenvalues of state ``i`` with their tolerance (None: not linearised)."""
        if self.status[i] != 0:
            return None
        return Spectrum(self.eigenvalues[i], float(self.tolerances[i]), self.margins[i])

    @property
    def spectral_abscissa(self) -> np.ndarray:
        """max Re lambda at each state (NaN where not linearised), shape (N,)."""
        re = self.eigenvalues.real
        out = np.full(re.shape[0], np.nan)
        ok = ~np.isnan(re).any(axis=1) if re.shape[1] else np.zeros(re.shape[0], bool)
        if re.shape[1]:
            out[ok] = re[ok].max(axis=1)
        return out


def linearize_batch(model, states, parameters=None, *,
                    reference: "Linearization | ChartChoice",
                    families=None, step: float = STEP, generator=None,
                    build: bool = True) -> LinearizationBatch:
    """Linearise the constrained dynamics at N steady states in the reference's chart.

    Parameters
    ----------
    model : NumericModel
        Its kernels (its own parameter values are used where ``parameters`` is None).
    states : array_like, shape (N, 2n)
        The steady states (coordinates, then velocities, in the model's order); the
        chart's dependent coordinates and velocities are solved from the constraints
        first, from these values (:func:`~nhham.numerics.chart.lift`).
    parameters : array_like, shape (N, P), optional
        Every parameter's value at each state, in ``model.parameter_names`` order
        (inputs at their steady values); default: the model's at every state.
    reference : Linearization or ChartChoice
        A linearisation of the same family (same chart), or its :class:`ChartChoice`:
        its ``chart``, ``neutral`` and ``coordinates`` are used at every state.
    families : sequence of mappings, optional
        The steady family's tangents at each state (``{parameter: {name: derivative}}``),
        needed when the reference divided one out (a ``d/d<p>`` in its ``neutral``).
    step : float, optional
        The imaginary step.
    generator : nhham.numerics.relative.Generator, optional
        A symmetry the steady motions move along (a scene's checked ``[symmetry]``): each
        state's rate w from its velocities, "steady" meaning X = w Xi there, and the
        Jacobians those of X - w Xi, as :func:`~nhham.numerics.linearization.linearize`
        forms them; needed when the reference divided out its orbit or momentum.
    build : bool, optional
        Compile the complex kernels now (default: worth it for a study's thousands of
        states, not for one linearisation).

    Returns
    -------
    LinearizationBatch

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import ChartChoice, linearize_batch
    >>> from nhham.numerics.linearization import linearize
    >>> reference = ChartChoice.of(linearize(model, forward))
    >>> states = [model.state({**forward, "x_dot": u}) for u in (1.0, 2.0, -1.0)]
    >>> linearize_batch(model, states, reference=reference).eigenvalues.round(12).ravel()
    array([-1.+0.j, -2.+0.j,  1.+0.j])
    """
    Y = np.atleast_2d(np.asarray(states, dtype=float))
    N = Y.shape[0]
    P = (np.tile(np.asarray(model.parameter_values, dtype=float), (N, 1)) if parameters is None
         else np.atleast_2d(np.asarray(parameters, dtype=float)))
    chart = chart_of(model, reference.chart)
    steps = [s for s in reference.neutral if not is_axis(s)]
    kept = [s for s in reference.chart if s not in reference.neutral]
    columns = [reference.chart.index(s) for s in kept]
    divided = [s for s in steps if s.startswith("d/d")]
    if divided and families is None:
        raise ComputationError("linearize_batch: the reference divided out "
                               f"{', '.join(divided)}; give the families")
    if (ORBIT in steps or MOMENTUM in steps) and generator is None:
        raise ComputationError("linearize_batch: the reference divided out the [symmetry]'s "
                               "orbit or momentum; give the generator")
    cf = ComplexField(model, build=build)
    # the steady motion where the parameters moved it (a swept fork offset moves the
    # bicycle's upright pitch): dependent coordinates and velocities solved in the chart;
    # where that fails the state stays as given and is "not on M_1" below
    Y, _ = lift(cf, chart, Y, P)
    rates, lifted = (None, None) if generator is None else spin_rates(generator, Y, model.n, P)
    checked = check_states(cf, Y, P, rates, lifted)
    status = checked.status
    d = len(reference.coordinates)
    r = len(model.input_names)
    A = np.full((N, d, d), np.nan)
    B = np.full((N, d, r), np.nan)
    ok = np.flatnonzero(status == 0)
    if ok.size and columns:
        try:
            J = chart_jacobians(cf, chart, Y[ok], step, P[ok].T, columns=columns,
                                generator=generator,
                                rates=None if rates is None else rates[ok])
            Bfull = input_jacobians(cf, chart, Y[ok], step, model, P[ok].T)
        except (ComputationError, np.linalg.LinAlgError):
            J, Bfull = None, None
        if J is None:  # one singular state spoils the batch: the states one by one
            J, Bfull, bad = _one_by_one(cf, chart, Y[ok], P[ok], step, columns, model,
                                        generator, None if rates is None else rates[ok])
            status[ok[bad]] = 3
            ok, J, Bfull = ok[~bad], J[~bad], Bfull[~bad]
        Ak = J[:, columns, :]
        Bk = Bfull[:, columns, :]
        if steps:
            vectors = step_vectors(cf, chart, Y[ok], P[ok], step, kept, steps,
                                   [families[i] for i in ok] if divided else None,
                                   generator, None if lifted is None else lifted[ok])
            Ak, Bk, lost = _quotients(Ak, Bk, kept, steps, vectors, d)
            status[ok[lost]] = 3
            ok, Ak, Bk = ok[~lost], Ak[~lost], Bk[~lost]
        A[ok], B[ok] = Ak, Bk
    elif ok.size:
        A[ok] = np.zeros((ok.size, 0, 0))
    eig = np.full((N, d), np.nan + 0j)
    margins = np.full((N, d), np.nan)
    verdict = np.full(N, -1, dtype=np.int8)
    tol = np.full(N, np.nan)
    if ok.size:
        eig[ok], margins[ok], tol[ok], verdict[ok] = spectra(A[ok])
    return LinearizationBatch(tuple(reference.coordinates), A, eig, verdict, tol, status,
                              checked.constraint_residuals, checked.acceleration_residuals,
                              tuple(model.input_names), B, margins, checked.kkt_ratios)


def chart_of(model, names) -> Chart:
    """The Chart whose independent variables are ``names``."""
    n = model.n
    own = model.names
    iq = tuple(i for i in range(n) if own[i] in names)
    iv = tuple(i for i in range(n) if own[n + i] in names)
    return Chart(iq, tuple(i for i in range(n) if i not in iq), iv,
                 tuple(i for i in range(n) if i not in iv))


@dataclass(frozen=True)
class StateChecks:
    """Whether states are on M_1 and steady (:func:`check_states`).

    Attributes
    ----------
    status : ndarray of int8, shape (N,)
        0, 1 (not on M_1), 2 (not steady), 3 (singular), as :data:`STATUS_TEXT`.
    scaled : ndarray, shape (N, m + k)
        |phi_i| / (1 + |mu_i| |v| + |h_i|), |g_a| / (1 + |grad g_a| |q|).
    constraint_residuals : ndarray, shape (N,)
        Their largest.
    accelerations : ndarray, shape (N, n)
        The constrained accelerations (less w times the lift's: X - w Xi), NaN where not
        on M_1.
    acceleration_residuals : ndarray, shape (N,)
        ``max |a|``.
    kkt_ratios : ndarray, shape (N,)
    """

    status: np.ndarray
    scaled: np.ndarray
    constraint_residuals: np.ndarray
    accelerations: np.ndarray
    acceleration_residuals: np.ndarray
    kkt_ratios: np.ndarray


def check_states(cf, Y, P, rates=None, lifted=None) -> StateChecks:
    """Whether each state is on M_1 and steady, to the relative tolerance ON_TOLERANCE
    (residuals by their natural size; accelerations against max(1, max |y|)^2; with
    ``rates`` (N,) and ``lifted`` Xi (N, 2n): the accelerations less w times the lift's,
    X = w Xi). The one decision of a single linearisation and of a batch."""
    from nhham.numerics.nullspace import diagonal_ratio

    n, k = cf.n, cf.k
    N = Y.shape[0]
    Q, V = Y[:, :n], Y[:, n:]
    status = np.zeros(N, dtype=np.int8)
    W, F, mu, drift, h, g = (x.real for x in cf.pieces(Q, V, P))
    phi = np.einsum("kij,kj->ki", mu, V) + h
    mnorm = np.sqrt(np.sum(mu * mu, axis=-1))
    vnorm = np.linalg.norm(V, axis=1)[:, None]
    qnorm = np.linalg.norm(Q, axis=1)[:, None]
    scaled = np.concatenate([np.abs(phi) / (1.0 + mnorm * vnorm + np.abs(h)),
                             np.abs(g) / (1.0 + mnorm[:, :k] * qnorm)], axis=1)
    cres = scaled.max(axis=1, initial=0.0)
    status[~(cres <= ON_TOLERANCE)] = 1
    ares = np.full(N, np.nan)
    acc = np.full((N, n), np.nan)
    ratio = np.asarray(diagonal_ratio(W))
    on = np.flatnonzero(status == 0)
    if on.size:
        a, singular = _accelerations(W[on], F[on], mu[on], drift[on], n)
        if rates is not None:
            a = a - rates[on, None] * lifted[on, n:]
        acc[on] = a
        ares[on] = np.abs(a).max(axis=1, initial=0.0)
        scale = np.maximum(1.0, np.abs(Y[on]).max(axis=1))
        status[on[~(ares[on] <= ON_TOLERANCE * scale ** 2)]] = 2
        status[on[singular]] = 3
    return StateChecks(status, scaled, cres, acc, ares, np.atleast_1d(ratio))


def _accelerations(W, F, mu, drift, n):
    """(a, singular) of the saddle-point systems, one per state (the null-space solve,
    :func:`~nhham.numerics.nullspace.solve_null_space`)."""
    singular = np.zeros(W.shape[0], dtype=bool)
    with np.errstate(all="ignore"):
        try:
            a = solve_null_space(W, mu, F, -drift)[0]
        except np.linalg.LinAlgError:
            a = np.full(F.shape, np.nan)
            for i in range(W.shape[0]):
                try:
                    a[i] = solve_null_space(W[i], mu[i], F[i], -drift[i])[0]
                except np.linalg.LinAlgError:
                    singular[i] = True
    a[singular] = 0.0
    return a, singular


def _one_by_one(cf, chart, Y, P, step, columns, model, generator=None, rates=None):
    """The Jacobians state by state: (J, B, singular mask)."""
    d = len(chart.iq) + len(chart.iv)
    r = len(model.input_names)
    J = np.full((Y.shape[0], d, len(columns)), np.nan)
    B = np.full((Y.shape[0], d, r), np.nan)
    bad = np.zeros(Y.shape[0], dtype=bool)
    for i in range(Y.shape[0]):
        try:
            J[i] = chart_jacobians(cf, chart, Y[i:i + 1], step, P[i:i + 1].T, columns,
                                   generator, None if rates is None else rates[i:i + 1])[0]
            B[i] = input_jacobians(cf, chart, Y[i:i + 1], step, model, P[i:i + 1].T)[0]
        except (ComputationError, np.linalg.LinAlgError):
            bad[i] = True
    return J, B, bad


def step_vectors(cf, chart, Y, P, step, kept, steps, families=None, generator=None,
                 lifted=None) -> list:
    """The vectors of the non-axis neutral directions ``steps`` at each state, in the
    variables ``kept`` (:mod:`nhham.numerics.quotient`): one list of (label, vector or
    None) per state. ``orbit(xi)``: Xi(y) in the chart (``lifted`` (N, 2n)); ``d/d<p>``:
    ``families[i][p]``; ``level(J)``: dJ along M_1 in the chart (complex step through the
    lift, :func:`~nhham.numerics.chart.chart_gradients`), J the generator's momentum."""
    n = cf.n
    names = list(chart_names(cf, chart))
    where = [names.index(s) for s in kept]
    cols = list(chart.iq) + [n + i for i in chart.iv]
    orbit = None if lifted is None or ORBIT not in steps else lifted[:, cols][:, where]
    level = None
    if MOMENTUM in steps and generator is not None and generator.momentum is not None:
        level = chart_gradients(cf, chart, Y, step, P.T, generator.momentum, where)
    out = []
    for i in range(Y.shape[0]):
        row = []
        for label in steps:
            if label == ORBIT:
                row.append((label, None if orbit is None else orbit[i]))
            elif label == MOMENTUM:
                row.append((label, None if level is None else level[i]))
            else:
                tangent = (families[i] or {}).get(label[3:]) if families is not None else None
                row.append((label, None if tangent is None else
                            np.array([float(tangent.get(s, 0.0)) for s in kept])))
        out.append(row)
    return out


def chart_names(cf, chart) -> tuple:
    """The chart's variables' names (coordinates, then velocities)."""
    names = cf.names
    return (tuple(names[i] for i in chart.iq) + tuple(names[cf.n + i] for i in chart.iv))


def _quotients(A, B, names, steps, vectors, d):
    """Each state's quotient by the reference's steps (all required): (A, B, lost),
    ``lost`` where a step does not hold at that state (its rows are NaN: no matrix of
    the reference's size)."""
    outA = np.full((A.shape[0], d, d), np.nan)
    outB = np.full((A.shape[0], d, B.shape[2]), np.nan)
    lost = np.zeros(A.shape[0], dtype=bool)
    for i in range(A.shape[0]):
        done = divide(A[i], B[i], names, vectors[i], required=True)
        if done is None or done[0].shape[0] != d:
            lost[i] = True
            continue
        outA[i], outB[i] = done[0], done[1]
    return outA, outB, lost
