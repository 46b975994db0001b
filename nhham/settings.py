"""One home for the settings every layer shares: precision, tolerances, sampling.

No sympy here: the numeric layer reads these too.

- :data:`SEED`: the default seed of every seeded sample (decisions are
  reproducible run to run);
- :data:`STATE_BOX`, :data:`PARAMETER_BOX`: where random sample points are
  drawn (coordinates and velocities; parameters without a value);
- :class:`Precision`: float64 or mpmath with a number of digits, with its
  label, its default relative tolerance and its "clearly zero" level.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["__version__", "SEED", "STATE_BOX", "PARAMETER_BOX", "Precision"]

#: The version of nhham (the package, the command's --version and its JSON read it here).
__version__ = "0.1.0"

#: Default seed of seeded sample points (the year of the paper).
SEED = 1996

#: Interval of random coordinates and velocities at sample points.
STATE_BOX = (-1.3, 1.3)

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
