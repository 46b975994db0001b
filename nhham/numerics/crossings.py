"""Where an eigenvalue of a state matrix crosses the imaginary axis along a parameter.

One finder for every route (``nhham linearize --sweep``, the stability maps of
``nhham sweep``): :func:`crossings_many` takes lines of values with their spectra and a
callable that gives spectra at new values, and locates the crossings of all lines
together (one batch of spectra per round).

Right by construction
---------------------
A bracket [a, b] is an interval whose ends differ in the number of eigenvalues with
Re above their margin (the count; :func:`nhham.numerics.spectra.unstable_counts`: the
verdict's tolerance, or an eigenvalue's error estimate where that is larger, in a
cluster at 0). The search keeps that property at every step: a new value x replaces the
end whose count it shares; a count equal to neither splits the bracket in two (several
crossings in one interval). The count alone decides, except inside the band (an
eigenvalue within its margin of the axis at x), where the sign of a smooth function g of
the characteristic polynomial lambda^k p(lambda) does (k eigenvalues on the axis at both
ends of the grid interval, structural zeros, are left out):

- an odd change of the count: g = p(0), the product of the other eigenvalues up to its
  sign, which changes sign exactly when a real eigenvalue passes through 0;
- an even change: g = the Hurwitz determinant Delta_(n-1) of p, prod_(i<j)(lambda_i +
  lambda_j) up to its sign, which changes sign when a complex pair crosses the
  imaginary axis (the factor 2 Re lambda) and stays continuous when a pair collides on
  the real axis.

g is formed from the coefficients, which rounding perturbs by eps only, even where it
perturbs clustered eigenvalues by eps^(1/3). Its regula falsi (Illinois) proposes the
next value; a bisection follows two steps that did not halve the bracket (g is flat
where an eigenvalue touches 0 beside the crossing, in the same grid interval), and
where g is inconsistent with the count the bracket is bisected. A crossing is reported
only where the bracket is narrower than ``xtol`` and an eigenvalue is on the imaginary
axis at its end; one within ``xtol`` of a grid value with an eigenvalue on the axis is
put at that value. Its kind is what crosses: an odd change of the count is a real
eigenvalue (a pair +-sigma meeting at 0 and leaving along the imaginary axis included),
an even one a complex pair (or two real eigenvalues at once, where the one on the axis
is real). A count change with no eigenvalue on the axis (a jump of the linearisation, a
value with no spectrum, a bracket not narrowed within the evaluations allowed) is
returned as :class:`Unlocated` with the reason. A touch (an eigenvalue reaching the axis
and going back) changes no count and is no crossing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from nhham.numerics.spectra import unstable_counts

__all__ = ["Crossing", "CrossingSearch", "CrossingFinder", "Unlocated", "crossings",
           "crossings_many"]

#: Bound on the spectra one bracket may ask for (bisection from a width of 1e6 to 1e-12
#: takes 60; a split bracket shares its parent's bound).
MAX_EVALUATIONS = 200

# Illinois halves an end's g no further than this (its sign must survive).
_TINY = 1e-280


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
                gen = _interval(float(values[i]), float(values[i + 1]), spectra[i],
                                spectra[i + 1], xtol)
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


def _margins(s):
    """Each eigenvalue's margin (:mod:`nhham.numerics.spectra`), or the spectrum's
    tolerance for every one."""
    ev = np.asarray(s.eigenvalues)
    margins = getattr(s, "margins", None)
    return np.full(ev.shape, float(s.tolerance)) if margins is None else np.asarray(margins)


def _count(s):
    if s is None:
        return None
    ev = np.asarray(s.eigenvalues)
    if not np.all(np.isfinite(ev)):
        return None
    return int(unstable_counts(ev, _margins(s)))


def _structural(sa, sb) -> int:
    """How many eigenvalues are 0 (to their margin) at both ends: left out of g."""
    za = int(np.sum(np.abs(np.asarray(sa.eigenvalues)) <= _margins(sa)))
    zb = int(np.sum(np.abs(np.asarray(sb.eigenvalues)) <= _margins(sb)))
    return min(za, zb)


def _log_g(s, structural, odd):
    """(sign, log|g|) of g, from the characteristic polynomial lambda^k p(lambda) of the
    spectrum (k = ``structural``): ``odd``: p(0), the product of the other eigenvalues up
    to its sign; else the Hurwitz determinant Delta_(n-1) of p, prod_(i<j)(lambda_i +
    lambda_j) up to its sign (Orlando). Both are polynomials in the coefficients, which
    the eigenvalues of a backward stable solver give to rounding even where the
    eigenvalues themselves are not (a cluster at 0)."""
    ev = np.asarray(s.eigenvalues, dtype=complex)
    c = np.real(np.poly(ev)) if ev.size else np.ones(1)
    p = c[:c.size - structural] if structural else c
    if odd:
        g = float(p[-1])
        return (0.0, -math.inf) if g == 0 else (math.copysign(1.0, g), math.log(abs(g)))
    n = p.size - 1
    if n < 2:
        return 1.0, 0.0
    # the Hurwitz matrix H_ij = p_(2j - i + 1) (p_0 the leading coefficient), order n - 1
    H = np.zeros((n - 1, n - 1))
    for i in range(n - 1):
        for j in range(n - 1):
            k = 2 * j - i + 1
            if 0 <= k <= n:
                H[i, j] = p[k]
    sign, log = np.linalg.slogdet(H)
    return (0.0, -math.inf) if sign == 0 else (float(sign), float(log))


def _near_axis(s, structural):
    """The eigenvalues on the imaginary axis to their margin, less the ``structural``
    ones nearest 0."""
    ev = np.asarray(s.eigenvalues, dtype=complex)
    margins = _margins(s)
    order = np.argsort(np.abs(ev), kind="stable")[structural:]
    ev, margins = ev[order], margins[order]
    near = np.abs(ev.real) <= margins
    return ev[near], margins[near]


def _interval(a, b, sa, sb, xtol):
    """The search of one grid interval (:func:`_search`), a crossing found within
    ``xtol`` of an end where an eigenvalue is on the axis put at that end: the rocking
    rattleback's pairs exchange at w = 0 exactly, not at -6.5e-16 and 0."""
    structural = _structural(sa, sb)
    found = yield from _search(a, b, sa, sb, structural, xtol, [MAX_EVALUATIONS])
    out = []
    for item in found:
        if isinstance(item, Crossing):
            for end, s in ((a, sa), (b, sb)):
                if (abs(item.value - end) <= xtol and item.value != end
                        and _near_axis(s, structural)[0].size):
                    item = Crossing(end, item.kind, item.eigenvalue, item.direction)
        out.append(item)
    return out


def _search(a, b, sa, sb, structural, xtol, budget):
    """The search of one bracket, a generator: it yields the values it needs, is sent
    their spectra and returns the crossings and unlocated intervals it found."""
    ca, cb = _count(sa), _count(sb)
    odd = (cb - ca) % 2 == 1
    (sga, lga), (sgb, lgb) = _log_g(sa, structural, odd), _log_g(sb, structural, odd)
    # at an end with an eigenvalue on the axis, g is 0 to rounding and its sign is
    # noise: the crossing is at that end or inside, so g has the other end's other sign
    band_a, band_b = (_near_axis(s, structural)[0].size > 0 for s in (sa, sb))
    if band_a and not band_b and sgb:
        sga = -sgb
    elif band_b and not band_a and sga:
        sgb = -sga
    ref = max(lga, lgb) if math.isfinite(max(lga, lgb)) else 0.0

    def value(sign, log):
        return 0.0 if sign == 0 else sign * math.exp(max(-700.0, min(700.0, log - ref)))

    ga, gb = value(sga, lga), value(sgb, lgb)
    falsi = ga * gb < 0
    side = 0
    # Regula falsi stalls where g is flat (an eigenvalue touching 0 beside the crossing
    # makes g ~ (x - touch)^2 there): a step that does not halve the bracket twice in a
    # row is followed by a bisection, so at most three steps halve it.
    slow = 0
    while b - a > xtol + 4 * np.finfo(float).eps * max(abs(a), abs(b)):
        if budget[0] <= 0:
            return [Unlocated(a, b, f"not narrowed to {xtol:g} within {MAX_EVALUATIONS} "
                                    f"evaluations")]
        budget[0] -= 1
        width = b - a
        x = b - gb * (b - a) / (gb - ga) if falsi and slow < 2 else 0.5 * (a + b)
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
        if falsi and gx != 0 and _near_axis(s, structural)[0].size:
            to_a = np.sign(gx) == np.sign(ga)     # in the band, g decides
        else:
            # g = 0 (an eigenvalue exactly at 0: a touch as well as a crossing) says
            # nothing of the side: the count does
            to_a = c == ca
            if gx == 0 and falsi:
                # the end keeps its sign: g still changes sign in the bracket (at its
                # end x, when x is the crossing)
                gx = math.copysign(2 * _TINY, ga if to_a else gb)
            elif falsi and gx != 0 and (np.sign(gx) == np.sign(ga)) != to_a:
                # g disagrees with the count: this step and the next bisect
                a, sa, ga, b, sb, gb = ((x, s, gx, b, sb, gb) if to_a else
                                        (a, sa, ga, x, s, gx))
                falsi, side, slow = False, 0, 0
                continue
        if to_a:
            a, sa, ga = x, s, gx
            if side == 1 and abs(gb) > _TINY:   # Illinois: the other end kept twice,
                gb /= 2                              # halve its value (never to 0: its sign decides)
            side = 1
        else:
            b, sb, gb = x, s, gx
            if side == -1 and abs(ga) > _TINY:
                ga /= 2
            side = -1
        slow = slow + 1 if b - a > 0.5 * width else 0
    return [_verified(a, b, sa, sb, ca, cb, structural, odd)]


def _verified(a, b, sa, sb, ca, cb, structural, odd):
    """The crossing at the end of the (narrow) bracket [a, b] where an eigenvalue is on
    the imaginary axis, or why there is none. The kind is what crosses: a change of the
    count by an odd number is a real eigenvalue through 0 (a complex pair changes it by
    two), whatever the eigenvalues near 0 at the ends look like (a real pair +-sigma
    meeting at 0 and leaving along the imaginary axis is a divergence: at the end past
    the collision they are +-i omega, omega tiny); an even change is a complex pair, or
    two real eigenvalues at once where the one on the axis is real."""
    best = None
    for x, s in ((a, sa), (b, sb)):
        near, margins = _near_axis(s, structural)
        if not near.size:
            continue
        if odd:   # the eigenvalue nearest 0
            i = int(np.argmin(np.abs(near)))
        else:     # a pair nearest the axis, else a real one
            pair = np.abs(near.imag) > margins
            pool = np.flatnonzero(pair) if pair.any() else np.arange(near.size)
            i = int(pool[np.argmin(np.abs(near.real[pool]))])
        z, m = near[i], margins[i]
        key = abs(z) if odd else abs(z.real)
        if best is None or key < best[0]:
            best = (key, x, z, m)
    if best is None:
        return Unlocated(a, b, f"the number of eigenvalues with Re > 0 changes from {ca} to "
                               f"{cb} within [{a:.17g}, {b:.17g}] but none is on the "
                               f"imaginary axis there (the linearisation jumps)")
    _, x, z, m = best
    kind = "real" if odd or abs(z.imag) <= m else "complex"
    return Crossing(float(x), kind, complex(z.real, abs(z.imag)), 1 if cb > ca else -1)
