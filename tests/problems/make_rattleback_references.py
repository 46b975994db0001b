"""The second route's values for the rattleback with Kane & Levinson's parameters
(catalog.toml, problem ``rattleback_kane_levinson``): the eigenvalues of the upright spin
at w = +-5 rad/s from sympy's KanesMethod in body-frame speeds
(tests/numerics/rattleback_kane.py, nothing from nhham).

Usage::

    python tests/problems/make_rattleback_references.py

prints the ``published`` lists as catalog.toml holds them; tests/problems/test_problems.py
checks that the catalogue still holds what this prints.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "numerics"))

from rattleback_kane import reduced_jacobian  # noqa: E402

#: Kane & Levinson's rattleback (1982), as pydy's example sets it up; g = 9.81.
KANE_LEVINSON = {"m": 1.0, "g": 9.81, "a": 0.2, "b": 0.03, "c": 0.02, "h": 0.01,
                 "I11": 2e-4, "I22": 1.6e-3, "I33": 1.7e-3, "I12": -2e-5}
SPINS = (5.0, -5.0)


def references() -> dict:
    """Spin w -> its four nonzero eigenvalues as [re, im] pairs (the zero one, the
    neighbouring spins, dropped)."""
    out = {}
    for w in SPINS:
        ev = np.linalg.eigvals(reduced_jacobian(KANE_LEVINSON, w))
        ev = ev[np.argsort(np.abs(ev))][1:]
        out[w] = [[float(z.real), float(z.imag)] for z in sorted(ev, key=lambda z: (z.real, z.imag))]
    return out


if __name__ == "__main__":
    for w, pairs in references().items():
        print(f"w = {w:g}: published = {pairs!r}")
