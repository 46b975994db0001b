"""Where an eigenvalue of a state matrix crosses the imaginary axis along a parameter.

One finder for every route (``nhham linearize --sweep``, the stability maps of
``nhham sweep``): :func:`crossings_many` takes lines of values with their spectra and a
callable that gives spectra at new values, and locates the crossings of all lines
together (one batch of spectra per round).

Right by construction
---------------------
A bracket [a, b] is an interval whose ends differ in the number of eigenvalues with
Re > tolerance (the count). The search keeps that property at every step: a new value
x replaces the end whose count it shares; a count equal to neither splits the bracket in
two (several crossings in one interval). The count alone decides, except inside the
tolerance band (an eigenvalue with |Re| <= tolerance at x), where the sign of a smooth
function g of the spectrum does:

- an odd change of the count: g = det A = prod(lambda), whose sign is (-1)^(number of
  negative real eigenvalues), so it changes sign exactly when a real eigenvalue passes
  through 0;
- an even change: g = the Hurwitz determinant Delta_(n-1) up to its sign,
  prod_(i<j)(lambda_i + lambda_j), which changes sign when a complex pair crosses the
  imaginary axis (the factor 2 Re lambda) and stays continuous when a pair collides on
  the real axis.

g's regula falsi (Illinois) proposes the next value; where g is inconsistent with the
count the bracket is bisected. A crossing is reported only where an eigenvalue is on
the imaginary axis to the spectrum's tolerance (checked at the reported value); a count
change with no eigenvalue on the axis (a jump of the linearisation, a value with no
spectrum) is returned as :class:`Unlocated` with the reason. A touch (an eigenvalue
reaching the axis and going back) changes no count and is no crossing. Eigenvalues on
the axis at both ends of a grid interval (structural zeros) are left out of g and of the
check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

__all__ = ["Crossing", "CrossingSearch", "CrossingFinder", "Unlocated", "crossings",
           "crossings_many"]

#: Bound on the spectra one bracket may ask for (bisection from a width of 1e6 to 1e-12
#: takes 60; a split bracket shares its parent's bound).
MAX_EVALUATIONS = 200


@dataclass(frozen=True)
class Crossing:
    """A parameter value where an eigenvalue's real part changes sign.

    Attributes
    ----------
    value : float
        Within ``xtol`` of a change of the number of unstable eigenvalues, with an
        eigenvalue on the imaginary axis (to the spectrum's tolerance) there.
    kind : {"real", "complex"}
        A real eigenvalue through 0, or a complex pair through the imaginary axis.
    eigenvalue : complex
        The crossing eigenvalue at ``value`` (|Re| <= tolerance).
    direction : int
        +1 when the number of eigenvalues with Re > 0 grows with the parameter.
    """

    value: float
    kind: str
    eigenvalue: complex
    direction: int


@dataclass(frozen=True)
class Unlocated:
    """An interval where the number of unstable eigenvalues changes but no crossing
    could be located (``reason`` says why)."""

    low: float
    high: float
    reason: str


@dataclass(frozen=True)
class CrossingSearch:
    """Per line, the crossings located and the intervals that could not be.

    Attributes
    ----------
    crossings : tuple of tuple of Crossing
        Sorted by value on each line.
    unlocated : tuple of tuple of Unlocated
    """

    crossings: tuple
    unlocated: tuple


def crossings(spectrum_at: Callable, values: Sequence[float] | np.ndarray, spectra: Sequence, *,
              xtol: float = 1e-12) -> CrossingSearch:
    """:func:`crossings_many` on one line, ``spectrum_at(value)`` one spectrum at a time.

    Examples
    --------
    >>> import numpy as np
    >>> class Spectrum:
    ...     def __init__(self, p):   # a real eigenvalue p - 1/3 and a stable pair
    ...         self.eigenvalues = np.array([p - 1/3, -1 + 2j, -1 - 2j])
    ...         self.tolerance = 1e-12
    >>> values = np.linspace(0, 1, 4)
    >>> found = crossings(Spectrum, values, [Spectrum(p) for p in values])
    >>> c = found.crossings[0][0]
    >>> c.kind, round(c.value, 12), c.direction
    ('real', 0.333333333333, 1)
    """
    def at(requests):
        return [spectrum_at(float(v)) for _, v in requests]

    return crossings_many(at, [(values, spectra)], xtol=xtol)


class CrossingFinder:
    """The crossings on many lines, located together, asked for spectra rather than
    calling for them: the caller reads :attr:`requests`, computes the spectra there however
    it computes them (a study's batch, a sweep's model) and hands them to :meth:`supply`,
    until nothing is requested; :meth:`result` then holds the crossings.

    Parameters
    ----------
    lines, xtol, counts
        As for :func:`crossings_many`.

    Examples
    --------
    One line on which the eigenvalue p - 0.3 crosses 0:

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> def spectrum(p):
    ...     return SimpleNamespace(eigenvalues=np.array([p - 0.3 + 0j, -1 + 0j]),
    ...                            tolerance=1e-12)
    >>> values = np.linspace(0.0, 1.0, 5)
    >>> finder = CrossingFinder([(values, [spectrum(v) for v in values])])
    >>> while finder.requests:
    ...     finder.supply([spectrum(x) for _, x in finder.requests])
    >>> [round(c.value, 12) for c in finder.result().crossings[0]]
    [0.3]
    """

    def __init__(self, lines: Sequence, *, xtol: float = 1e-12,
                 counts: Sequence | None = None) -> None:
        self._found: list = [[] for _ in lines]
        self._unlocated: list = [[] for _ in lines]
        searches = []
        for k, (values, spectra) in enumerate(lines):
            line = ([_count(s) for s in spectra] if counts is None
                    else [None if c < 0 else int(c) for c in counts[k]])
            for i in range(len(values) - 1):
                if None in (line[i], line[i + 1]) or line[i] == line[i + 1]:
                    continue
                sa, sb = spectra[i], spectra[i + 1]
                gen = _search(float(values[i]), float(values[i + 1]), sa, sb,
                              _structural(sa, sb), xtol, [MAX_EVALUATIONS])
                searches.append((k, gen))
        self._active = [(k, gen, x) for k, gen in searches
                        if (x := self._step(k, gen, None)) is not None]

    @property
    def requests(self) -> list:
        """``[(line index, value), ...]``: where spectra are wanted next (empty: done)."""
        return [(k, x) for k, _, x in self._active]

    def supply(self, spectra: Sequence) -> None:
        """The spectra at :attr:`requests`, in their order (None where there is none)."""
        self._active = [(k, gen, x) for (k, gen, _), s in zip(self._active, spectra)
                        if (x := self._step(k, gen, s)) is not None]

    def result(self) -> CrossingSearch:
        """The crossings found (sorted along each line) and the intervals left unlocated."""
        return CrossingSearch(tuple(tuple(sorted(f, key=lambda c: c.value))
                                    for f in self._found),
                              tuple(tuple(u) for u in self._unlocated))

    def _step(self, k, gen, spectrum):
        try:
            return gen.send(spectrum)
        except StopIteration as stop:
            for item in stop.value:
                (self._found if isinstance(item, Crossing) else self._unlocated)[k].append(item)
            return None


def crossings_many(spectra_at: Callable, lines: Sequence, *, xtol: float = 1e-12,
                   counts: Sequence | None = None) -> CrossingSearch:
    """The crossings of the imaginary axis on many lines, located together.

    Parameters
    ----------
    spectra_at : callable
        ``[(line index, value), ...] -> [spectrum or None, ...]``: spectra at many points
        in one call. A spectrum has ``eigenvalues`` (complex array) and ``tolerance`` (a
        real part at or below it counts as 0); None where there is none.
    lines : sequence of (values, spectra)
        Each line's increasing values and the spectra there (any sequence: only the ends
        of the intervals where the count changes are read).
    xtol : float, optional
        Absolute width of the final brackets.
    counts : sequence of sequences of int, optional
        Per line, the number of eigenvalues with real part above the tolerance at each
        value (-1 where there is no spectrum), when the caller has them; default: counted
        here from the spectra.

    Returns
    -------
    CrossingSearch
        See the module docstring for what makes a crossing. (:class:`CrossingFinder`
        is the same search for a caller that computes the spectra itself.)
    """
    finder = CrossingFinder(lines, xtol=xtol, counts=counts)
    while finder.requests:
        finder.supply(spectra_at(finder.requests))
    return finder.result()


def _count(s):
    if s is None:
        return None
    ev = np.asarray(s.eigenvalues)
    if not np.all(np.isfinite(ev)):
        return None
    return int(np.sum(ev.real > s.tolerance))


def _structural(sa, sb) -> int:
    """How many eigenvalues are 0 (to the tolerance) at both ends: left out of g."""
    za = int(np.sum(np.abs(np.asarray(sa.eigenvalues)) <= sa.tolerance))
    zb = int(np.sum(np.abs(np.asarray(sb.eigenvalues)) <= sb.tolerance))
    return min(za, zb)


def _moving(s, structural):
    """The eigenvalues less the ``structural`` ones nearest 0."""
    ev = np.asarray(s.eigenvalues, dtype=complex)
    if structural:
        ev = ev[np.argsort(np.abs(ev), kind="stable")[structural:]]
    return ev


def _log_g(s, structural, odd):
    """(sign, log|g|) of det A (``odd``) or prod_(i<j)(lambda_i + lambda_j)."""
    ev = _moving(s, structural)
    if odd:
        f = ev
    else:
        i, j = np.triu_indices(ev.size, 1)
        f = ev[i] + ev[j]
    if not f.size:
        return 1.0, 0.0
    if np.any(f == 0):
        return 0.0, -math.inf
    # conjugate pairs make the product real: its sign from the summed angles
    angle = float(np.sum(np.angle(f)))
    return (1.0 if math.cos(angle) > 0 else -1.0), float(np.sum(np.log(np.abs(f))))


def _near_axis(s, structural):
    ev = _moving(s, structural)
    return ev[np.abs(ev.real) <= s.tolerance]


def _search(a, b, sa, sb, structural, xtol, budget):
    """The search of one bracket, a generator: it yields the values it needs, is sent
    their spectra and returns the crossings and unlocated intervals it found."""
    ca, cb = _count(sa), _count(sb)
    odd = (cb - ca) % 2 == 1
    (sga, lga), (sgb, lgb) = _log_g(sa, structural, odd), _log_g(sb, structural, odd)
    ref = max(lga, lgb) if math.isfinite(max(lga, lgb)) else 0.0

    def value(sign, log):
        return 0.0 if sign == 0 else sign * math.exp(max(-700.0, min(700.0, log - ref)))

    def root(g, s):     # g = 0 with an eigenvalue on the axis (not a false root of g)
        return g == 0 and _near_axis(s, structural).size > 0

    ga, gb = value(sga, lga), value(sgb, lgb)
    if root(ga, sa) or root(gb, sb):
        return [_verified(a, b, sa, sb, ca, cb, structural, odd)]
    falsi = ga * gb < 0
    side = 0
    while b - a > xtol + 4 * np.finfo(float).eps * max(abs(a), abs(b)):
        if budget[0] <= 0:
            found = _verified(a, b, sa, sb, ca, cb, structural, odd)
            return [found if isinstance(found, Crossing) else
                    Unlocated(a, b, f"not narrowed to {xtol:g} within {MAX_EVALUATIONS} "
                                    f"evaluations")]
        budget[0] -= 1
        x = b - gb * (b - a) / (gb - ga) if falsi else 0.5 * (a + b)
        if not a < x < b:
            x = 0.5 * (a + b)
        # after a bisection step g may bracket again (a false root of g left behind)
        falsi = ga * gb < 0
        s = yield x
        c = _count(s)
        if c is None:
            return [Unlocated(a, b, f"no linearisation at {x:.17g} inside the interval")]
        if c not in (ca, cb):
            # a count equal to neither end: a crossing on each side
            left = yield from _search(a, x, sa, s, structural, xtol, budget)
            right = yield from _search(x, b, s, sb, structural, xtol, budget)
            return left + right
        gx = value(*_log_g(s, structural, odd))
        if root(gx, s):
            a = b = x
            sa = sb = s
            break
        if falsi and gx != 0 and _near_axis(s, structural).size:
            to_a = np.sign(gx) == np.sign(ga)     # in the band, g decides
        else:
            to_a = c == ca
            if falsi and (gx == 0 or (np.sign(gx) == np.sign(ga)) != to_a):
                # g disagrees with the count: this step and the next bisect
                a, sa, ga, b, sb, gb = ((x, s, gx, b, sb, gb) if to_a else
                                        (a, sa, ga, x, s, gx))
                falsi, side = False, 0
                continue
        if to_a:
            a, sa, ga = x, s, gx
            if side == 1:   # Illinois: the other end kept twice, halve its value
                gb /= 2
            side = 1
        else:
            b, sb, gb = x, s, gx
            if side == -1:
                ga /= 2
            side = -1
    return [_verified(a, b, sa, sb, ca, cb, structural, odd)]


def _verified(a, b, sa, sb, ca, cb, structural, odd):
    """The crossing at the end of [a, b] where an eigenvalue is on the imaginary axis,
    or why there is none."""
    best = None
    for x, s in ((a, sa), (b, sb)):
        near = _near_axis(s, structural)
        if not near.size:
            continue
        real = near[np.abs(near.imag) <= s.tolerance]
        pair = near[near.imag > s.tolerance]
        # the kind the count's parity calls for first
        pick = (real if real.size else pair) if odd else (pair if pair.size else real)
        z = pick[np.argmin(np.abs(pick.real))]
        if best is None or abs(z.real) < abs(best[1].real):
            best = (x, z, s.tolerance)
    if best is None:
        return Unlocated(a, b, f"the number of eigenvalues with Re > 0 changes from {ca} to "
                               f"{cb} within [{a:.17g}, {b:.17g}] but none is on the "
                               f"imaginary axis there (the linearisation jumps)")
    x, z, tol = best
    kind = "real" if abs(z.imag) <= tol else "complex"
    return Crossing(float(x), kind, complex(z.real, abs(z.imag)), 1 if cb > ca else -1)
