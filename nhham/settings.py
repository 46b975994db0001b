"""One home for the settings every layer shares: precision, tolerances, sampling.

No sympy here: the numeric layer reads these too.

- :data:`SEED`: the default seed of every seeded sample (decisions are
  reproducible run to run);
- :data:`STATE_BOX`, :data:`PARAMETER_BOX`: where random sample points are
  drawn (coordinates and velocities; parameters without a value);
- :class:`Precision`: float64 or mpmath with a number of digits, with its
  label, its default relative tolerance and its "clearly zero" level;
- :func:`option_problem` and :func:`check_options`: the ranges of the options every
  entry point shares (``precision``, ``samples``, ``seed``, ``tol``, ...), one rule each,
  for the library's functions and the command's flags alike.
"""

from __future__ import annotations

import math
import numbers
import threading
from dataclasses import dataclass

__all__ = ["__version__", "COMPILER_LOCK", "SEED", "STATE_BOX", "PARAMETER_BOX", "Precision", "MIN_DIGITS",
           "MAX_DIGITS", "MAX_SAMPLES", "option_problem", "check_options", "json_number"]

#: The version of nhham (the package, the command's --version and its JSON read it here).
__version__ = "0.1.0"

#: Held around every call of Python's compiler (``ast.parse``, ``compile``): CPython 3.11
#: before 3.11.8 fails with "AST constructor recursion depth mismatch" when two threads
#: compile at once (a study on a cluster of threads parses and loads in several).
COMPILER_LOCK = threading.Lock()

#: Default seed of seeded sample points (the year of the paper).
SEED = 1996

#: Interval of random coordinates and velocities at sample points.
STATE_BOX = (-1.3, 1.3)

#: Range of mpmath digits (``precision``, ``--reference-digits``): more than float64.
MIN_DIGITS = 16
MAX_DIGITS = 1000

#: Most seeded sample points an entry point takes (``samples``, ``--samples``).
MAX_SAMPLES = 1000

#: Interval of random values of parameters that have none (positive: masses,
#: lengths and inertias are positive in every model).
PARAMETER_BOX = (0.6, 1.7)


@dataclass(frozen=True)
class Precision:
    """The arithmetic of sampled decisions and numeric evaluations.

    Parameters
    ----------
    digits : int or None
        None for float64, an integer for mpmath with that many significant
        digits.
    """

    digits: int | None = None

    @property
    def label(self) -> str:
        """``"float64"`` or ``"mpmath:<digits>"``."""
        return "float64" if self.digits is None else f"mpmath:{self.digits}"

    @property
    def tolerance(self) -> float:
        """Default relative tolerance: 1e-9 in float64, 10**(3 - digits) in mpmath."""
        return 1e-9 if self.digits is None else 10.0 ** (3 - self.digits)

    @property
    def zero_level(self) -> float:
        """Relative size below which a value is clearly zero (1e-12, 10**(1 - digits))."""
        return 1e-12 if self.digits is None else 10.0 ** (1 - self.digits)


def _whole(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def option_problem(key: str, value) -> str | None:
    """What is wrong with ``key = value`` for an option every entry point shares, or None.

    ``precision`` None or MIN_DIGITS..MAX_DIGITS digits; ``samples`` 1..MAX_SAMPLES;
    ``seed`` a whole number >= 0; ``max_stages`` None or at least 1; ``tol`` None or a
    positive finite number; ``near`` a finite number >= 0; ``max_depth`` a whole number
    >= 0; ``points`` at least 1.

    >>> option_problem("precision", 8)
    'expected None (float64) or 16 to 1000 digits (more than float64), got 8'
    >>> option_problem("samples", 6) is None
    True
    """
    if key == "precision":
        if value is None or (_whole(value) and MIN_DIGITS <= value <= MAX_DIGITS):
            return None
        return (f"expected None (float64) or {MIN_DIGITS} to {MAX_DIGITS} digits (more than "
                f"float64), got {value!r}")
    if key == "samples":
        if _whole(value) and 1 <= value <= MAX_SAMPLES:
            return None
        return f"expected 1 to {MAX_SAMPLES} points, got {value!r}"
    if key in ("max_stages", "points"):
        if (value is None and key == "max_stages") or (_whole(value) and value >= 1):
            return None
        return f"expected a whole number >= 1{' or None' if key == 'max_stages' else ''}, got {value!r}"
    if key in ("seed", "max_depth"):   # numpy's generators take seeds >= 0 only
        if _whole(value) and value >= 0:
            return None
        return f"expected a whole number >= 0, got {value!r}"
    if key in ("tol", "near"):
        if value is None and key == "tol":
            return None
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            number = float(value)
            if math.isfinite(number) and (number > 0 or (key == "near" and number >= 0)):
                return None
        return (f"expected a finite number {'> 0' if key == 'tol' else '>= 0'}"
                f"{' or None' if key == 'tol' else ''}, got {value!r}")
    raise KeyError(key)


def check_options(where: str, **options) -> None:
    """Raise :class:`~nhham.errors.InputError` naming the first option out of its range.

    ``where`` names the function (``"analyze_constraints"``); the options are those of
    :func:`option_problem`.
    """
    from nhham.errors import InputError

    for key, value in options.items():
        why = option_problem(key, value)
        if why is not None:
            raise InputError(f"{where}: {key}: {why}", key=key)


def json_number(x) -> float | None:
    """A float for JSON: finite numbers as numbers, others (nan, inf) as null."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None
