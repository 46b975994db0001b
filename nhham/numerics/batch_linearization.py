"""Linearisations at many steady states at once: the fast path of parameter studies.

:func:`~nhham.numerics.linearization.linearize` decides the chart and the neutral
directions at each state and checks them (the Jacobian in every chart variable, and
again along the motion). A study evaluates thousands of states of one family, so
:func:`linearize_batch` takes those decisions from a *reference* linearisation (made at
probe states by the caller) and computes, for all states in one batch of the generated
kernel, only what changes from state to state:

- whether the state is on M_1 and steady (scaled residuals and the largest
  acceleration, as ``linearize`` checks them), as a status per state instead of an
  exception;
- the complex-step Jacobian columns of the kept variables only (the reference's
  ``coordinates``, before any tangent of the steady family is divided out), so the
  bicycle needs 4 columns per state instead of the 2 x 10 of ``linearize``;
- the eigenvalues (LAPACK, batched) and the verdict with ``linearize``'s tolerance.

The neutral directions are the reference's: the caller checks them at its probes (a
column zero at one state of a smooth family is zero at its neighbours only generically).
No sympy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nhham.errors import ComputationError
from nhham.numerics.chart import (Chart, ComplexField, chart_jacobians, input_jacobians,
                                  lift)
from nhham.numerics.linearization import (EIGENVALUE_TOLERANCE, ON_TOLERANCE, STEP,
                                          Linearization, divide_family)
from nhham.numerics.relative import spin_rates
from nhham.numerics.saddle import solve_saddle

__all__ = ["ChartChoice", "LinearizationBatch", "Spectrum", "linearize_batch", "STATUS_TEXT"]

#: Status of a state (``LinearizationBatch.status``): what each code means.
STATUS_TEXT = {0: "linearised", 1: "not on M_1", 2: "not steady",
               3: "singular (the saddle-point matrix or a constraint at the state)"}


@dataclass(frozen=True)
class ChartChoice:
    """What a batch takes from its reference linearisation (plain data: it crosses
    process boundaries).

    Attributes
    ----------
    chart : tuple of str
        The independent coordinates and velocities.
    neutral : tuple of str
        Chart variables removed (and ``d/d<p>`` tangents divided out).
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
    def of(cls, lin: Linearization) -> "ChartChoice":
        return cls(tuple(lin.chart), tuple(lin.neutral), tuple(lin.coordinates))


@dataclass(frozen=True)
class Spectrum:
    """Eigenvalues and the tolerance of their verdict (what locating a crossing reads)."""

    eigenvalues: np.ndarray
    tolerance: float


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
        1 asymptotically stable (every Re < -tol), 0 unstable (some Re > tol), -1 not
        decided by linearisation (or not linearised).
    tolerances : ndarray, shape (N,)
        ``|Re| <=`` this counts as 0 (``1e-9 max(1, max |A|)``, as ``linearize``).
    status : ndarray of int8, shape (N,)
        0 linearised; 1 not on M_1; 2 not steady; 3 singular (:data:`STATUS_TEXT`).
    constraint_residuals : ndarray, shape (N,)
        The largest scaled constraint residual at each state.
    acceleration_residuals : ndarray, shape (N,)
        ``max |a|`` at each state (0 for a steady motion).
    inputs : tuple of str
    input_matrices : ndarray, shape (N, d, len(inputs))
        B of x' = A x + B u.

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

    @property
    def stable(self) -> np.ndarray:
        """Boolean (N,): asymptotically stable."""
        return self.verdicts == 1

    def spectrum(self, i: int) -> Spectrum | None:
        """The eigenvalues of state ``i`` with their tolerance (None: not linearised)."""
        if self.status[i] != 0:
            return None
        return Spectrum(self.eigenvalues[i], float(self.tolerances[i]))

    @property
    def spectral_abscissa(self) -> np.ndarray:
        """max Re lambda at each state (NaN where not linearised), shape (N,)."""
        re = self.eigenvalues.real
        out = np.full(re.shape[0], np.nan)
        ok = ~np.isnan(re).any(axis=1) if re.shape[1] else np.zeros(re.shape[0], bool)
        if re.shape[1]:
            out[ok] = re[ok].max(axis=1)
        return out


def linearize_batch(model, states, parameters=None, *, reference: Linearization | ChartChoice,
                    families=None, step: float = STEP, generator=None) -> LinearizationBatch:
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
        forms them.

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
    chart = _chart(model, reference.chart)
    kept = [s for s in reference.chart if s not in reference.neutral]
    columns = [reference.chart.index(s) for s in kept]
    divided = [s for s in reference.neutral if s.startswith("d/d")]
    if divided and families is None:
        raise ComputationError("linearize_batch: the reference divided out "
                               f"{', '.join(divided)}; give the families")
    cf = ComplexField(model, build=True)   # a study's thousands of states
    # the steady motion where the parameters moved it (a swept fork offset moves the
    # bicycle's upright pitch): dependent coordinates and velocities solved in the chart;
    # where that fails the state stays as given and is "not on M_1" below
    Y, _ = lift(cf, chart, Y, P)
    rates, lifted = (None, None) if generator is None else spin_rates(generator, Y, model.n, P)
    status, cres, ares = _check_states(cf, Y, P, model, rates, lifted)
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
        if divided:
            Ak, Bk, lost = _divide(Ak, Bk, kept, [families[i] for i in ok], divided)
            status[ok[lost]] = 3
            ok, Ak, Bk = ok[~lost], Ak[~lost], Bk[~lost]
        A[ok], B[ok] = Ak, Bk
    elif ok.size:
        A[ok] = np.zeros((ok.size, 0, 0))
    eig, verdict, tol = _spectra(A, ok)
    return LinearizationBatch(tuple(reference.coordinates), A, eig, verdict, tol, status,
                              cres, ares, tuple(model.input_names), B)


def _chart(model, names) -> Chart:
    """The Chart whose independent variables are ``names``."""
    n = model.n
    own = model.names
    iq = tuple(i for i in range(n) if own[i] in names)
    iv = tuple(i for i in range(n) if own[n + i] in names)
    return Chart(iq, tuple(i for i in range(n) if i not in iq), iv,
                 tuple(i for i in range(n) if i not in iv))


def _check_states(cf, Y, P, model, rates=None, lifted=None):
    """(status, scaled constraint residual, max |a|) at each state, as ``linearize``
    decides "on M_1" and "steady" (relative tolerance ON_TOLERANCE; with ``rates``: the
    accelerations less w times the lift's, X = w Xi)."""
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
    on = np.flatnonzero(status == 0)
    if on.size:
        a, singular = _accelerations(W[on], F[on], mu[on], drift[on], n)
        if rates is not None:
            a = a - rates[on, None] * lifted[on, n:]
        ares[on] = np.abs(a).max(axis=1, initial=0.0)
        scale = np.maximum(1.0, np.abs(Y[on]).max(axis=1))
        status[on[~(ares[on] <= ON_TOLERANCE * scale ** 2)]] = 2
        status[on[singular]] = 3
    return status, cres, ares


def _accelerations(W, F, mu, drift, n):
    """(a, singular) of the saddle-point systems, one per state (the solve of
    :func:`~nhham.numerics.saddle.solve_saddle`: its one decision between the saddle and
    the null-space solve)."""
    singular = np.zeros(W.shape[0], dtype=bool)
    with np.errstate(all="ignore"):
        try:
            a = solve_saddle(W, mu, F, -drift)[0]
        except np.linalg.LinAlgError:
            a = np.full(F.shape, np.nan)
            for i in range(W.shape[0]):
                try:
                    a[i] = solve_saddle(W[i], mu[i], F[i], -drift[i])[0]
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


def _divide(A, B, names, families, divided):
    """Each state's tangents of the steady family divided out, as ``linearize`` does:
    (A, B, lost), ``lost`` where a tangent is not in that state's kernel of A (its rows
    are NaN: no matrix of the reference's size)."""
    wanted = {s[3:] for s in divided}
    d = A.shape[1] - len(divided)
    outA = np.full((A.shape[0], d, d), np.nan)
    outB = np.full((A.shape[0], d, B.shape[2]), np.nan)
    lost = np.zeros(A.shape[0], dtype=bool)
    for i, (Ai, Bi, fam) in enumerate(zip(A, B, families)):
        fam = {p: t for p, t in (fam or {}).items() if p in wanted}
        Ai, _, removed, Bi = divide_family(Ai, list(names), fam, Bi)
        if len(removed) != len(divided):
            lost[i] = True
            continue
        outA[i], outB[i] = Ai, Bi
    return outA, outB, lost


def _spectra(A, ok):
    """(eigenvalues sorted, verdicts, tolerances) of the state matrices ``A[ok]``."""
    N, d = A.shape[0], A.shape[1]
    eig = np.full((N, d), np.nan + 0j)
    verdict = np.full(N, -1, dtype=np.int8)
    tol = np.full(N, np.nan)
    if not ok.size:
        return eig, verdict, tol
    Ak = A[ok]
    tol[ok] = EIGENVALUE_TOLERANCE * np.maximum(1.0, np.abs(Ak).max(axis=(1, 2), initial=0.0))
    if not d:
        return eig, verdict, tol
    ev = np.linalg.eigvals(Ak)
    order = np.lexsort((-ev.imag, -np.round(ev.real, 12)), axis=-1)
    ev = np.take_along_axis(ev, order, axis=-1)
    eig[ok] = ev
    top = ev.real.max(axis=1)
    v = np.full(ok.size, -1, dtype=np.int8)
    v[top < -tol[ok]] = 1
    v[top > tol[ok]] = 0
    verdict[ok] = v
    return eig, verdict, tol
