"""A parameter swept through steady motions: the eigenvalues along the way and where
they cross the imaginary axis (the weave and capsize speeds of a bicycle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from nhham.errors import InputError
from nhham.numerics.linearization import Linearization, linearize, linearize_many

__all__ = ["Crossing", "Sweep", "crossings", "crossings_many", "sweep", "sweep_steady",
           "with_steady_inputs"]


@dataclass(frozen=True)
class Crossing:
    """A parameter value where an eigenvalue's real part changes sign.

    Attributes
    ----------
    value : float
        Located by Brent's method on the real part of the crossing branch.
    kind : {"real", "complex"}
        A real eigenvalue through 0, or a complex pair through the imaginary axis.
    eigenvalue : complex
        The crossing eigenvalue at ``value`` (real part ~ 0).
    direction : int
        +1 when the real part becomes positive with increasing parameter.
    """

    value: float
    kind: str
    eigenvalue: complex
    direction: int


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
    coordinates : tuple of str
        The variables of the state matrices.
    """

    parameter: str
    values: np.ndarray
    eigenvalues: tuple
    stable: tuple
    crossings: tuple
    coordinates: tuple

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
            "coordinates": list(self.coordinates),
        }


def sweep(linearize_at: Callable[[float], Linearization], parameter: str,
          values: Sequence[float], *, xtol: float = 1e-12,
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
        Crossings are where the number of eigenvalues with positive real
        part changes between consecutive values; each is located by Brent's
        method on the real part of the crossing branch: the real eigenvalue
        nearest to 0 ("real") or the complex eigenvalue of smallest |Re|
        ("complex"), after bisecting on the count until one of them brackets.
    """
    values = np.asarray(values, dtype=float)
    lins = (list(linearize_all([float(v) for v in values])) if linearize_all is not None
            else [linearize_at(float(v)) for v in values])
    coords = lins[0].coordinates if lins else ()
    return Sweep(parameter, values, tuple(lin.eigenvalues for lin in lins),
                 tuple(lin.stable for lin in lins),
                 tuple(crossings(linearize_at, values, lins, xtol=xtol)), tuple(coords))


def crossings(linearize_at: Callable, values: Sequence[float], spectra: Sequence, *,
              xtol: float = 1e-12) -> list:
    """Where an eigenvalue crosses the imaginary axis between consecutive values.

    Parameters
    ----------
    linearize_at : callable
        ``value -> spectrum``, called to locate each crossing.
    values : sequence of float
        Increasing.
    spectra : sequence
        At each value, an object with ``eigenvalues`` (complex array) and ``tolerance``
        (a real part at or below it counts as 0), e.g. a :class:`Linearization`; None
        where there is none (such a value bounds no interval).
    xtol : float, optional

    Returns
    -------
    list of Crossing
        One or more per interval where the number of eigenvalues with positive real part
        changes (see :func:`sweep`).
    """
    found = []
    counts = [None if s is None else _n_positive(s) for s in spectra]
    for i in range(len(values) - 1):
        if None not in (counts[i], counts[i + 1]) and counts[i] != counts[i + 1]:
            found.extend(_locate(linearize_at, values[i], values[i + 1], spectra[i],
                                 spectra[i + 1], xtol))
    return found


def crossings_many(spectra_at: Callable, lines: Sequence, *, xtol: float = 1e-12,
                   maxiter: int = 200, counts: Sequence | None = None) -> list:
    """:func:`crossings` on many lines at once, the root finding batched across them.

    Parameters
    ----------
    spectra_at : callable
        ``[(line index, value), ...] -> [spectrum or None, ...]``: the spectra at many
        points in one call (one batch of the generated kernels).
    lines : sequence of (values, spectra)
        Each line's increasing values and the spectra there (as for :func:`crossings`;
        any sequence: only the ends of the intervals where the count changes are read).
    xtol : float, optional
    maxiter : int, optional
    counts : sequence of sequences of int, optional
        Per line, the number of eigenvalues with real part above the tolerance at each
        value (-1 where there is no spectrum), when the caller has them (computed for the
        whole batch at once); default: counted here from the spectra.

    Returns
    -------
    list of list of Crossing
        Per line, as :func:`crossings` gives them. Each crossing whose eigenvalue branch
        is found at both ends is located by the Illinois variant of regula falsi (a
        superlinear bracketing method), all lines' brackets advanced together; the others
        by :func:`crossings`' own search, one by one.
    """
    out: list = [[] for _ in lines]
    brackets = []     # [line, a, b, fa, fb, za, zb, kind, side]
    for k, (values, spectra) in enumerate(lines):
        line = ([None if s is None else _n_positive(s) for s in spectra] if counts is None
                else [None if c < 0 else c for c in counts[k]])
        for i in range(len(values) - 1):
            if None in (line[i], line[i + 1]) or line[i] == line[i + 1]:
                continue
            pairs = [(kind, *_same_branch(spectra[i], spectra[i + 1], kind, at_end=True))
                     for kind in ("real", "complex")]
            pairs = [p for p in pairs if p[1] is not None]
            if not pairs:
                out[k].extend(_locate(lambda v, k=k: spectra_at([(k, v)])[0], values[i],
                                      values[i + 1], spectra[i], spectra[i + 1], xtol))
                continue
            for kind, za, zb in pairs:
                # a real part 0 to the tolerance at an end: that end is the crossing
                fa = 0.0 if abs(za.real) <= spectra[i].tolerance else za.real
                fb = 0.0 if abs(zb.real) <= spectra[i + 1].tolerance else zb.real
                brackets.append([k, float(values[i]), float(values[i + 1]), fa, fb,
                                 za, zb, kind, 0, float(values[i]), float(values[i + 1])])
    for _ in range(maxiter):
        active = [b for b in brackets if b[2] - b[1] > xtol + 4 * np.finfo(float).eps *
                  max(abs(b[1]), abs(b[2])) and b[3] != 0 and b[4] != 0]
        if not active:
            break
        points = []
        for b in active:
            _, a, c, fa, fc = b[:5]
            x = c - fc * (c - a) / (fc - fa)
            if not a < x < c:
                x = 0.5 * (a + c)
            points.append(x)
        spectra = spectra_at([(b[0], x) for b, x in zip(active, points)])
        for b, x, s in zip(active, points, spectra):
            k, a0, c0 = b[0], b[9], b[10]
            z = _branch(s, b[7], b[5] + (b[6] - b[5]) * (x - a0) / (c0 - a0))
            if z is None:   # no spectrum there: located one by one below
                b[8] = None
                b[3] = b[4] = 0.0
                continue
            fx = z.real
            if fx == 0:
                b[1] = b[2] = x
                b[3] = b[4] = 0.0
            elif np.sign(fx) == np.sign(b[3]):
                b[1], b[3] = x, fx
                if b[8] == 1:       # Illinois: the other end kept twice, halve its value
                    b[4] /= 2
                b[8] = 1
            else:
                b[2], b[4] = x, fx
                if b[8] == -1:
                    b[3] /= 2
                b[8] = -1
    located = []
    for b in brackets:
        k, a, c, fa, fc = b[:5]
        a0, c0 = b[9], b[10]
        if b[8] is None:
            values, spectra = lines[k]
            i = list(values).index(a0)
            out[k].extend(c for c in _locate(lambda v, k=k: spectra_at([(k, v)])[0], a0, c0,
                                             spectra[i], spectra[i + 1], xtol)
                          if c.kind == b[7])
            continue
        located.append((b, a if fa == 0 else c if fc == 0 else (a if abs(fa) < abs(fc) else c)))
    # the crossing eigenvalues at the roots, in one batch
    for (b, root), s in zip(located, spectra_at([(b[0], root) for b, root in located])
                            if located else []):
        a0, c0 = b[9], b[10]
        z = _branch(s, b[7], b[5] + (b[6] - b[5]) * (root - a0) / (c0 - a0))
        if z is None:
            continue
        out[b[0]].append(Crossing(float(root), b[7], complex(z), 1 if b[6].real > b[5].real
                                  else -1))
    for found in out:
        found.sort(key=lambda c: c.value)
    return out


def _n_positive(lin):
    return int(np.sum(lin.eigenvalues.real > lin.tolerance))


def _branch(lin, kind, target=None):
    """The eigenvalue of ``kind`` nearest to ``target``; without a target, the one
    of smallest |Re| among those with |Re| above the tolerance (a structural zero
    eigenvalue is no branch). None where there is no linearisation (``lin`` None)."""
    if lin is None:
        return None
    ev = lin.eigenvalues
    pick = ev[ev.imag == 0] if kind == "real" else ev[ev.imag > 0]
    if target is None:
        pick = pick[np.abs(pick.real) > lin.tolerance]
        if not pick.size:
            return None
        return pick[np.argmin(np.abs(pick.real))]
    if not pick.size:
        return None
    return pick[np.argmin(np.abs(pick - target))]


def _same_branch(lin_a, lin_b, kind, at_end=False):
    """Eigenvalues of one branch at both ends whose real parts differ in sign, or (None, None).

    The branch is followed from the end where it is nearest to the imaginary
    axis (a structural zero excluded) to the nearest eigenvalue at the other end.
    ``at_end``: also a branch whose real part is 0 to the tolerance at one end (and
    clearly not at the other): the crossing is that end (a grid value hit it).
    """
    za0, zb0 = _branch(lin_a, kind), _branch(lin_b, kind)
    pairs = []
    if za0 is not None:
        pairs.append((za0, _branch(lin_b, kind, za0)))
    if zb0 is not None:
        pairs.append((_branch(lin_a, kind, zb0), zb0))
    for za, zb in pairs:
        if (za is not None and zb is not None and za.real * zb.real < 0
                and abs(za.real) > lin_a.tolerance and abs(zb.real) > lin_b.tolerance):
            return za, zb
    if not at_end:
        return None, None
    for lin, other in ((lin_a, lin_b), (lin_b, lin_a)):   # the branch through 0 at an end
        ev = lin.eigenvalues
        pick = ev[ev.imag == 0] if kind == "real" else ev[ev.imag > 0]
        zero = pick[np.abs(pick.real) <= lin.tolerance]
        if zero.size:
            z0 = zero[0]
            z1 = _branch(other, kind, z0)
            if z1 is not None and abs(z1.real) > other.tolerance:
                return (z0, z1) if lin is lin_a else (z1, z0)
    return None, None


def _locate(linearize_at, a, b, lin_a, lin_b, xtol):
    from scipy.optimize import brentq

    found = []
    for _ in range(60):
        for kind in ("real", "complex"):
            za, zb = _same_branch(lin_a, lin_b, kind)
            if za is None:
                continue

            def f(p, kind=kind, a=a, b=b, za=za, zb=zb):
                z = _branch(linearize_at(p), kind, za + (zb - za) * (p - a) / (b - a))
                return math.nan if z is None else z.real

            try:
                root = brentq(f, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps)
            except ValueError:
                continue
            z = _branch(linearize_at(root), kind, za + (zb - za) * (root - a) / (b - a))
            if z is None:
                continue
            found.append(Crossing(float(root), kind, complex(z), 1 if zb.real > za.real else -1))
        if found:
            return found
        if b - a <= xtol:
            break
        mid = 0.5 * (a + b)
        lin_m = linearize_at(mid)
        if lin_m is None:   # no linearisation there: the interval is all that is known
            break
        if _n_positive(lin_m) != _n_positive(lin_a):
            b, lin_b = mid, lin_m
        else:
            a, lin_a = mid, lin_m
    kind = "real" if abs(_n_positive(lin_a) - _n_positive(lin_b)) % 2 else "complex"
    z = _branch(lin_b, kind)
    return [Crossing(float(0.5 * (a + b)), kind, complex(z if z is not None else 0),
                     1 if _n_positive(lin_b) > _n_positive(lin_a) else -1)]


def with_steady_inputs(model, values: Mapping[str, float]) -> tuple:
    """(model, state): the inputs' steady values of ``values`` (a scene's ``[steady]``
    gives one for every input) set in the model, its coordinates and velocities the
    state (an input that a control law replaced is not the model's: its entry is not
    used)."""
    inputs = {u: values[u] for u in model.input_names if u in values}
    names = set(model.names)
    state = {k: v for k, v in values.items() if k in names}
    return (model.with_parameters(**inputs) if inputs else model), state


def sweep_steady(model, state_of: Callable[[Mapping[str, float]], Mapping[str, float]],
                 parameter: str, values: Sequence[float], *, independent=None,
                 xtol: float = 1e-12, family_of=None) -> Sweep:
    """:func:`sweep` of a steady motion that moves with a parameter.

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

    Returns
    -------
    Sweep
    """
    if parameter in model.input_names:
        raise InputError(f"--sweep: {parameter!r} is an input, whose steady value the "
                         f"[steady] table gives; sweep a parameter that its entry uses (e.g. "
                         f"u = \"u0\" in [steady], then --sweep u0=...)", key="--sweep")
    if parameter not in model.parameter_names:
        raise InputError(f"--sweep: {parameter!r} is not a parameter of the scene "
                         f"(parameters: {', '.join(model.parameter_names) or 'none'})")
    def model_and_state(value):
        m = model.with_parameters(**{parameter: value})
        return with_steady_inputs(m, state_of(m.parameters))

    def fam(value):
        if family_of is None:
            return None
        return family_of(model.with_parameters(**{parameter: value}).parameters)

    # One chart and one set of neutral directions for every value: those
    # found neutral at the first, middle and last values (a direction can be
    # neutral at an isolated value only, e.g. the yaw rate of a disc at rest).
    values = np.asarray(values, dtype=float)
    probes = [values[0], values[len(values) // 2], values[-1]] if len(values) else []
    first = None
    neutral = None
    for value in probes:
        lin = linearize(*model_and_state(value),
                        independent=independent if first is None else first.chart)
        first = first or lin
        neutral = [s for s in (lin.neutral if neutral is None else neutral) if s in lin.neutral]

    def at(value):
        return linearize(*model_and_state(value), independent=first.chart, neutral=neutral,
                         family=fam(value))

    def at_all(values):
        pairs = [model_and_state(v) for v in values]
        return linearize_many([m for m, _ in pairs], [s for _, s in pairs], first.chart,
                              neutral=neutral, families=[fam(v) for v in values])

    return sweep(at, parameter, values, xtol=xtol, linearize_all=at_all)
