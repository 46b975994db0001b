"""A parameter swept through steady motions: the eigenvalues along the way and where
they cross the imaginary axis (the weave and capsize speeds of a bicycle).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from nhham.autonomy import require_autonomous
from nhham.errors import InputError
from nhham.numerics.crossings import crossings
from nhham.numerics.linearization import Linearization, linearize

__all__ = ["Sweep", "steady_state", "sweep", "sweep_steady", "sweep_batches",
           "common_reference", "probe_values", "check_swept", "with_steady_inputs"]


@dataclass(frozen=True)
class Sweep:
    """Eigenvalues of the linearisation along a parameter.

    Attributes
    ----------
    parameter : str
    values : ndarray, shape (N,)
    eigenvalues : tuple of ndarray
        One array of complex eigenvalues per value (sorted as in
        :class:`Linearization`).
    stable : tuple of bool or None
    crossings : tuple of Crossing
        Located by :func:`~nhham.numerics.crossings.crossings`.
    coordinates : tuple of str
        The variables of the state matrices.
    unlocated : tuple of Unlocated
        Intervals where the number of unstable eigenvalues changes but no eigenvalue
        could be put on the imaginary axis (each with its reason).

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import sweep_steady
    >>> swept = sweep_steady(model, lambda parameters: forward, "a", [0.25, 0.5, 1.0])
    >>> swept.coordinates, [e.round(12) for e in swept.eigenvalues]
    (('theta_dot',), [array([-1.6+0.j]), array([-2.+0.j]), array([-1.6+0.j])])
    """

    parameter: str
    values: np.ndarray
    eigenvalues: tuple
    stable: tuple
    crossings: tuple
    coordinates: tuple
    unlocated: tuple = ()

    def to_dict(self) -> dict:
        """``parameter``, ``values``, ``eigenvalues`` (lists of [re, im]), ``crossings``."""
        return {
            "parameter": self.parameter,
            "values": [float(v) for v in self.values],
            "eigenvalues": [[[float(z.real), float(z.imag)] for z in ev] for ev in self.eigenvalues],
            "stable_at": list(self.stable),
            "crossings": [{"value": c.value, "kind": c.kind,
                           "eigenvalue": [c.eigenvalue.real, c.eigenvalue.imag],
                           "direction": c.direction} for c in self.crossings],
            "unlocated_crossings": [{"low": u.low, "high": u.high, "reason": u.reason}
                                    for u in self.unlocated],
            "coordinates": list(self.coordinates),
        }


def sweep(linearize_at: Callable[[float], Linearization], parameter: str,
          values: Sequence[float] | np.ndarray, *, xtol: float = 1e-12,
          linearize_all: Callable[[Sequence[float]], list] | None = None) -> Sweep:
    """Eigenvalues along a parameter, with the crossings of the imaginary axis.

    Parameters
    ----------
    linearize_at : callable
        ``value -> Linearization`` (the caller moves the steady state and the
        parameter together; the same chart at every value).
    parameter : str
    values : sequence of float
        Increasing values.
    xtol : float, optional
        Absolute tolerance of the located crossings.
    linearize_all : callable, optional
        ``values -> [Linearization]`` at once (one batch), the same as
        ``linearize_at`` at each; ``linearize_at`` then only locates the crossings.

    Returns
    -------
    Sweep
        Crossings are where the number of eigenvalues with positive real part changes
        between consecutive values, located by
        :func:`~nhham.numerics.crossings.crossings` (an eigenvalue on the imaginary axis
        at every reported value).
    """
    grid = np.asarray(values, dtype=float)
    lins = (list(linearize_all([float(v) for v in grid])) if linearize_all is not None
            else [linearize_at(float(v)) for v in grid])
    coords = lins[0].coordinates if lins else ()
    found = crossings(linearize_at, grid, lins, xtol=xtol)
    return Sweep(parameter, grid, tuple(lin.eigenvalues for lin in lins),
                 tuple(lin.stable for lin in lins), found.crossings[0], tuple(coords),
                 found.unlocated[0])


def with_steady_inputs(model, values: Mapping[str, float]) -> tuple:
    """(model, state): the inputs' steady values of ``values`` (a scene's ``[steady]``
    gives one for every input) set in the model, its coordinates and velocities the
    state (an input that a control law replaced is not the model's: its entry is not
    used)."""
    inputs = {u: values[u] for u in model.input_names if u in values}
    names = set(model.names)
    state = {k: v for k, v in values.items() if k in names}
    return (model.with_parameters(**inputs) if inputs else model), state


def steady_state(model, values: Mapping[str, float], independent=None, *,
                 warn: bool = True) -> tuple:
    """(model, state): :func:`with_steady_inputs`, with the state moved onto M_1.

    A ``[steady]`` table is written for the scene's parameter values; at others (a
    swept fork offset moves the bicycle's upright pitch) the chart's dependent
    coordinates are solved from the holonomic constraints by Newton's method from the
    table's values and the dependent velocities from the velocity constraints, the
    independent entries held (:func:`~nhham.numerics.chart.lift`).

    Parameters
    ----------
    model : NumericModel
    values : mapping
        The table's values at the model's parameters.
    independent : sequence of str, optional
        The chart (default: chosen at the table's state).
    warn : bool, optional
        Warn (:class:`~nhham.errors.NhhamWarning`) naming every entry that moved by more
        than 1e-9 (relative).

    Raises
    ------
    InputError
        No state of M_1 near the table's (key ``steady``).
    """
    import warnings

    from nhham.errors import NhhamWarning
    from nhham.numerics.chart import ComplexField, choose_chart, lift

    model, state = with_steady_inputs(model, values)
    # a steady motion of a system with t in L or the constraints: refused before the lift
    # evaluates them (at t = 0, where 1/t is a ZeroDivisionError in the generated code)
    require_autonomous("linearize_geometry", model.time_in_geometry, key=model.timed_key)
    names = model.names
    y = np.array([float(state[s]) for s in names])
    chart = choose_chart(model, y, independent)
    Y, ok = lift(ComplexField(model), chart, y[None, :])
    if not ok[0]:
        dependent = [names[i] for i in chart.dq] + [names[model.n + i] for i in chart.dv]
        raise InputError(f"[steady]: no state of M_1 near the table's at these parameter "
                         f"values (solving {', '.join(dependent)} from the constraints "
                         f"failed)", key="steady")
    moved = [i for i in range(len(y)) if abs(Y[0, i] - y[i]) > 1e-9 * max(1.0, abs(y[i]))]
    if moved and warn:
        warnings.warn("[steady]: " + ", ".join(f"{names[i]} = {Y[0, i]:.12g} (given "
                                              f"{y[i]:.12g})" for i in moved)
                      + " solved from the constraints at these parameter values",
                      NhhamWarning, stacklevel=2)
    return model, dict(zip(names, (float(v) for v in Y[0])))


def sweep_steady(model, state_of: Callable[[Mapping[str, float]], Mapping[str, float]],
                 parameter: str, values: Sequence[float] | np.ndarray, *, independent=None,
                 xtol: float = 1e-12, family_of=None, generator=None) -> Sweep:
    """:func:`sweep` of a steady motion that moves with a parameter: the chart and the
    neutral directions decided at the first, middle and last values
    (:func:`common_reference`), every value then linearised in one batch
    (:func:`~nhham.numerics.batch_linearization.linearize_batch`), as a study does.

    Parameters
    ----------
    model : NumericModel
    state_of : callable
        ``{parameter name: value} -> {state name: value}``, e.g. the
        ``values`` method of a scene's :class:`~nhham.system.steady.SteadyState`.
    parameter : str
        A parameter of the model.
    values : sequence of float
    independent : sequence of str, optional
        As for :func:`linearize`; default: the chart chosen at the first value,
        kept for every value (with the neutral directions found there).
    xtol : float, optional
    family_of : callable, optional
        ``{parameter: value} -> family`` (see :func:`linearize`).
    generator : nhham.numerics.relative.Generator, optional
        A symmetry the steady motions move along (see :func:`linearize`): each value
        linearised in co-moving variables at its own rate w.

    Returns
    -------
    Sweep

    Examples
    --------
    >>> from nhham import models, numeric_model
    >>> model = numeric_model(models.chaplygin_sleigh(), backend="numpy")
    >>> forward = dict(x=0.0, y=0.0, theta=0.0, x_dot=2.0, y_dot=0.0, theta_dot=0.0)
    >>> from nhham import sweep_steady
    >>> swept = sweep_steady(model, lambda parameters: forward, "a", [-0.5, -0.25, 0.25, 0.5])
    >>> swept.stable                     # -m a u / (I + m a**2) changes sign at a = 0
    (False, False, True, True)
    >>> [(c.value, c.kind) for c in swept.crossings]
    [(0.0, 'real')]
    """
    from nhham.numerics.batch_linearization import linearize_batch

    check_swept(model, parameter)
    grid = np.asarray(values, dtype=float)
    if grid.size == 0:
        raise InputError(f"--sweep: no values of {parameter!r} to sweep", key="--sweep")

    def model_and_state(value, chart=independent):
        m = model.with_parameters(**{parameter: value})
        try:
            return steady_state(m, state_of(m.parameters), chart, warn=False)
        except InputError as exc:
            raise InputError(f"{exc} ({parameter} = {value:g})", key=exc.key) from None

    def fam(value):
        return None if family_of is None else family_of(
            model.with_parameters(**{parameter: value}).parameters)

    probes = probe_values(grid)
    first = linearize(*model_and_state(probes[0]), independent=independent,
                      family=fam(probes[0]), generator=generator)
    lins = [first] + [linearize(*model_and_state(v, first.chart), independent=first.chart,
                                family=fam(v), generator=generator) for v in probes[1:]]
    choice = common_reference(lins, lambda neutral, keep: linearize(
        *model_and_state(probes[0], first.chart), independent=first.chart, neutral=neutral,
        family={p: t for p, t in (fam(probes[0]) or {}).items() if p in keep} or None,
        generator=generator))

    def batch_at(vals):
        pairs = [model_and_state(v, choice.chart) for v in vals]
        Y = np.array([m.state(st) for m, st in pairs])
        P = np.array([m.parameter_values for m, _ in pairs], dtype=float)
        return linearize_batch(model, Y, P, reference=choice, families=[fam(v) for v in vals],
                               generator=generator, build=False)

    return sweep_batches(parameter, grid, batch_at, choice.coordinates, xtol=xtol)


def check_swept(model, parameter: str) -> None:
    """Refuse an input or a name that is not a parameter (key ``--sweep``)."""
    if parameter in model.input_names:
        raise InputError(f"--sweep: {parameter!r} is an input, whose steady value the "
                         f"[steady] table gives; sweep a parameter that its entry uses (e.g. "
                         f"u = \"u0\" in [steady], then --sweep u0=...)", key="--sweep")
    if parameter not in model.parameter_names:
        raise InputError(f"--sweep: {parameter!r} is not a parameter of the scene "
                         f"(parameters: {', '.join(model.parameter_names) or 'none'})",
                         key="--sweep")


def probe_values(values) -> list:
    """Where a sweep's (or a study's line's) reference is decided: the first, middle and
    last values."""
    grid = np.asarray(values, dtype=float).ravel()
    return [float(grid[i]) for i in sorted({0, grid.size // 2, grid.size - 1})]


def common_reference(probes: Sequence, relinearize: Callable):
    """One chart and one set of neutral directions for a family of steady motions: the
    first probe's chart and the directions neutral at every probe (a direction can be
    neutral at an isolated value only: the yaw rate of a disc at rest, the speed of a
    sleigh with drag at U = 0).

    Parameters
    ----------
    probes : sequence of Linearization
        At the probe values, in the first's chart.
    relinearize : callable
        ``(neutral labels, family parameters kept) -> Linearization`` at the first probe,
        called when the first divided out more than the others.

    Returns
    -------
    ChartChoice
    """
    from nhham.numerics.batch_linearization import ChartChoice

    from nhham.numerics.quotient import is_axis

    first = probes[0]
    labels = list(dict.fromkeys(s for lin in probes for s in (*lin.neutral, *lin.implied)))
    # a chart variable neutral at every probe; another direction divided out or implied
    # by the variables removed at every probe, and divided out at one
    common = [s for s in labels if all(s in lin.neutral or (not is_axis(s) and s in lin.implied)
                                       for lin in probes)
              and (is_axis(s) or any(s in lin.neutral for lin in probes))]
    if common != list(first.neutral):
        first = relinearize(common, {s[3:] for s in common if s.startswith("d/d")})
    return ChartChoice.of(first)


def sweep_batches(parameter: str, values, batch_at: Callable, coordinates, *,
                  xtol: float = 1e-12) -> Sweep:
    """The eigenvalues along ``values`` and the crossings between them, every spectrum
    from ``batch_at(values) -> LinearizationBatch`` (the grid in one batch, then the
    values the crossing finder asks for, a batch per round).

    Raises
    ------
    InputError
        (key ``steady``) a grid value where the steady motion has no linearisation.
    """
    from nhham.numerics.batch_linearization import STATUS_TEXT
    from nhham.numerics.crossings import CrossingFinder

    grid = np.asarray(values, dtype=float)
    batch = batch_at(grid)
    failed = np.flatnonzero(batch.status != 0)
    if failed.size:
        i = int(failed[0])
        why = {1: "no state of M_1 near the table's at these parameter values (the "
                  "dependent coordinates and velocities not solved from the constraints, "
                  "or an entry not a finite number)",
               2: "the motion is not steady at these parameter values (or a [control] law "
                  "does not give its input's [steady] value)"}.get(
                      int(batch.status[i]), STATUS_TEXT.get(int(batch.status[i]), ""))
        raise InputError(f"[steady]: {why} ({parameter} = {grid[i]:g})", key="steady")
    spectra = [batch.spectrum(i) for i in range(grid.size)]
    finder = CrossingFinder([(grid, spectra)], xtol=xtol,
                            counts=[batch.unstable_counts.tolist()])
    while finder.requests:
        more = batch_at(np.array([x for _, x in finder.requests]))
        finder.supply([more.spectrum(i) for i in range(more.status.size)])
    found = finder.result()
    stable = tuple({1: True, 0: False}.get(int(v)) for v in batch.verdicts)
    return Sweep(parameter, grid, tuple(batch.eigenvalues), stable, found.crossings[0],
                 tuple(coordinates), found.unlocated[0])
