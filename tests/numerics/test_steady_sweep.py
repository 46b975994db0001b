"""Sweeps of a steady motion's stability over a parameter (nhham.numerics.steady_sweep):
crossings of the imaginary axis located by root finding on branches whose eigenvalues are
written down by hand, and a parameter the model does not have. (The bicycle's weave and
capsize speeds, against the benchmark: test_linearization.py.)"""

import numpy as np
import pytest

from nhham import InputError
from nhham.numerics.steady_sweep import sweep, sweep_steady


def test_sweep_locates_a_real_crossing_by_root_finding():
    # a toy branch: lambda(p) = p - 1/3 crossing at exactly 1/3
    class Lin:
        def __init__(self, p):
            self.eigenvalues = np.array([p - 1 / 3, -1.0 + 0j])
            self.tolerance = 1e-12
            self.stable = p < 1 / 3
            self.coordinates = ("a",)

    s = sweep(Lin, "p", np.linspace(0, 1, 4))
    assert len(s.crossings) == 1 and s.crossings[0].kind == "real"
    assert abs(s.crossings[0].value - 1 / 3) < 1e-12


def test_unknown_sweep_parameter(bicycle):
    scene, model = bicycle
    with pytest.raises(InputError, match="'w' is not a parameter"):
        sweep_steady(model, scene.steady.values, "w", [0.0, 1.0])


def _branch(eigenvalues):
    """A linearisation whose eigenvalues at parameter p are ``eigenvalues(p)``."""
    class Lin:
        def __init__(self, p):
            self.eigenvalues = np.array(eigenvalues(p), dtype=complex)
            self.tolerance = 1e-12
            self.stable = bool(np.all(self.eigenvalues.real < -self.tolerance))
            self.coordinates = ("a", "b")

    return Lin


def test_a_complex_pair_crossing_is_a_complex_crossing():
    """(p - 1/2) +- 2i: a Hopf crossing at exactly p = 1/2, from stable to unstable; the
    real eigenvalue -1 crosses nothing."""
    s = sweep(_branch(lambda p: [p - 0.5 + 2j, p - 0.5 - 2j, -1.0]), "p",
              np.linspace(0, 1, 4))
    assert [(c.kind, c.direction) for c in s.crossings] == [("complex", 1)]
    assert abs(s.crossings[0].value - 0.5) < 1e-12
    assert abs(s.crossings[0].eigenvalue - 2j) < 1e-12
    assert list(s.stable) == [True, True, False, False]


def test_a_real_eigenvalue_going_back_is_a_second_crossing():
    """-(p^2 - 2 p + 3/4) = -(p - 1/2)(p - 3/2): positive on (1/2, 3/2) only, so two
    crossings, one each way, at the roots."""
    s = sweep(_branch(lambda p: [-(p - 0.5) * (p - 1.5), -2.0]), "p", np.linspace(0, 2, 8))
    assert [(c.kind, c.direction) for c in s.crossings] == [("real", 1), ("real", -1)]
    assert np.allclose([c.value for c in s.crossings], [0.5, 1.5], atol=1e-12)
