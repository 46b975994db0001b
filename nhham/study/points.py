"""Where a parameter study evaluates: grids, samples and perturbed initial states.

A :class:`Design` is plain data (numbers and names, no sympy): a full-factorial *grid*
over swept names (one dimension each, named after it), or *samples* (one dimension
``sample``) drawn by Latin hypercube, Sobol or plain uniform sampling
(:mod:`scipy.stats.qmc`, seeded) inside the ranges given, optionally with seeded normal
perturbations of initial values (an ensemble). The swept names are parameters of the
scene or, for simulations, names of its state (coordinates and velocities).

A *chunk* of a design is a block of its array: one slice per dimension. Chunks are what
a study ships to its workers and writes to its store, so a chunk is a region of the
stored arrays.
"""

from __future__ import annotations

import math
import re
from fractions import Fraction
from dataclasses import dataclass
from itertools import product

import numpy as np

from nhham.errors import InputError

__all__ = ["Axis", "Design", "parse_over", "parse_perturbation", "grid", "samples",
           "chunk_slices", "check_seed", "SAMPLERS", "MAX_POINTS"]

#: Ways to draw samples: Latin hypercube, scrambled Sobol, independent uniform.
SAMPLERS = ("lhs", "sobol", "uniform")

#: Most points of one study (a bound on the memory of its arrays and of its store).
MAX_POINTS = 10_000_000

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_RANGE = re.compile(rf"^\s*({_NAME})\s*=\s*([^:,]+):([^:,]+)(?::([^:,]+))?\s*$")
_LIST = re.compile(rf"^\s*({_NAME})\s*=\s*([^:]+(?:,[^:]+)+)\s*$")


@dataclass(frozen=True)
class Axis:
    """One swept name.

    Attributes
    ----------
    name : str
    listed : tuple of float
        Values given one by one (``P=A,B,C``; empty otherwise).
    bounds : (float, float)
        The range: the first and last value of a grid, or where samples are drawn.
    text : str
        As the user wrote it (``--over``).
    spacing : tuple
        A grid ``P=START:STOP:COUNT``: ``(START, STOP, COUNT)`` (the two as the exact
        decimals written, :class:`fractions.Fraction`); its values are made only when
        asked (:meth:`array`), after the size of the whole design was checked.
    """

    name: str
    listed: tuple
    bounds: tuple
    text: str
    spacing: tuple = ()

    @property
    def count(self) -> int | None:
        """Number of grid values (None for a range to sample)."""
        return self.spacing[2] if self.spacing else (len(self.listed) or None)

    @property
    def values(self) -> tuple:
        """The grid's values (empty for a range to sample)."""
        return tuple(self.array().tolist())

    def array(self) -> np.ndarray:
        """The grid's values as float64: each the double nearest to the exact decimal
        START + i (STOP - START)/(COUNT - 1), so that 0:1:11 has 0.3 (not linspace's
        0.30000000000000004): a point is where the user meant it, also for the exact
        placement of a classify study."""
        if not self.spacing:
            return np.asarray(self.listed, dtype=float)
        return _decimal_grid(*self.spacing)


def _decimal_grid(lo: Fraction, hi: Fraction, count: int) -> np.ndarray:
    """The correctly rounded values of lo + i (hi - lo)/(count - 1), i < count.

    Written as integers (A + i B)/D over a common denominator: when numerators and D are
    below 2**53 they are exact doubles and one IEEE division rounds correctly (vectorised:
    10**7 values in a fraction of a second); otherwise Python's int/int true division,
    also correctly rounded, one value at a time.
    """
    if count == 1:
        return np.array([float(lo)])
    n = count - 1
    D = math.lcm(lo.denominator, hi.denominator) * n
    A = lo.numerator * (D // lo.denominator)
    B = ((hi - lo) * D / n).numerator   # an integer: D holds both denominators and n
    exact = 2 ** 53
    if max(abs(A), abs(A + n * B), D) <= exact:
        numerators = A + np.arange(count, dtype=np.int64) * np.int64(B)
        return numerators.astype(np.float64) / float(D)
    return np.array([(A + i * B) / D for i in range(count)], dtype=float)


def _number(text: str, whole: str) -> float:
    """A value of ``--over``: a finite float that is the number written (``1e-400``,
    which a double reads as 0, is refused as a scene's literal is)."""
    value = float(text)   # ValueError: the caller names the option
    if value == 0.0:
        try:
            exact = Fraction(text.strip())
        except ValueError:
            exact = Fraction(0)
        if exact != 0:
            raise InputError(f"--over: the number {text.strip()!r} is outside the range of "
                             f"double precision (about 1e-308 to 1e308), in {whole!r}",
                             key="--over")
    return value


def parse_over(text: str) -> Axis:
    """``"v=0:10:201"`` (a grid: START:STOP:COUNT, both ends included), ``"c=0:0.2"`` (a
    range, for samples) or ``"m=1,2,5"`` (listed values) -> :class:`Axis`.

    A grid's values are not made here (:meth:`Axis.array`): the size of the design is
    checked first, from the counts alone.

    Raises
    ------
    InputError
        Naming ``--over`` and what is wrong.
    """
    text = text or ""
    listed = _LIST.match(text)
    if listed:
        name, items = listed.groups()
        try:
            values = tuple(_number(s, text) for s in items.split(","))
        except ValueError:
            raise InputError(f"--over: listed values must be numbers, got {text!r}",
                             key="--over") from None
        if not all(math.isfinite(v) for v in values) or len(set(values)) != len(values):
            raise InputError(f"--over: listed values must be finite and distinct, got {text!r}",
                             key="--over")
        if len(values) > MAX_POINTS:
            raise InputError(f"--over: at most {MAX_POINTS} values, got {len(values)}",
                             key="--over")
        return Axis(name, values, (min(values), max(values)), text)
    match = _RANGE.match(text)
    if not match:
        raise InputError(f"--over: expected NAME=START:STOP:COUNT (a grid, e.g. v=0:10:201), "
                         f"NAME=START:STOP (a range to sample) or NAME=A,B,C, got {text!r}",
                         key="--over")
    name, a, b, c = match.groups()
    try:
        start, stop = _number(a, text), _number(b, text)
        count = None if c is None else int(c)
    except ValueError:
        raise InputError(f"--over: START and STOP must be numbers and COUNT an integer, "
                         f"got {text!r}", key="--over") from None
    if not (math.isfinite(start) and math.isfinite(stop)) or stop <= start:
        raise InputError(f"--over: need finite START < STOP, got {text!r}", key="--over")
    if count is None:
        return Axis(name, (), (start, stop), text)
    if not 1 <= count <= MAX_POINTS:
        raise InputError(f"--over: COUNT must be between 1 and {MAX_POINTS}, got {text!r}",
                         key="--over")
    return Axis(name, (), (start, stop), text, (Fraction(a.strip()), Fraction(b.strip()), count))


def parse_perturbation(text: str) -> tuple:
    """``"phi=0.01"`` -> ``("phi", 0.01)``: the standard deviation of a normal
    perturbation of that initial value."""
    match = re.match(rf"^\s*({_NAME})\s*=\s*([^=]+)$", text or "")
    try:
        scale = float(match.group(2)) if match else math.nan
    except ValueError:
        scale = math.nan
    if not match or not (math.isfinite(scale) and scale > 0):
        raise InputError(f"--initial-perturbation: expected NAME=SIGMA with SIGMA > 0 (a "
                         f"normal perturbation of an initial value), got {text!r}",
                         key="--initial-perturbation")
    return match.group(1), scale


@dataclass(frozen=True)
class Design:
    """The points of a study.

    Attributes
    ----------
    kind : {"grid", "samples"}
    names : tuple of str
        The swept names, in the order of ``points``' columns.
    dims : tuple of str
        Dimensions of the result arrays: the names (grid) or ``("sample",)``.
    shape : tuple of int
    coordinates : dict of str to ndarray
        A grid's values by name; the samples' drawn values by name (each of shape
        ``shape``).
    perturbed : tuple of str
        Initial values perturbed (samples only).
    perturbations : ndarray, shape (shape + (len(perturbed),))
        The drawn perturbations (zeros where nothing is perturbed).
    description : dict
        JSON-ready: how the design was made (kept with the results, checked on resume).
    """

    kind: str
    names: tuple
    dims: tuple
    shape: tuple
    coordinates: dict
    perturbed: tuple
    perturbations: np.ndarray
    description: dict

    @property
    def size(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64))

    def values(self, region: tuple) -> dict:
        """``{name: array}`` of the swept values on a region (one slice per dimension),
        each of the region's shape."""
        if self.kind == "grid":
            axes = [self.coordinates[d][s] for d, s in zip(self.dims, region)]
            mesh = np.meshgrid(*axes, indexing="ij")
            return dict(zip(self.names, mesh))
        return {name: self.coordinates[name][region] for name in self.names}

    def perturbation(self, region: tuple) -> np.ndarray:
        """The perturbations on a region, shape (region shape + (len(perturbed),))."""
        return self.perturbations[region]


def grid(axes) -> Design:
    """The full-factorial grid of the axes (each with its values)."""
    axes = list(axes)
    _distinct(axes)
    missing = [a.text for a in axes if not a.count]
    if missing:
        raise InputError(f"--over: a grid needs a COUNT (NAME=START:STOP:COUNT) or listed "
                         f"values; {', '.join(missing)} is a range (give --samples to sample "
                         f"it)", key="--over")
    shape = tuple(a.count for a in axes)
    _check_size(shape)   # from the counts: no value is made for a design refused
    names = tuple(a.name for a in axes)
    return Design("grid", names, names, shape, {a.name: a.array() for a in axes}, (),
                  np.zeros(shape + (0,)),
                  {"kind": "grid", "over": [a.text for a in axes]})


def samples(axes, count: int, *, sampler: str = "lhs", seed: int = 0,
            perturbations=()) -> Design:
    """``count`` points drawn in the ranges of the axes, and perturbed initial values.

    Parameters
    ----------
    axes : sequence of Axis
        Each a range (``bounds``; listed values or a grid's values are sampled in their
        range too).
    count : int
    sampler : {"lhs", "sobol", "uniform"}
        ``scipy.stats.qmc.LatinHypercube``, ``Sobol`` (scrambled) or independent uniform.
    seed : int
    perturbations : sequence of (str, float)
        Initial values and the standard deviations of their normal perturbations.

    Returns
    -------
    Design
    """
    from scipy.stats import qmc

    axes = list(axes)
    _distinct(axes)
    if sampler not in SAMPLERS:
        raise InputError(f"--sampler: one of {', '.join(SAMPLERS)}, got {sampler!r}",
                         key="--sampler")
    if not 1 <= count <= MAX_POINTS:
        raise InputError(f"--samples: between 1 and {MAX_POINTS}, got {count}", key="--samples")
    check_seed(seed)
    names = tuple(a.name for a in axes)
    rng = np.random.default_rng(seed)
    if axes:
        d = len(axes)
        if sampler == "lhs":
            unit = qmc.LatinHypercube(d=d, seed=rng).random(count)
        elif sampler == "sobol":
            unit = qmc.Sobol(d=d, scramble=True, seed=rng).random(count)
        else:
            unit = rng.random((count, d))
        lo = np.array([a.bounds[0] for a in axes])
        hi = np.array([a.bounds[1] for a in axes])
        drawn = qmc.scale(unit, lo, hi)
    else:
        drawn = np.zeros((count, 0))
    perturbed = tuple(name for name, _ in perturbations)
    if len(set(perturbed)) != len(perturbed):
        raise InputError("--initial-perturbation: a name is perturbed twice",
                         key="--initial-perturbation")
    scales = np.array([s for _, s in perturbations], dtype=float)
    noise = np.random.default_rng([seed, 1]).standard_normal((count, len(perturbed))) * scales
    return Design("samples", names, ("sample",), (count,),
                  {name: drawn[:, i] for i, name in enumerate(names)}, perturbed, noise,
                  {"kind": "samples", "over": [a.text for a in axes], "samples": count,
                   "sampler": sampler, "seed": seed,
                   "initial_perturbation": [f"{n}={s!r}" for n, s in perturbations]})


def check_seed(seed) -> None:
    """A seed of the samples is a non-negative integer (numpy's generators take no other).

    Raises
    ------
    InputError
        Naming ``--seed``.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"--seed: a non-negative integer, got {seed!r}", key="--seed")


def chunk_slices(shape: tuple, points: int, whole: int | None = None,
                 first: int | None = None) -> list:
    """Regions (tuples of slices) covering an array of ``shape``, about ``points``
    elements each (at most ``points``, the pieces along a dimension of sizes that differ
    by at most one), in C order.

    ``whole``: a dimension never cut (each region holds whole lines along it: a
    boundary traced along that dimension is found within one region). ``first``: a
    dimension filled first (whole lines along it when a line fits in ``points``, else
    pieces of lines of at most ``points``).
    """
    points = max(1, int(points))
    sizes = [1] * len(shape)
    room = points
    lead = whole if whole is not None else first
    order = ([lead] if lead is not None else []) + [i for i in reversed(range(len(shape)))
                                                    if i != lead]
    for i in order:
        take = shape[i] if i == whole else max(1, min(shape[i], room))
        sizes[i] = take
        room = max(1, room // take)
    # as many pieces along each dimension, of sizes differing by at most one: no small
    # last piece (a chunk of one line is a worker idle at the end)
    sizes = [-(-n // -(-n // s)) for n, s in zip(shape, sizes)]
    ranges = [range(0, n, s) for n, s in zip(shape, sizes)]
    return [tuple(slice(a, min(a + s, n)) for a, s, n in zip(starts, sizes, shape))
            for starts in product(*ranges)]


def _distinct(axes) -> None:
    names = [a.name for a in axes]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise InputError(f"--over: {', '.join(repeated)} given twice", key="--over")


def _check_size(shape) -> None:
    size = math.prod(shape)   # Python's integers: three axes of 10**7 do not wrap around
    if size > MAX_POINTS:
        raise InputError(f"--over: {' x '.join(map(str, shape))} = {size} points; at most "
                         f"{MAX_POINTS} in one study", key="--over")
